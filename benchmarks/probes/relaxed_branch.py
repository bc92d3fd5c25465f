"""Probe (issue 9, item 2): past the continuum, is the branch followed with the relaxed tail
threshold the branch? The evidence behind ``RejectionPolicy.relaxed_k_max`` and
``after_lost_branch``.

    PYTHONPATH=src python benchmarks/probes/relaxed_branch.py [P4] [0.1,0.2,0.5] [100,125,160,200,244]
        [--band] [--sigma=-0.03-0.817j]

For each k and N, on the sinh-mapped and on the plain grid: the value of
``near_continuum_branch`` (drift, tail, phase velocity −Im α/k) and the direct solve's mode
(``direct_mode``: dense QZ at N and N'). With ``--band``: the QZ eigenvalues at the largest N
whose phase velocity lies in the range of u0. With ``--sigma=S``: the eigenvalue nearest S by
shift-invert (``least_stable(sigma=S)``) at N = 125 … 360 on both grids.

Measured (P4, k = 0.5): the continuation lands on different members of a band of
critical-layer eigenvalues (Re α from −0.018 to −0.22, tails ~1e-3) at each N and grid
(N = 200: −0.0279 − 0.8199i mapped, −0.0350 − 0.8188i plain). One eigenvalue of the band
converges: −0.0300272 − 0.8170587i (N = 200, drift 6.4e-4, tail 1.8e-5), −0.0300167 −
0.8171262i (244, 2.0e-4, 4.9e-6), −0.0300283 − 0.8171609i (300, 4.2e-5, 9.0e-7),
−0.0300217 − 0.8171577i (360, 9.1e-6, 1.3e-7); plain grid at 360: −0.0300326 − 0.8171525i.
That is the branch; the direct solve's resolved mode −2.5105894 − 0.8721045i is far more
damped. At P5 the direct mode −0.3666995 − 8.4620970i is less damped than the relaxed
value −0.828 − 7.629i.
"""

from __future__ import annotations

import sys
import time

from chuteflow.closures import ChuteModel
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.stability import OperatorCache, least_stable
from chuteflow.stability.lost import near_continuum_branch
from chuteflow.stability.modes import direct_mode, spectrum
from chuteflow.steady import solve_steady


def main(argv):
    band = "--band" in argv
    sigma = next((complex(a.split("=", 1)[1]) for a in argv if a.startswith("--sigma=")), None)
    argv = [a for a in argv if not a.startswith("--")]
    name = argv[0] if argv else "P4"
    ks = [float(x) for x in argv[1].split(",")] if len(argv) > 1 else [0.1, 0.2, 0.5]
    ns = [int(x) for x in argv[2].split(",")] if len(argv) > 2 else [100, 125, 160, 200, 244]
    p = POINTS[name]
    flow = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
    u_lo, u_hi = float(flow.u.min()), float(flow.u.max())
    print(f"{name}: u0 in [{u_lo:.5f}, {u_hi:.5f}]")
    if sigma is not None:
        for mapped in (True, False):
            for n in (125, 160, 200, 244, 300, 360):
                m = least_stable(flow, ks[-1], sigma=sigma, n=n, cache=OperatorCache(2, mapped=mapped))
                grid = "mapped" if mapped else "plain"
                head = f"sigma: k = {ks[-1]:g} N = {n} {grid}:"
                print(f"{head} {m.alpha:.7f} drift {m.drift:.1e} tail {m.tail:.1e}")
        return
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
