"""The steady solver's rows derived from :mod:`chuteflow.equations` against the hand-written
forms they replace.

Before the rows came from the compiled first integral and far-field conditions, the steady
solver wrote the integrated x-momentum (§3, eq. (3.7), μ u0' = tan θ p) with its Jacobian,
T0' = 0 on top (eq. (3.13)) and the cold start's u0' = 0 on top by hand from the closures'
p and μ. That code is kept here, verbatim up to names, as the reference: the derived rows
must equal it to round-off, and Newton must take the same iterates.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.steady.cold_start import isothermal_guess
from chuteflow.steady.newton import SteadyNewton
from chuteflow.steady.state import NewtonState


def hand_written_rows(newton, st, jac=True):
    """The rows as the steady solver wrote them by hand (at commit f630553).

    Returns [(row slice, R rows, J rows)] for the integrated x-momentum (nodes 1..n) or,
    for the cold start's second-order form, u0' = 0 on top; and T0' = 0 on top.
    """
    n, m, L = newton.n, newton.n + 1, st.L
    D1 = newton.ref.D / L
    nu = np.exp(st.s)
    u1, T1 = D1 @ st.u, D1 @ st.T
    part = newton.model.evaluate(nu, st.T)
    N = 3 * m + 1
    R = np.zeros(N)
    J = np.zeros((N, N))
    tan, sc = newton.sin / newton.cos, 1.0 / newton.nu0
    mu, p = part["mu"], part["p"]
    if not newton.integrated:
        R[m + n] = u1[n]
        J[m + n, m : 2 * m] = D1[n]
        J[m + n, -1] = -R[m + n] / L
        xrows = slice(m + n, m + n + 1)
    else:
        R[m + 1 : m + m] = sc * (mu[(0, 0)][1:] * u1[1:] - tan * p[(0, 0)][1:])
        Jr = J[m + 1 : m + m]
        i = np.arange(n)
        Jr[:, m : 2 * m] = sc * mu[(0, 0)][1:, None] * D1[1:]
        Jr[i, 1 + i] = sc * nu[1:] * (mu[(1, 0)][1:] * u1[1:] - tan * p[(1, 0)][1:])
        Jr[i, 2 * m + 1 + i] = sc * (mu[(0, 1)][1:] * u1[1:] - tan * p[(0, 1)][1:])
        Jr[:, -1] = -sc * mu[(0, 0)][1:] * u1[1:] / L
        xrows = slice(m + 1, 2 * m)
    R[2 * m + n] = T1[n]
    J[2 * m + n, 2 * m : 3 * m] = D1[n]
    J[2 * m + n, -1] = -R[2 * m + n] / L
    trows = slice(2 * m + n, 2 * m + n + 1)
    return [(xrows, R[xrows], J[xrows]), (trows, R[trows], J[trows])]


class _HandWrittenNewton(SteadyNewton):
    """The steady Newton solver with the hand-written rows put back."""

    def evaluate(self, st, jac=True):
        R, J = super().evaluate(st, jac)
        for rows, r, j in hand_written_rows(self, st):
            R[rows] = r
            if jac:
                J[rows] = j
        return R, J


CASES = [(16.0, 0.05), (16.0, 0.15), (20.0, 0.17)]


@pytest.mark.parametrize(("theta", "nu0"), CASES)
@pytest.mark.parametrize("integrated", [True, False])
def test_derived_rows_equal_hand_written(theta, nu0, integrated):
    """At a state away from the solution (the isothermal cold start, and that start
    perturbed), the derived residual and Jacobian rows equal the hand-written ones to a few
    ulps of the row's largest entry."""
    model = ChuteModel(roughness=0.10 if theta == 20.0 else 0.05)
    newton = SteadyNewton(48, theta, nu0, model, 1e-9, integrated=integrated)
    st0 = isothermal_guess(theta, nu0, model, 1e-9, newton.ref)
    rng = np.random.default_rng(1)
    y = newton.ref.y
    wiggle = 0.05 * np.sin(3.0 * y) * rng.uniform(0.5, 1.0)
    st1 = NewtonState(st0.n, st0.s + wiggle, st0.u * (1 + wiggle), st0.T * (1 - wiggle), st0.L * 1.1)
    for st in (st0, st1):
        R, J = newton.evaluate(st)
        for rows, r, j in hand_written_rows(newton, st):
            scale_r = max(np.abs(r).max(), 1e-300)
            assert np.abs(R[rows] - r).max() <= 1e-13 * max(
                scale_r, np.abs(J[rows]).max() * np.abs(st.pack()).max()
            )
            for a, b in zip(J[rows], j):
                assert np.abs(a - b).max() <= 1e-13 * np.abs(b).max(), rows


