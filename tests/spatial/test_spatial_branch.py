"""Spatial branch k(ω) at the paper's P1 (θ = 16°, ν0(0) = 0.05): checked against Gaster's
relation (independent: the temporal branch's Re α / c_g at real k) and the identity α(k) = −iω."""

import math

import pytest

from chuteflow.closures import ChuteModel
from chuteflow.errors import ParameterError
from chuteflow.spatial import spatial_point
from chuteflow.steady import solve_steady


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))


def test_spatial_point_matches_gaster(p1):
    pt = spatial_point(p1, 0.02)
    assert pt.converged, pt.note
    assert pt.alpha_residual < 1e-12
    # growth ~1.5e-4 at c_g ~ 8: Gaster's relation holds to O(Re α · α''/α'²) ~ 1e-2 relative
    # (measured 1.4e-3 at ω = 0.02 and 0.8e-2 at ω = 0.005)
    assert pt.spatial_growth > 0
    assert math.isclose(pt.spatial_growth, pt.gaster_growth, rel_tol=1e-2)
    assert abs(pt.k.real - pt.k_real) < 1e-2 * pt.k_real
    assert pt.drift < 1e-7
    assert pt.tail < 1e-7


@pytest.mark.parametrize("omega", [0.0, -1.0, float("nan")])
def test_bad_omega(p1, omega):
    with pytest.raises(ParameterError, match="omega"):
        spatial_point(p1, omega)
