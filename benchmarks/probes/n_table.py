"""Probe (issue 9, item 2): resolution N needed for the paper's tests (drift and tail < 1e-7)
on the plain and on the sinh-mapped grid, and the agreement of the two at high N.

    PYTHONPATH=src python benchmarks/probes/n_table.py [P1,P2,...] [0.002,0.005,0.02,0.5]

For each paper point and k: N_plain, N_mapped (smallest N of 32, 40, 48, 56, 64, 80, 100,
125, 160, 200, 256 at which ``least_stable(flow, k, n=N)`` is physical) and
|α_mapped(200) − α_plain(200)| / |α|.
"""

from __future__ import annotations

import sys
import time

from chuteflow.closures import ChuteModel
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.stability import OperatorCache, least_stable
from chuteflow.steady import solve_steady

LADDER = (32, 40, 48, 56, 64, 80, 100, 125, 160, 200, 256)


def n_needed(flow, k, cache):
    for n in LADDER:
        m = least_stable(flow, k, n=n, cache=cache)
        if m.physical:
            return n
    return None


def main(argv):
    names = argv[0].split(",") if argv else list(POINTS)
    ks = [float(x) for x in argv[1].split(",")] if len(argv) > 1 else [0.002, 0.005, 0.02, 0.5]
    print("point  k       N_plain  N_mapped  |a_map(200)-a_plain(200)|/|a|   alpha(mapped, 200)")
    for name in names:
        p = POINTS[name]
        flow = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
        for k in ks:
            t0 = time.perf_counter()
            plain, mapped = OperatorCache(3, mapped=False), OperatorCache(3)
            np_, nm = n_needed(flow, k, plain), n_needed(flow, k, mapped)
            ap = least_stable(flow, k, n=200, cache=plain).alpha
            am = least_stable(flow, k, n=200, cache=mapped).alpha
            print(
                f"{name:5s}  {k:<6g}  {np_ or '>256':>7}  {nm or '>256':>8}  {abs(am - ap) / abs(am):14.2e}"
                f"                 {am:.12g}  ({time.perf_counter() - t0:.0f} s)",
                flush=True,
            )


if __name__ == "__main__":
    main(sys.argv[1:])
