"""The steady solver's sinh-mapped grid (nodes clustered at the layer's edge).

Reference values: the same flows on the plain Chebyshev grid of before (the paper's
discretisation), which needs n = 486 near the upper existence boundary where the mapped
grid needs 144–216. Both are converged to the ladder's rtol = 1e-8, so they must agree to
that (measured: 6e-10 relative for h at θ = 16.6154°, ν0(0) = 0.1823).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.spectral import LAYER_MAP_WIDTH as MAP_WIDTH
from chuteflow.steady import solve_steady, steady_family
from chuteflow.steady.grid import layer_grid_map
from chuteflow.steady.one_grid import solve_state
from chuteflow.steady.state import quantities, state_of

KEYS = ("u_floor", "T_floor", "h", "nu_mean", "rho_bar", "Q", "y_max")


@pytest.fixture(scope="module")
def p1():
    """θ = 16°, ν0(0) = 0.05, φ = 0.05 (P1)."""
    return solve_steady(16.0, 0.05)


def test_flow_carries_its_grid(p1):
    """The flow's grid is the mapped one its profiles live on: nodes, spectral
    interpolation at the nodes and the floor/top values agree."""
    assert p1.grid_map is not None
    g = p1.grid
    assert np.allclose(g.y, p1.y, rtol=0, atol=1e-12 * p1.y_max)
    pr = p1.profiles(p1.y)
    assert np.allclose(np.log(pr["nu"]), p1.log_nu, rtol=0, atol=1e-10)
    assert p1.profiles([0.0])["T"][0] == pytest.approx(p1.T_floor, rel=1e-12)
    assert p1.profiles([p1.y_max])["nu"][0] == pytest.approx(p1.nu_top, rel=1e-9)


def test_map_sits_at_the_edge(p1):
    """ξ_c is the thickness h/y_max (to the sampling 1/(8n) of the search), ξ_w =
    MAP_WIDTH·T0(h)/(cos θ y_max)."""
    xc, xw = layer_grid_map(state_of(p1), p1.theta)
    assert xc == pytest.approx(p1.h / p1.y_max, abs=1.0 / (8 * p1.n))
    T_h = p1.profiles([xc * p1.y_max])["T"][0]
    assert xw == pytest.approx(MAP_WIDTH * T_h / math.cos(math.radians(p1.theta)) / p1.y_max, rel=1e-12)


def test_mapped_and_plain_grids_agree(p1):
    """The same flow on the plain Chebyshev grid (n = 216, converged: change < 1e-10 to 324)
    and on the mapped one agree to 1e-9 relative (measured ≲ 1e-10)."""
    m = p1.model
    st, _, _ = solve_state(16.0, 0.05, m, p1.nu_top, 216, guess=state_of(p1), grid_map=None, min_iter=1)
    assert st.grid_map is None
    q = quantities(16.0, st, m)[1]
    for k in KEYS:
        assert q[k] == pytest.approx(getattr(p1, k), rel=1e-9), k


@pytest.mark.slow
def test_upper_boundary_resolved_with_few_nodes():
    """Near the upper existence boundary (θ = 16.6154°, φ = 0.05: a dense band under a
    cold top, T0(h) ≈ 0.08) the plain grid needed n = 486 and left ν0(0) ≥ 0.1885 not
    converged (Newton's round-off floor ∝ n⁴ at the rtol); the mapped grid converges every
    point with n ≤ 216, and h agrees with the plain grid's converged value at ν0(0) = 0.1823
    (6.785653688586598, n = 486, change 5.9e-9) to 1e-8."""
    nus = np.linspace(0.01, 0.25, 40)[26:32]
    ds = steady_family(16.615384615385, nus, ChuteModel(roughness=0.05), tangent=False)
    assert (ds.status.values == "ok").all(), ds.error.values
    assert ds.n.values.max() <= 216
    assert float(ds.h.values[2]) == pytest.approx(6.785653688586598, rel=1e-8)
