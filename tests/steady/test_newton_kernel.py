"""The compiled rows of the steady Newton system (chuteflow.steady._newton_kernel).

Source: the numpy road of the same solver (SteadyNewton._residual and _jacobian: the compiled
equations evaluated term by term, the row scaling and the chain rule of ν = e^s applied in
Python), an independent assembly of the same quantities. The two differ only in the order of
floating-point operations: agreement to ~1e-13 relative (measured 1e-14 for R, 1e-16 of the
largest entry for J) shows that the kernel states the same rows. The Jacobian itself is
checked against finite differences in tests/steady/test_newton_step.py (through the compiled
road wherever a C compiler exists, as here).
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow import _ccode
from chuteflow.closures import ChuteModel
from chuteflow.steady import solve_steady
from chuteflow.steady.grid import reference_grid
from chuteflow.steady.linear import _u_basis
from chuteflow.steady.newton import SteadyNewton
from chuteflow.steady.state import _node_interpolation, resample, state_of

pytestmark = pytest.mark.skipif(_ccode.compiler() is None, reason="no C compiler: only the numpy road")

_POINTS = [(16.0, 0.08), (14.0, 0.3), (18.0, 0.03)]


@pytest.fixture(scope="module")
def flows():
    return {p: solve_steady(*p) for p in _POINTS}


@pytest.mark.parametrize("point", _POINTS)
@pytest.mark.parametrize("integrated", [True, False])
@pytest.mark.parametrize("n", [48, 96])
def test_compiled_rows_equal_the_numpy_road(flows, point, integrated, n):
    flow = flows[point]
    st = resample(state_of(flow), n)
    st.u = st.u * (1 + 1e-3 * np.sin(np.arange(n + 1)))  # off the solution, as Newton's iterates
    st.T = st.T * (1 + 1e-3 * np.cos(np.arange(n + 1)))
    theta, nu0 = point
    newton = SteadyNewton(n, theta, nu0, ChuteModel(), 1e-9, integrated=integrated, grid_map=st.grid_map)
    assert newton._fast is not None
    fast, slow = newton._residual_compiled(st), newton._residual(st)
    R1, R0 = fast["R"], slow["R"]
    assert np.max(np.abs(R1 - R0)) <= 1e-12 * np.max(np.abs(R0))
    gs = [None] + ([_u_basis(n, st.grid_map, st.L)[1]] if integrated else [])
    for g in gs:
        J1, J0 = newton._jacobian_compiled(fast, g), newton._jacobian(slow, g)
        scale = np.max(np.abs(J0), axis=1, keepdims=True)  # row by row (rows are scaled)
        assert np.max(np.abs(J1 - J0) / scale) <= 1e-12


def test_solve_without_compiled_kernels_agrees(monkeypatch):
    """CHUTEFLOW_CCODE=off: the numpy road alone gives the same flow within its own
    convergence estimate."""
    flow = solve_steady(16.0, 0.05)
    monkeypatch.setattr("chuteflow.steady.system._road_parts", lambda *a: None)
    plain = solve_steady(16.0, 0.06)  # another point: the flow cache cannot answer
    back = solve_steady(16.0, 0.05, guess=plain)
    for k in ("h", "Q", "rho_bar", "u_floor", "T_floor"):
        a, b = getattr(flow, k), getattr(back, k)
        assert abs(a - b) <= 10 * max(flow.convergence, back.convergence, 1e-10) * abs(a), k


def test_node_interpolation_is_the_interpolant():
    """The cached matrix between two node sets of the same map equals the grid's own
    interpolation at the new nodes (barycentric there too): to round-off."""
    flow = solve_steady(16.0, 0.05)
    st = state_of(flow)
    for n in (64, 144):
        M = _node_interpolation(st.n, n)
        y = reference_grid(n, st.grid_map).y
        for f in (st.s, st.u, st.T):
            ref = st.ref.interpolate(f, y)
            assert np.max(np.abs(f @ M - ref)) <= 1e-12 * max(1.0, np.max(np.abs(f)))
