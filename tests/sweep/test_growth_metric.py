"""The growth metric keeps a flagged estimate where the paper's 1e-7 is missed (issue 9)."""

from __future__ import annotations

import pytest

from chuteflow.steady import solve_steady
from chuteflow.sweep.metrics import GrowthMetric
from chuteflow.sweep.points import Point


def test_unconverged_k_keeps_values_with_flag_and_drift():
    """θ = 14.3077°, ν0(0) = 0.102308 (a point of the quick φ = 0.05 diagram): at k = 0.0063
    the branch misses the drift test at N = 160 (measured drift 3.5e-7, tail 9.1e-10).
    Version 2 left growth_max missing; now the estimate is kept, flagged, with its drift."""
    theta, nu0 = 14.307692307692, 0.102307692308
    flow = solve_steady(theta, nu0)
    point = Point(-1, -1, theta, nu0)
    out = GrowthMetric().compute(flow, point)
    assert out["dispersion_sampled"] and out["growth_converged"] is False
    assert 1e-7 < out["growth_drift"] < 1e-6  # the convergence estimate (measured 3.5e-7)
    # stable at every sampled k (the long-wave verdict there: stable)
    assert out["growth_max"] < 0 and out["k_growth_max"] == pytest.approx(1e-4)
    assert "k_c" not in out
    assert any("not converged to the paper's thresholds" in n for n in point.notes)
