"""Probe (issue 9, item 2): is the branch followed with the relaxed tail threshold the branch,
or a member of the continuum? The evidence behind ``RejectionPolicy.relaxed_k_max``.

    PYTHONPATH=src python benchmarks/probes/relaxed_branch.py [P4] [0.1,0.2,0.5] [100,125,160,200,244]

For each k and N, on the sinh-mapped and on the plain grid: the value of
``near_continuum_branch`` (drift, tail, phase velocity −Im α/k) and the direct solve's mode
(``direct_mode``: dense QZ at N and N'). A value that converges is the same, within its
drift, at every N and on both grids; at P4 (θ = 14°, ν0(0) = 0.05) for k ≥ 0.1 the relaxed
value scatters by 1e-3 … 7e-3 (each N and grid picks a different member of a band of
unresolved eigenvalues with tails ~1e-3 inside the range of u0), while the direct mode
agrees to ≤ 2e-7. With ``--band`` it also lists the QZ eigenvalues at the largest N whose
phase velocity lies in the range of u0 (the band).
"""

from __future__ import annotations

import sys
import time

from chuteflow.closures import ChuteModel
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.stability import OperatorCache
from chuteflow.stability.dispersion import near_continuum_branch
from chuteflow.stability.modes import direct_mode, spectrum
from chuteflow.steady import solve_steady


def main(argv):
    band = "--band" in argv
    argv = [a for a in argv if a != "--band"]
    name = argv[0] if argv else "P4"
    ks = [float(x) for x in argv[1].split(",")] if len(argv) > 1 else [0.1, 0.2, 0.5]
    ns = [int(x) for x in argv[2].split(",")] if len(argv) > 2 else [100, 125, 160, 200, 244]
    p = POINTS[name]
    flow = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
    u_lo, u_hi = float(flow.u.min()), float(flow.u.max())
    print(f"{name}: u0 in [{u_lo:.5f}, {u_hi:.5f}]")
    print("k      N    grid    relaxed alpha (drift, tail, c)               direct alpha (drift, tail)")
    for k in ks:
        for n in ns:
            for mapped in (True, False):
                cache = OperatorCache(2, mapped=mapped)
                t0 = time.perf_counter()
                r = near_continuum_branch(flow, k, n=n, cache=cache)
                d = direct_mode(flow, k, n=n, cache=cache)
                rs = "none"
                if r is not None:
                    rs = f"{r.alpha:.6f} ({r.drift:.1e}, {r.tail:.1e}, {-r.alpha.imag / k:.4f})"
                ds = "none" if d is None else f"{d.alpha:.9f} ({d.drift:.1e}, {d.tail:.1e})"
                grid = "mapped" if mapped else "plain"
                dt = time.perf_counter() - t0
                print(f"{k:<6g} {n:<4d} {grid:<7s} {rs:<44s} {ds}  [{dt:.1f} s]", flush=True)
        if band:
            for mapped in (True, False):
                cache = OperatorCache(2, mapped=mapped)
                modes = spectrum(flow, k, n=ns[-1], physical_only=False, cache=cache)
                inside = [
                    m for m in modes if u_lo <= -m.alpha.imag / k <= u_hi and -0.25 < m.alpha.real < -1e-3
                ]
                grid = "mapped" if mapped else "plain"
                print(f"  band at k = {k:g}, N = {ns[-1]}, {grid}: {len(inside)} eigenvalues")
                for m in inside[:12]:
                    print(f"    {m.alpha:.6f}  drift {m.drift:.1e}  tail {m.tail:.1e}")


if __name__ == "__main__":
    main(sys.argv[1:])
