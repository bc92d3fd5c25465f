"""Oblique wavevectors against a brute-force reference (issue 40: the mode resolver's contract).

For each flow (the paper's eight points and seeded random off-paper flows) and each
(k_x, k_z) in {0.002, 0.005} × {0.002, 0.02, 0.1}: :func:`chuteflow.stability.least_stable`
with empty operator caches (as one ``chuteflow eig`` call), timed, against the brute-force
reference: dense QZ of the whole spectrum at N = 156 and N' = 125 on the mapped grid, the
physical mode of largest Re α (drift and tail < 1e-7), no tracking, no candidates. A
different mode reported as converged is WRONG; an answer flagged where the reference has a
resolved mode is listed as flagged. Prints one line a case and a summary; also times one
dense QZ of a 405 × 405 complex pencil (the issue's unit).

    python benchmarks/probes/oblique_check.py [--random 8] [--seed 40] [--plain-check]
"""

from __future__ import annotations

import argparse
import math
import random
import time

import numpy as np

from chuteflow import ChuteModel, solve_steady
from chuteflow.errors import ChuteflowError
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.stability import least_stable
from chuteflow.stability.eigen import qz
from chuteflow.stability.modes import OPERATORS, OPERATORS_3D, OperatorCache, check_n, make_mode


def reference(flow, kx, kz, n=156, mapped=True):
    """Brute force: every eigenvalue at N by dense QZ, drift against N' by dense QZ."""
    cache = OperatorCache(2, mapped=mapped, mapped_3d=mapped)
    p1 = cache.get(flow, n, True).pencil(kx, kz)
    n2 = check_n(n)
    p2 = cache.get(flow, n2, True).pencil(kx, kz)
    w1, V1 = qz(*p1.equilibrated())
    w2, _ = qz(*p2.equilibrated(), vectors=False)
    pending = None
    for j in range(len(w1)):
        d = float(np.abs(w2 - w1[j]).min())
        m = make_mode(p1, w1[j], V1[:, j], d, n2)
        if m.physical:
            return m, pending
        if pending is None and m.tail < 1e-5 and d < 1e-4:
            pending = m
    return None, pending


def unit_qz():
    """One dense QZ of the 405 × 405 complex pencil of P1 at (0.002, 0.02), N = 80 (3D)."""
    flow = solve_steady(theta=16.0, nu0=0.05, model=ChuteModel(roughness=0.05))
    A, B = OperatorCache(1, mapped_3d=True).get(flow, 80, True).pencil(0.002, 0.02).equilibrated()
    best = math.inf
    for _ in range(2):
        t = time.perf_counter()
        qz(A, B)
        best = min(best, time.perf_counter() - t)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--random", type=int, default=8)
    ap.add_argument("--seed", type=int, default=40)
    ap.add_argument("--kx", type=float, nargs="+", default=[0.002, 0.005])
    ap.add_argument("--kz", type=float, nargs="+", default=[0.002, 0.02, 0.1])
    ap.add_argument("--plain-check", action="store_true", help="reference on the plain grid at N = 250")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    flows = [
        (pt.name, dict(theta=pt.theta, nu0=pt.nu0), dict(roughness=pt.roughness)) for pt in POINTS.values()
    ]
    while len(flows) < len(POINTS) + a.random:
        phi = round(rng.uniform(0.04, 0.11), 4)
        th = round(rng.uniform(11.5 + 70 * (phi - 0.05), 19.5 + 110 * (phi - 0.05)), 3)
        nu0 = round(10 ** rng.uniform(-2.1, -0.66), 4)
        mk = dict(
            roughness=phi,
            wall_loss=round(rng.uniform(0.3, 0.5), 3),
            restitution=round(rng.uniform(0.6, 0.9), 3),
        )
        try:
            solve_steady(theta=th, nu0=nu0, model=ChuteModel(**mk))
        except ChuteflowError:
            continue
        flows.append((f"R{len(flows) - len(POINTS) + 1}", dict(theta=th, nu0=nu0), mk))
    unit = unit_qz()
    print(f"one dense QZ of a 405 x 405 complex pencil: {unit:.3f} s", flush=True)
    times, wrong, flagged, bad_ref = [], [], [], 0
    for name, fp, mk in flows:
        flow = solve_steady(**fp, model=ChuteModel(**mk))
        for kx in a.kx:
            for kz in a.kz:
                OPERATORS.clear()
                OPERATORS_3D.clear()
                t = time.perf_counter()
                m = least_stable(flow, kx, kz=kz)
                dt = time.perf_counter() - t
                times.append(dt)
                ref, pend = reference(flow, kx, kz, 250 if a.plain_check else 156, mapped=not a.plain_check)
                tag = ""
                if ref is None:
                    bad_ref += 1
                    tag = "reference: no resolved mode"
                else:
                    same = abs(m.alpha - ref.alpha) <= 1e-6 + 1e-4 * abs(ref.alpha)
                    if not same and ref.alpha.real > m.alpha.real:
                        if m.converged:
                            tag = "WRONG"
                            wrong.append((name, kx, kz))
                        else:
                            tag = "flagged"
                            flagged.append((name, kx, kz))
                    elif not same and m.converged and m.alpha.real > ref.alpha.real + 1e-6:
                        tag = "above reference" + (
                            f" (reference pending {pend.alpha:.6g})" if pend is not None else ""
                        )
                    elif same and not m.converged:
                        tag = "flagged, right value"
                r = f"{ref.alpha:.7g}" if ref is not None else "-"
                print(
                    f"{name} {fp} ({kx}, {kz}): {m.alpha:.7g} conv={m.converged} N={m.n} {m.method} "
                    f"{dt:.2f} s | ref {r} {tag}",
                    flush=True,
                )
    times = np.array(times)
    print(
        f"{len(times)} cases: time median {np.median(times):.2f} s, max {times.max():.2f} s "
        f"({times.max() / unit:.1f} x the 405 x 405 QZ), > 2 s: {(times > 2).sum()}; "
        f"WRONG {len(wrong)} {wrong}; flagged where the reference resolves {len(flagged)} {flagged}; "
        f"reference unresolved {bad_ref}"
    )


if __name__ == "__main__":
    main()
