"""Probe (issue 9, item 4): the work of the diagram's stability metrics, flow by flow.

    PYTHONPATH=src python benchmarks/probes/metric_work.py [growth|longwave] [STRIDE]
        [--size=60] [--roughness=0.05] [--out=FILE.json] [--top=10] [--lw-n=48 ...]

On the SIZE × SIZE diagram grid of the given roughness (the configuration of
``bench_sweep.py``'s ``sweep_phi005_60x60`` row), at the points the growth metric samples
(every STRIDE-th point in θ and ν0, offset STRIDE // 2; STRIDE defaults to the metric's 6):
the steady flow (:func:`chuteflow.steady.solve_steady` as the sweep calls it, outside the
count), then the metric's ``compute`` (the long-wave metric's first, as the growth metric
reads its sign). Prints, for the metric asked for, the CPU time, the LU factorisations of
shifted pencils by size (:func:`chuteflow.stability.eigen.factor_shifted`), the dense QZ
solves, and the flows that cost most. The counts do not depend on the machine's load (CPU
times of two processes side by side differ by up to ±15 % on the 2-core development
machine), so two versions are compared by their counts and by the values, which ``--out``
writes (JSON, one record per flow) for a point-by-point comparison (``--lw-OPTION=VALUE``: an
option of the long-wave metric, e.g. ``--lw-n=60`` or ``--lw-taylor=true``; two settings of
one version side by side in one process: ``longwave_start.py``):
``PYTHONPATH=/other/checkout/src python benchmarks/probes/metric_work.py growth --out=b.json``.
"""

from __future__ import annotations

import collections
import json
import math
import sys
import time


def _nan(v) -> bool:
    return isinstance(v, float) and math.isnan(v)


def main(argv: list[str]) -> None:
    opts = {a[2:].split("=", 1)[0]: a.split("=", 1)[1] for a in argv if a.startswith("--")}
    args = [a for a in argv if not a.startswith("--")]
    which = args[0] if args else "growth"
    if which not in ("growth", "longwave"):
        raise SystemExit("usage: metric_work.py [growth|longwave] [STRIDE] [--size=60] [--out=F]")
    stride = int(args[1]) if len(args) > 1 else 6
    size = int(opts.get("size", 60))
    roughness = float(opts.get("roughness", 0.05))
    top = int(opts.get("top", 10))

    from chuteflow._threads import limit_blas_threads

    limit_blas_threads(1)
    import numpy as np

    import chuteflow.stability.eigen as eigen
    from chuteflow.errors import ChuteflowError
    from chuteflow.steady import solve_steady
    from chuteflow.sweep import SweepConfig
    from chuteflow.sweep.metrics import GrowthMetric, LongWaveMetric
    from chuteflow.sweep.points import Point

    cfg = SweepConfig.grid(roughness, shape=(size, size), markers=())

    def _value(v: str):
        return v == "true" if v in ("true", "false") else float(v) if "." in v else int(v)

    lw_opts = {k[3:]: _value(v) for k, v in opts.items() if k.startswith("lw-")}
    lw, gm = LongWaveMetric(**lw_opts), GrowthMetric(stride=stride)
    lus: collections.Counter = collections.Counter()
    qz: collections.Counter = collections.Counter()
    factor = eigen.factor_shifted

    counting = {"on": False}

    def counted_factor(M, sigma):
        if counting["on"]:
            lus[M.shape[0]] += 1
        return factor(M, sigma)

    eigen.factor_shifted = counted_factor
    import scipy.linalg as sla

    eig = sla.eig

    def counted_eig(a, b=None, *args, **kw):
        if counting["on"]:
            qz[a.shape[0]] += 1
        return eig(a, b, *args, **kw)

    sla.eig = counted_eig
    records = []
    cpu = {"longwave": 0.0, "growth": 0.0}
    s = stride
    for i, th in enumerate(cfg.theta):
        if i % s != s // 2:
            continue
        for j, nu in enumerate(cfg.nu0):
            if j % s != s // 2:
                continue
            try:
                flow = solve_steady(
                    th,
                    nu,
                    cfg.model,
                    nu_top=cfg.nu_top,
                    rtol=cfg.steady_rtol,
                    n_max=cfg.n_max,
                    min_thickness=0.0,
                )
            except ChuteflowError:
                continue
            point = Point(i, j, th, nu)
            rec = {"theta": th, "nu0": nu}
            for name, fn in (("longwave", lw), ("growth", gm)):
                lu0 = sum(lus.values())
                counting["on"] = name == which
                c0 = time.process_time()
                try:
                    vals = dict(fn.compute(flow, point))
                except ChuteflowError as exc:
                    vals = {"error": str(exc)}
                dt = time.process_time() - c0
                cpu[name] += dt
                point.values.update(vals)
                if name == which:
                    rec["cpu"] = dt
                    rec["lus"] = sum(lus.values()) - lu0
                    rec.update({k: v for k, v in vals.items() if not _nan(v)})
                if name == "longwave" and which == "longwave":
                    break
            rec["notes"] = point.notes
            records.append(rec)
        print(f"theta row {i}: {len(records)} flows, {cpu[which]:.1f} s CPU in {which}", flush=True)
    print(f"{which}: {len(records)} flows, {cpu[which]:.2f} s CPU")
    print(f"  LUs by size: {dict(sorted(lus.items()))}  (total {sum(lus.values())})")
    print(f"  dense QZ by size: {dict(sorted(qz.items()))}")
    for r in sorted(records, key=lambda r: -r["cpu"])[:top]:
        print(f"  {r['theta']:.4f} {r['nu0']:.5f}: {r['cpu']:.2f} s, {r['lus']} LUs")
    if "out" in opts:
        with open(opts["out"], "w") as f:
            json.dump(records, f, indent=1, default=lambda o: bool(o) if isinstance(o, np.bool_) else str(o))


if __name__ == "__main__":
    main(sys.argv[1:])
