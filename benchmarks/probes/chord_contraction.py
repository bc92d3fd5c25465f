"""Probe (issue 9, item 4): why a neighbour's LU does not replace the coarse rung's factorisation.

    PYTHONPATH=src python benchmarks/probes/chord_contraction.py [ROUGHNESS] [SIZE]

A steady map's continuation step (:func:`chuteflow.steady.continuation_step._continue`) starts Newton
from the Euler predictor of its neighbour and may take *chord* steps with the neighbour's LU
(:attr:`chuteflow.steady.newton.SteadyNewton.chord`, ``inherit``); a chord step is kept
while it lowers the residual at least ten times. On the 60 × 60 paper map the first such step
is kept at most points (it removes the predictor's O(Δν0²) error) and the second is not, so
every converged point still factorises once at its coarse rung (stop 35).

For a few points of the SIZE × SIZE diagram grid of the paper (default φ = 0.05, 60 × 60)
this prints, at n = 64 on the first point's grid map, the spectral radius ρ of I − J_a⁻¹ J_b
(J_a: the Jacobian at the converged point a, J_b at its neighbour b one grid step up in ν0(0)
or in θ; ρ is the asymptotic contraction of chord steps at b with a's LU), the unknown that
dominates the slowest error mode (y_max, the free top of the domain, at most points), and the
residuals of four steps from the Euler predictor: chord steps with J_a, Broyden's update of
J_a (Kelley's "brsola" form; one residual and one back-solve a step, as the chord) and full
Newton. A chord that is to replace the factorisation (~0.5 ms at n = 64: Jacobian, elimination
and LU, against ~0.12 ms for a residual and a back-solve) would need ρ ≲ 0.01; measured
ρ = 0.08 … 1.9 (docs/numerics.md).
"""

from __future__ import annotations

import sys


def main(argv: list[str]) -> None:
    roughness = float(argv[0]) if argv else 0.05
    size = int(argv[1]) if len(argv) > 1 else 60

    import numpy as np

    from chuteflow._threads import limit_blas_threads

    limit_blas_threads(1)
    np.seterr(all="ignore")  # a diverging chord leaves the closures' domain (NaN, shown)
    from chuteflow.closures import ChuteModel
    from chuteflow.errors import ChuteflowError
    from chuteflow.papers.mitarai2004.points import DIAGRAM_RANGES
    from chuteflow.steady.newton import SteadyNewton
    from chuteflow.steady.one_grid import solve_state
    from chuteflow.steady.state import NewtonState
    from chuteflow.steady.tangent import state_tangent_vectors

    model = ChuteModel(roughness=roughness)
    (t0, t1), (n0, n1) = DIAGRAM_RANGES[roughness]
    ths, nus = np.linspace(t0, t1, size), np.geomspace(n0, n1, size)
    n, nu_top = 64, 1e-9
    names = ("ln nu0", "u0", "T0")

    def dominant(v: np.ndarray) -> str:
        k = int(np.argmax(np.abs(v)))
        return "y_max" if k == len(v) - 1 else f"{names[k // (n + 1)]} at node {k % (n + 1)}"

    print(f"phi = {roughness:g}, {size} x {size} grid, n = {n}: rho(I - J_a^-1 J_b), then the")
    print("max-norm residual after 0 … 4 steps from the Euler predictor (chord / Broyden / Newton)")
    # points as fractions of the grid (the 60 × 60 grid's rows 40, 20, 50, 54, 45)
    for fi, fj in ((0.678, 0.339), (0.339, 0.508), (0.508, 0.847), (0.915, 0.678), (0.763, 0.169)):
        i, j = min(round(fi * (size - 1)), size - 2), min(round(fj * (size - 1)), size - 2)
        for label, (tb, nb) in (("nu0 step", (ths[i], nus[j + 1])), ("theta step", (ths[i + 1], nus[j]))):
            ta, na = ths[i], nus[j]
            try:
                sa = solve_state(ta, na, model, nu_top, n)[0]
                sb = solve_state(tb, nb, model, nu_top, n, guess=sa, grid_map=sa.grid_map)[0]
            except (ChuteflowError, ArithmeticError, ValueError) as exc:
                print(f"theta = {ta:.3f}, nu0 = {na:.4f} ({label}): no flow pair ({type(exc).__name__})")
                continue
            A = SteadyNewton(n, ta, na, model, nu_top, grid_map=sa.grid_map)
            B = SteadyNewton(n, tb, nb, model, nu_top, grid_map=sa.grid_map)
            Ja, Jb = A.evaluate(sa)[1], B.evaluate(sb)[1]
            assert Ja is not None
            assert Jb is not None
            w, V = np.linalg.eig(np.eye(len(Ja)) - np.linalg.solve(Ja, Jb))
            top = int(np.argmax(np.abs(w)))
            # the Euler predictor of the map's continuation (dX/dν0 and dX/dθ at a)
            d_nu, d_theta = state_tangent_vectors(ta, na, model, nu_top, sa)
            X0 = sa.pack() + (nb - na) * d_nu + (tb - ta) * d_theta
            rows = []
            for kind in ("chord", "Broyden", "Newton"):
                X, res, steps = X0.copy(), [], []
                for _ in range(5):
                    st = NewtonState.unpack(n, X, sa.grid_map)
                    R, J = B.evaluate(st)
                    res.append(float(np.abs(R).max()))
                    if kind == "Newton":
                        assert J is not None
                        s = -np.linalg.solve(J, R)
                    else:
                        s = -np.linalg.solve(Ja, R)
                        if kind == "Broyden" and steps:
                            for a, b in zip(steps[:-1], steps[1:]):
                                s = s + b * (a @ s) / (a @ a)
                            last = steps[-1]
                            s = s / (1.0 - (last @ s) / (last @ last))
                    steps.append(s)
                    X = X + s
                rows.append(f"{kind} " + " ".join(f"{r:.0e}" for r in res))
            print(
                f"theta = {ta:.3f}, nu0 = {na:.4f} ({label}): rho = {abs(w[top]):.3f}, slowest mode "
                f"mostly {dominant(V[:, top])}; y_max {sa.L:.4g} -> {sb.L:.4g}"
            )
            print("    " + " | ".join(rows))


if __name__ == "__main__":
    main(sys.argv[1:])
