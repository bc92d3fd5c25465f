"""Probe (issue 9, item 4): the deterministic work of the steady solver on the paper's map.

    PYTHONPATH=src python benchmarks/probes/steady_work.py [map|families] [SIZE]

``map``: :func:`chuteflow.steady.steady_map` on the SIZE × SIZE φ = 0.05 diagram grid of the
paper (default 60), one process. ``families``: the diagrams' steady metric, every other θ row
of that grid solved as a row family on its own (:func:`chuteflow.sweep.runner._steady_chunk`).

Prints the statuses and the work counted while it runs: Newton steps (one LU each), residual
evaluations, Σ (n/64)² and Σ (n/64)³ over the steps (the LU's cost grows between the two),
the continuation attempts by outcome, and the CPU time. The counts do not depend on the
machine's load; CPU times of two processes side by side differed by up to ±15 % on the
2-core development machine (issue 9, stop 28). Compare two versions by their counts, e.g.
``PYTHONPATH=/path/to/other/checkout/src python benchmarks/probes/steady_work.py map``
(a quadratic row predictor cut the map's LUs by 10 % but not Σ (n/64)², and raised both for
the families: dropped).
"""

from __future__ import annotations

import collections
import sys
import time

import numpy as np


def main(argv: list[str]) -> None:
    mode = argv[0] if argv else "map"
    size = int(argv[1]) if len(argv) > 1 else 60
    if mode not in ("map", "families"):
        raise SystemExit("usage: steady_work.py [map|families] [SIZE]")

    from chuteflow._threads import limit_blas_threads

    limit_blas_threads(1)
    import chuteflow.steady.continuation_step as continuation_step
    import chuteflow.steady.newton as newton
    import chuteflow.steady.proofs as proofs
    from chuteflow.papers.mitarai2004.points import DIAGRAM_RANGES
    from chuteflow.steady import solve_steady, steady_map

    solve_steady(16.0, 0.05)  # generated code and caches, outside the count
    work: collections.Counter = collections.Counter()
    attempts: collections.Counter = collections.Counter()
    step, residual, attempt = (
        newton.SteadyNewton.step,
        newton.SteadyNewton._residual,
        continuation_step._attempt,
    )

    def counted_step(self, st, B):
        work["newton steps (LUs)"] += 1
        work["sum (n/64)^2"] += (self.n / 64) ** 2
        work["sum (n/64)^3"] += (self.n / 64) ** 3
        return step(self, st, B)

    def counted_residual(self, st):
        work["residuals"] += 1
        return residual(self, st)

    def counted_attempt(*args, **kw):
        p = attempt(*args, **kw)
        attempts[p.status] += 1
        return p

    newton.SteadyNewton.step = counted_step
    newton.SteadyNewton._residual = counted_residual
    continuation_step._attempt = proofs._attempt = counted_attempt

    (t0, t1), (n0, n1) = DIAGRAM_RANGES[0.05]
    ths, nus = np.linspace(t0, t1, size), np.geomspace(n0, n1, size)
    c0 = time.process_time()
    if mode == "map":
        statuses = steady_map(ths, nus, workers=1).status.values.ravel()
    else:
        from chuteflow.sweep import SweepConfig
        from chuteflow.sweep.runner import _steady_chunk

        cfg = SweepConfig.grid(0.05, shape=(size, size), markers=())
        statuses = np.array(
            [p[1] for i in range(0, size, 2) for p in _steady_chunk(cfg, cfg.theta[i], cfg.nu0, cfg.model)]
        )
    cpu = time.process_time() - c0
    print(f"{mode}, {size} x {size}: statuses {dict(collections.Counter(statuses.tolist()))}")
    print("work: " + ", ".join(f"{k} {v:.6g}" for k, v in work.items()))
    print(f"continuation and Newton attempts by outcome: {dict(attempts)}")
    print(f"CPU {cpu:.1f} s (machine-dependent)")


if __name__ == "__main__":
    main(sys.argv[1:])
