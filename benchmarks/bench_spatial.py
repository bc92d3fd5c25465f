"""Benchmarks of the spatial stability solvers (issue 43, "Speed"), one BLAS thread.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio, note (the
interface of ``benchmarks/run.py``; ratio = baseline / chuteflow). Run alone:
``python benchmarks/bench_spatial.py [--quick]``. Flows: the paper's unstable points P1
(16°, 0.05), P4 (14°, 0.05), P5 (17°, 0.10), φ = 0.05; the steady solve is excluded, every
timing starts from a fresh operator cache (operators built inside the timing), best of
``rep`` repetitions after a warm-up (compilation excluded).

- ``spatial_point_<P>``: :func:`chuteflow.spatial.spatial_point` at the point's most
  amplified frequency ω_max (the seed scan at k = 1e-4, Newton along the real axis, Newton in
  the complex k plane, drift and tail). Target ≤ 1 s.
- ``absolute_<P>``: :func:`chuteflow.spatial.absolute_instability` (temporal branch scan,
  the saddle family continued in V both ways, edges, Briggs' pinch check, drift at the
  saddle). Target ≤ 5 s.

Baseline, measured in the same run beside each row: one dense QZ
(``scipy.linalg.eig(A, B)``, eigenvalues only) of the equilibrated pencil at the same N and
the temporal peak's k — what one eigenvalue costs without the targeted solver.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


from benchmarks._timing import best_of as _best

#: ω_max at the paper's unstable points (measured: tests/spatial/test_spatial_metric.py and
#: the metric ``spatial``); their (θ, ν0(0)) from papers.mitarai2004.points.
OMEGA_MAX = {"P1": 0.0171871, "P4": 0.00231089, "P5": 0.0279487}


def run(quick: bool = False) -> list[dict]:
    import warnings

    import scipy.linalg as sla

    from chuteflow._threads import limit_blas_threads
    from chuteflow.closures import ChuteModel
    from chuteflow.papers.mitarai2004.points import point
    from chuteflow.spatial import absolute_instability, spatial_point
    from chuteflow.stability import OperatorCache, stability_operator
    from chuteflow.steady import solve_steady

    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    rep = 1 if quick else 3
    names = ["P1"] if quick else list(OMEGA_MAX)
    rows = []
    for name in names:
        theta, nu0, w = point(name).theta, point(name).nu0, OMEGA_MAX[name]
        flow = solve_steady(theta, nu0, ChuteModel(roughness=0.05))
        spatial_point(flow, w, cache=OperatorCache())  # warm-up (compilation)
        t_sp, pt = _best(lambda f=flow, w=w: spatial_point(f, w, cache=OperatorCache()), rep)
        t_abs, res = _best(lambda f=flow: absolute_instability(f, cache=OperatorCache()), max(1, rep - 1))
        for row, t, n, k in (
            (f"spatial_point_{name}", t_sp, pt.n, pt.k_real),
            (f"absolute_{name}", t_abs, res.n, res.k_peak),
        ):
            A, B = stability_operator(flow, n, cache=OperatorCache()).pencil(k).equilibrated()
            t_qz, _ = _best(lambda A=A, B=B: sla.eig(A, B, right=False, check_finite=False), max(1, rep - 1))
            if row.startswith("spatial"):
                note = (
                    f"omega = {w:g}: -Im k = {pt.spatial_growth:.6e}, N = {n}, converged "
                    f"{pt.converged}; target <= 1 s"
                )
            else:
                note = (
                    f"{res.verdict}, V- = {res.v_minus:.6f}, V+ = {res.v_plus:.6f}, N = {n}, "
                    f"converged {res.converged}; target <= 5 s"
                )
            rows.append(
                {
                    "name": row,
                    "seconds": t,
                    "baseline_seconds": t_qz,
                    "ratio": t_qz / t,
                    "note": note + f"; baseline one dense QZ at N = {n} (M = {A.shape[0]})",
                }
            )
    return rows


if __name__ == "__main__":
    for r in run(quick="--quick" in sys.argv):
        print(
            f"{r['name']:24s} {r['seconds']:8.3f} s  baseline {r['baseline_seconds']:8.3f} s  "
            f"ratio {r['ratio']:6.2f}  {r['note']}"
        )
