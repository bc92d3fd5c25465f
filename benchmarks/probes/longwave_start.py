"""Probe (issue 9, item 4): the long-wave metric with and without the strict Taylor α2.

    PYTHONPATH=src python benchmarks/probes/longwave_start.py [STRIDE] [--size=60] [--roughness=0.05]

The sweep's long-wave metric (``LongWaveMetric``, version 8) computes Re α/k² at k = 1e-5 by
one shift-invert solve per rung. Up to version 7 the solve at the finer rung started from
bordered perturbation theory (the grid's α1 k as the shift, V0 + k V1 as the start vector),
which also gave the strict Taylor α2 that no classification used; version 8 skips it unless
asked (``taylor=True``) and starts from the exact α1 k (eq. (B 2)) and V0.

For the flows of every STRIDE-th grid point in θ and ν0(0) (default 2: 661 flows of the
60 × 60 φ = 0.05 diagram's grid), in one process, ``eigen_sign`` with ``taylor=True`` and
``False`` alternately per flow: the CPU of each, the resolutions N reached, and the
relative change of Re α/k² between the two (percentiles, the largest ones against each
flow's own convergence estimate, and sign changes).
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections import Counter


def main(argv: list[str]) -> None:
    opts = {a[2:].split("=", 1)[0]: a.split("=", 1)[1] for a in argv if a.startswith("--")}
    rest = [a for a in argv if not a.startswith("--")]
    stride = int(rest[0]) if rest else 2
    import numpy as np

    from chuteflow._threads import limit_blas_threads
    from chuteflow.errors import ChuteflowError
    from chuteflow.longwave.theory import eigen_sign
    from chuteflow.stability import OperatorCache
    from chuteflow.steady import solve_steady
    from chuteflow.sweep import SweepConfig

    limit_blas_threads(1)
    size = int(opts.get("size", 60))
    cfg = SweepConfig.grid(float(opts.get("roughness", 0.05)), shape=(size, size), markers=())
    kw = dict(nu_top=cfg.nu_top, rtol=cfg.steady_rtol, n_max=cfg.n_max, min_thickness=0.0)
    flows = []
    for th in cfg.theta[1::stride]:
        for nu in cfg.nu0[1::stride]:
            with contextlib.suppress(ChuteflowError):
                flows.append(solve_steady(th, nu, cfg.model, **kw))
    if not flows:
        raise SystemExit(f"no steady flow at the grid points of stride {stride} on the {size} x {size} grid")
    cpu = {True: 0.0, False: 0.0}
    res: dict[bool, list] = {True: [], False: []}
    for i, f in enumerate(flows):
        for taylor in (True, False) if i % 2 else (False, True):
            t = time.process_time()
            es = eigen_sign(f, n=60, n_max=160, rtol=0.05, cache=OperatorCache(2), taylor=taylor)
            cpu[taylor] += time.process_time() - t
            res[taylor].append((es.coefficient, es.convergence, es.n))
    for taylor in (True, False):
        print(
            f"taylor={taylor!s:5}  {len(flows)} flows  {1e3 * cpu[taylor] / len(flows):6.2f} ms a flow  "
            f"N: {sorted(Counter(r[2] for r in res[taylor]).items())}"
        )
    a = np.array([r[0] for r in res[True]])
    b = np.array([r[0] for r in res[False]])
    est = np.maximum([r[1] for r in res[True]], [r[1] for r in res[False]])
    rel = np.abs(a - b) / np.abs(a)
    print("relative change of Re α/k², percentiles 50/90/99/100:", np.nanpercentile(rel, [50, 90, 99, 100]))
    print(
        "sign changes:",
        int(np.sum(np.sign(a) != np.sign(b))),
        " N changes:",
        int(sum(x[2] != y[2] for x, y in zip(res[True], res[False]))),
    )
    print("largest changes (theta, nu0, Re α/k² with, without, change, larger estimate):")
    for j in np.argsort(-np.nan_to_num(rel))[:8]:
        f = flows[j]
        print(f"  {f.theta:8.4f} {f.nu0:7.4f}  {a[j]:12.6g} {b[j]:12.6g}  {rel[j]:.1e}  {est[j]:.1e}")


if __name__ == "__main__":
    main(sys.argv[1:])
