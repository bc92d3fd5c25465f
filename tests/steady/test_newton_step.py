"""The steady Newton step: the exact Jacobian and the step that eliminates u0'.

Sources: central finite differences of the residual (independent of the assembly); the
dense LU of the full Jacobian (numpy.linalg.solve) for the eliminated step; the identity
D1 M⁻¹ = [g; e_1 … e_n] for M = [e_0; D1 rows 1…n] (analytic: the rows of M are D1's).
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.steady import solve_steady
from chuteflow.steady.grid import reference_grid
from chuteflow.steady.linear import _u_basis, _u_basis_ref
from chuteflow.steady.newton import SteadyNewton
from chuteflow.steady.state import resample, state_of

_FLOWS = [(16.0, 0.08), (14.0, 0.3), (18.0, 0.03)]


@pytest.fixture(scope="module")
def flows():
    return {p: solve_steady(*p) for p in _FLOWS}


def _off_solution(flow, n):
    """The flow on n + 1 nodes, moved off the solution (Newton's iterates are)."""
    st = resample(state_of(flow), n)
    st.u = st.u * (1 + 1e-3 * np.sin(np.arange(n + 1)))
    st.T = st.T * (1 + 1e-3 * np.cos(np.arange(n + 1)))
    return st


@pytest.mark.parametrize("integrated", [True, False])
def test_jacobian_against_finite_differences(flows, integrated):
    """J's columns equal central differences of the residual (step 1e-6 relative; the
    differences' own error is ~1e-8 of the column), for every kind of unknown."""
    flow = flows[(16.0, 0.08)]
    n = 48
    st = _off_solution(flow, n)
    newton = SteadyNewton(n, 16.0, 0.08, flow.model, 1e-9, integrated=integrated, grid_map=st.grid_map)
    _, J = newton.evaluate(st)
    X = st.pack()
    m = n + 1
    for col in (0, 5, m - 1, m, m + 7, 2 * m - 1, 2 * m, 2 * m + 20, 3 * m - 1, 3 * m):
        h = 1e-6 * max(abs(X[col]), 1e-3)
        Xp, Xm = X.copy(), X.copy()
        Xp[col] += h
        Xm[col] -= h
        up = type(st).unpack(n, Xp, st.grid_map)
        um = type(st).unpack(n, Xm, st.grid_map)
        fd = (newton.evaluate(up, jac=False)[0] - newton.evaluate(um, jac=False)[0]) / (2 * h)
        scale = max(np.abs(J[:, col]).max(), 1e-12)
        assert np.abs(fd - J[:, col]).max() / scale < 1e-6, col


@pytest.mark.parametrize("n", [64, 96, 144])
def test_eliminated_step_equals_dense_solve(flows, n):
    """SteadyNewton.step (u0' eliminated, a system of 2(n+1)+1 unknowns) gives J⁻¹ B of the
    dense LU to round-off (measured ≤ 2e-9 relative; the system's condition number is
    ~1e7 at n = 144), for the Newton step and the family tangent's right-hand side."""
    for (theta, nu0), flow in flows.items():
        st = _off_solution(flow, n)
        newton = SteadyNewton(n, theta, nu0, flow.model, 1e-9, grid_map=st.grid_map)
        assert newton.eliminate
        R, J = newton.evaluate(st)
        B = np.zeros((len(R), 2))
        B[:, 0], B[0, 1] = R, 1.0 / nu0
        ref = np.linalg.solve(J, B)
        got = newton.step(st, B)
        err = np.abs(got - ref).max(axis=0) / np.abs(ref).max(axis=0)
        assert err.max() < 1e-7, (theta, nu0, err)


def test_second_order_form_is_not_eliminated():
    """The cold start's second-order x-momentum has u0'' in it: the dense LU is used."""
    newton = SteadyNewton(32, 16.0, 0.08, ChuteModel(), 1e-9, integrated=False)
    assert not newton.eliminate


@pytest.mark.parametrize("grid_map", [None, (0.3, 0.1)])
@pytest.mark.parametrize("n", [32, 97])
def test_u_basis_identity(n, grid_map):
    """M⁻¹ maps (u(0), u' at nodes 1…n) to u, and D1 M⁻¹ has the unit rows 1…n that the
    eliminated step assumes: checked on a polynomial of degree n and on D1 @ M⁻¹."""
    L = 3.7
    q, g0 = _u_basis(n, grid_map, L)
    Minv = _u_basis_ref(n)[0] * q
    D1Minv = np.eye(n + 1)
    D1Minv[0] = g0  # the rows of D1 M⁻¹ that SteadyNewton.step assumes
    D1 = reference_grid(n, grid_map).D / L
    np.testing.assert_allclose(D1 @ Minv, D1Minv, atol=1e-9 * np.abs(D1 @ Minv).max())
    y = reference_grid(n, grid_map).y * L
    u = np.cos(y / L) + (y / L) ** 3
    back = Minv @ np.concatenate([[u[0]], (D1 @ u)[1:]])
    np.testing.assert_allclose(back, u, rtol=0, atol=1e-10)


def _reachable_arrays(fn):
    """The numpy arrays a function reaches through its closure (and the closures of the
    functions and partials found there)."""
    out, todo, seen = [], [fn], set()
    while todo:
        f = todo.pop()
        if id(f) in seen:
            continue
        seen.add(id(f))
        cells = getattr(f, "__closure__", None) or ()
        for c in cells:
            v = c.cell_contents
            items = v if isinstance(v, (list, tuple)) else [v]
            for x in items:
                if isinstance(x, np.ndarray):
                    out.append(x)
                elif callable(x):
                    todo.append(x)
                elif isinstance(x, tuple):
                    todo.extend(y for y in x if callable(y))
    return out


def test_kept_lu_does_not_keep_the_jacobian(flows):
    """A kept factorisation (``factored_step``'s solve: a row's LU slot, a neighbour's
    chord steps) holds the LU of the eliminated system and what its back-substitution
    needs, not the full Jacobian (3(n+1)+1 squared: 4.7 MB at n = 256; the 60 × 60
    diagram's rows kept eight of them at once). Its solve still equals the step's."""
    flow, n = flows[(16.0, 0.08)], 96
    st = _off_solution(flow, n)
    newton = SteadyNewton(n, 16.0, 0.08, flow.model, 1e-9, grid_map=st.grid_map)
    R, J = newton.evaluate(st)
    B = R[:, None].copy()
    sol, again = newton.factored_step(st, B)
    big = [a for a in _reachable_arrays(again) if a.size >= J.size]
    assert big == []
    assert np.allclose(again(B), sol, rtol=0, atol=1e-12 * np.abs(sol).max())
