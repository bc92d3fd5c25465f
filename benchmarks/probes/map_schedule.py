"""Probe (issue 9, item 4): how a steady map's work is shared between its processes.

    PYTHONPATH=src python benchmarks/probes/map_schedule.py [ROUGHNESS] [SIZE]

Runs :func:`chuteflow.steady.steady_map` on the SIZE × SIZE diagram grid of the paper
(default φ = 0.05, 60 × 60) with two processes and prints, for each process, when it ran
the start-row searches and the chains of rows (seconds from the call), its busy time, and
the wall time. The wall time of a map is about the later process's end: where one process
idles while the other works (before stop 33 the process that found the lower start row
waited ~1.1 s for the upper one), the schedule shows it. Wall times on the 2-core
development machine vary by ±15 % from run to run; the shares of the two processes do not.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time


def main(argv: list[str]) -> None:
    roughness = float(argv[0]) if argv else 0.05
    size = int(argv[1]) if len(argv) > 1 else 60

    import numpy as np

    from chuteflow._threads import limit_blas_threads

    limit_blas_threads(1)
    import chuteflow.steady.maps as maps
    from chuteflow.closures import ChuteModel
    from chuteflow.papers.mitarai2004.points import DIAGRAM_RANGES
    from chuteflow.steady import steady_map

    with tempfile.NamedTemporaryFile("w", suffix=".log", delete=False) as fh:
        log = fh.name

    def logged(func, label):
        # a module-level name the pool pickles by reference: the forked processes see it
        def run(args):
            a = time.time()
            out = func(args)
            with open(log, "a") as fh:
                fh.write(f"{label} {os.getpid()} {a} {time.time()}\n")
            return out

        run.__module__, run.__qualname__ = maps.__name__, func.__name__
        return run

    maps._first_good_worker = logged(maps._first_good_worker, "start-row search")
    maps._sweep_worker = logged(maps._sweep_worker, "chain")
    (t0, t1), (n0, n1) = DIAGRAM_RANGES[roughness]
    ths, nus = np.linspace(t0, t1, size), np.geomspace(n0, n1, size)
    start = time.time()
    ds = steady_map(ths, nus, ChuteModel(roughness=roughness), workers=2)
    wall = time.time() - start
    with open(log) as fh:
        rows = [line.split() for line in fh]
    os.unlink(log)
    events = sorted((int(r[-3]), float(r[-2]) - start, float(r[-1]) - start, " ".join(r[:-3])) for r in rows)
    for pid in sorted({e[0] for e in events}):
        mine = [e for e in events if e[0] == pid]
        print(f"process {pid}: busy {sum(b - a for _, a, b, _ in mine):.2f} s")
        for _, a, b, what in mine:
            print(f"  {a:6.2f} -> {b:6.2f} s  {what} ({b - a:.2f} s)")
    statuses = dict(zip(*np.unique(ds.status.values, return_counts=True)))
    print(f"wall {wall:.2f} s; statuses { ({str(k): int(v) for k, v in statuses.items()}) }")


if __name__ == "__main__":
    main(sys.argv[1:])