@pytest.mark.parametrize(("theta", "nu0"), CASES)
def test_same_newton_iterates_as_hand_written(theta, nu0):
    """Cold start and polish with the derived and with the hand-written rows: the same
    number of iterations, residual histories that agree to round-off (absolute a few 1e-12,
    the floor of the scaled residual) and the same solution."""
    model = ChuteModel(roughness=0.10 if theta == 20.0 else 0.05)
    out = []
    for cls in (SteadyNewton, _HandWrittenNewton):
        cold = cls(32, theta, nu0, model, 1e-9, integrated=False)
        st, it0, _, h0 = cold.solve(
            isothermal_guess(theta, nu0, model, 1e-9, cold.ref), tol=1e-9, maxiter=30, lam_min=2.0**-10
        )
        polish = cls(32, theta, nu0, model, 1e-9)
        st, it, _, h1 = polish.solve(st, tol=1e-11)
        out.append((st.pack(), it0, it, np.array(h0), np.array(h1)))
    (X, a0, a1, ha0, ha1), (Y, b0, b1, hb0, hb1) = out
    assert (a0, a1) == (b0, b1)
    for ha, hb in ((ha0, hb0), (ha1, hb1)):
        assert len(ha) == len(hb)
        # scaled residuals carry absolute round-off ~1e-13 … 1e-12 (terms of O(1)
        # cancelling; derivatives (D_ξ f)/L in the derived rows, (D_ξ/L) f in the
        # hand-written ones, which round differently): the last entry, after Newton's
        # final step, lies at that floor (2.1e-12 and 0.9e-12 at θ = 16°, ν0(0) = 0.15)
        assert np.allclose(ha, hb, rtol=1e-8, atol=5e-12)
    assert np.abs(X - Y).max() <= 1e-10 * np.abs(Y).max()


def test_top_condition_is_far_field_at_k_zero():
    """The steady top rows (T0' = 0, and u0' = 0 in the cold start) are the compiled
    far-field conditions û' + |k| û = 0, T̂' + |k| T̂ = 0 at |k| = 0: their residual at a
    state is the top derivative."""
    from chuteflow.equations import TOP_OF, compiled_equations

    model = ChuteModel()
    newton = SteadyNewton(32, 16.0, 0.05, model, 1e-9)
    st = isothermal_guess(16.0, 0.05, model, 1e-9, newton.ref)
    st.T = st.T * (1 + 0.1 * newton.ref.y)
    D1 = newton.ref.D / st.L
    base = {
        "nu": st.nu,
        "nu_y": D1 @ st.nu,
        "nu_yy": D1 @ D1 @ st.nu,
        "u": st.u,
        "u_y": D1 @ st.u,
        "u_yy": D1 @ D1 @ st.u,
        "T": st.T,
        "T_y": D1 @ st.T,
        "T_yy": D1 @ D1 @ st.T,
    }
    part = model.evaluate(st.nu, st.T)
    th = math.radians(16.0)
    for f in ("u", "T"):
        res, _ = compiled_equations()[TOP_OF[f]].evaluate(base, part, math.sin(th), math.cos(th))
        assert np.allclose(np.broadcast_to(res, st.nu.shape), base[f + "_y"], rtol=1e-15, atol=0)
