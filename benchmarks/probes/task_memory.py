"""Probe (issue 9, item 4): the memory a sweep task holds, deterministically.

    PYTHONPATH=src python benchmarks/probes/task_memory.py [TASK ...] [--size=60] [--roughness=0.05]

A worker's peak resident memory (``bench_sweep.py``'s "worker peak RSS") is not
reproducible: the same task of the 60 × 60 φ = 0.05 diagram peaks at 257, 257, 277 and
277 MiB in four fresh processes (glibc's heap, the kernel's pages). This probe measures what
the Python objects of a task hold instead, which does not depend on the run: for each task
(a θ row of the diagram; default the growth rows 21, 45 and 51, where the peaks are), in
one process after the sweep's warm-up,

- the peak of the memory traced by :mod:`tracemalloc` during the task (numpy's arrays
  included), absolute and above the task's start;
- the arrays kept by reference cycles at the task's end, with Python's cyclic collector off
  through the task (what a run would hold until the collector happens to run: 28 MiB on
  row 21 before stop 36, when scipy's ``brentq`` kept the growth metric's operators).

Compare two versions by running it with each on ``PYTHONPATH``.
"""

from __future__ import annotations

import gc
import sys
import tracemalloc


def _cycle_arrays(garbage) -> tuple[int, float]:
    import numpy as np

    seen: dict[int, int] = {}
    for o in garbage:
        for x in [o, *gc.get_referents(o)]:
            if isinstance(x, np.ndarray):
                seen[id(x)] = x.nbytes
    return len(seen), sum(seen.values()) / 2**20


def main(argv: list[str]) -> None:
    opts = {a[2:].split("=", 1)[0]: a.split("=", 1)[1] for a in argv if a.startswith("--")}
    tasks = [int(a) for a in argv if not a.startswith("--")] or [21, 45, 51]
    from chuteflow._threads import limit_blas_threads
    from chuteflow.sweep import SweepConfig
    from chuteflow.sweep.runner import run_task, warm_up

    limit_blas_threads(1)
    size = int(opts.get("size", 60))
    cfg = SweepConfig.grid(float(opts.get("roughness", 0.05)), shape=(size, size), markers=())
    warm_up(cfg)
    all_tasks = cfg.tasks()
    tracemalloc.start()
    print("task  theta    traced peak MiB (above start)   arrays in cycles")
    for i in tasks:
        gc.collect()
        gc.disable()
        gc.set_debug(gc.DEBUG_SAVEALL)
        tracemalloc.reset_peak()
        start = tracemalloc.get_traced_memory()[0]
        try:
            res = run_task(cfg, all_tasks[i])
            peak = tracemalloc.get_traced_memory()[1]
            gc.collect()
            n, mib = _cycle_arrays(gc.garbage)
        finally:
            gc.set_debug(0)
            gc.garbage.clear()
            gc.enable()
        del res
        theta = cfg.theta[all_tasks[i].i]
        print(
            f"{i:4d}  {theta:7.3f}  {peak / 2**20:8.1f} ({(peak - start) / 2**20:6.1f})"
            f"            {n} ({mib:.1f} MiB)",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1:])
