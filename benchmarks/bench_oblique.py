"""Benchmark of the mode resolver at oblique wavevectors (issue 40), one BLAS thread.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio, note (the
interface of ``benchmarks/run.py``). Run alone: ``python benchmarks/bench_oblique.py
[--quick]``.

- ``oblique_eig_<P>``: ``least_stable(flow, kx, kz=kz)`` at every (k_x, k_z) in
  {0.002, 0.005} × {0.002, 0.02, 0.1} for the paper's points (quick: P1, P4, P5), each with
  empty operator caches (as one ``chuteflow eig --kx --kz`` call); seconds = the slowest of
  the six, baseline = one dense QZ (eigenvalues and eigenvectors) of the 405 × 405 complex
  pencil of P1 at (0.002, 0.02), N = 80, measured in the same run; ratio = slowest /
  baseline (the issue's target: each call ≤ 2 s and ≤ 10 × that QZ). The note gives every
  call's time and whether all six converged.

The answers themselves are checked against a brute-force dense QZ by
``benchmarks/probes/oblique_check.py`` (and ``tests/stability/test_resolver.py``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

KXS = (0.002, 0.005)
KZS = (0.002, 0.02, 0.1)


def _unit_qz() -> float:
    from chuteflow import ChuteModel, solve_steady
    from chuteflow.stability import OperatorCache
    from chuteflow.stability.eigen import qz

    flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
    A, B = OperatorCache(1, mapped_3d=True).get(flow, 80, True).pencil(0.002, 0.02).equilibrated()
    best = float("inf")
    for _ in range(2):
        t0 = time.perf_counter()
        qz(A, B)
        best = min(best, time.perf_counter() - t0)
    return best


def run(quick: bool = False) -> list[dict]:
    from chuteflow import ChuteModel, solve_steady
    from chuteflow.papers.mitarai2004.points import POINTS
    from chuteflow.stability import least_stable
    from chuteflow.stability.modes import OPERATORS, OPERATORS_3D

    unit = _unit_qz()
    rows = []
    names = ("P1", "P4", "P5") if quick else tuple(POINTS)
    for name in names:
        pt = POINTS[name]
        flow = solve_steady(pt.theta, pt.nu0, ChuteModel(roughness=pt.roughness))
        least_stable(flow, KXS[0], kz=KZS[0])  # warm-up: compiled code, caches of the flow
        times, conv = [], []
        for kx in KXS:
            for kz in KZS:
                OPERATORS.clear()
                OPERATORS_3D.clear()
                t0 = time.perf_counter()
                mode = least_stable(flow, kx, kz=kz)
                times.append(time.perf_counter() - t0)
                conv.append(mode.converged)
        worst = max(times)
        rows.append(
            {
                "name": f"oblique_eig_{name}",
                "seconds": worst,
                "baseline_seconds": unit,
                "ratio": worst / unit,
                "note": (
                    "slowest of 6 (kx, kz) / one 405x405 QZ (target <= 2 s and <= 10x); each: "
                    + ", ".join(f"{t:.2f}" for t in times)
                    + f" s; converged {sum(conv)}/6"
                ),
            }
        )
    return rows


if __name__ == "__main__":
    for row in run(quick="--quick" in sys.argv):
        print(row)
