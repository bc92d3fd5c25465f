"""One sign convention for phase velocities (docs/conventions.md): c = −Im α / k, > 0 down
the slope, applied by chuteflow.conventions for every result that reports a phase velocity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.conventions import (
    PHASE_VELOCITY_CONVENTION,
    RATE_UNITS,
    long_wave_phase_velocity,
    phase_velocity,
)
from chuteflow.longwave import longwave
from chuteflow.stability import least_stable


def test_phase_velocity_helper():
    assert phase_velocity(0.1 - 2.0j, 0.5) == 4.0
    assert math.isnan(phase_velocity(1j, 0.0))
    c = phase_velocity(np.array([1 - 1j, 2j, 3j]), np.array([1.0, 0.0, 2.0]))
    assert c[0] == 1.0
    assert math.isnan(c[1])
    assert c[2] == -1.5
    assert long_wave_phase_velocity(-4.15j) == pytest.approx(4.15)
    assert "down the slope" in PHASE_VELOCITY_CONVENTION
    assert RATE_UNITS == "sqrt(g/sigma)"


@pytest.fixture(scope="module")
def p1(p1_flow):
    return p1_flow


def test_mode_and_longwave_agree_on_the_sign(p1):
    """At P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05) the wave runs down the slope: c ≈ dQ0/dρ̄0 =
    4.1524 (reference value of tests/stability/test_dispersion.py) for the mode at small k
    and for the long-wave limit."""
    lw = longwave(p1)
    assert lw.phase_velocity == pytest.approx(lw.dQ_drho, rel=1e-6)
    assert lw.phase_velocity == pytest.approx(4.1524, abs=1e-3)
    # at k = 1e-7 the O(k) correction Im α2 k ≈ −1.7e-4 is 4e-5 relative (test_dispersion.py)
    m = least_stable(p1, 1e-7)
    assert m.wave_speed > 0
    assert m.wave_speed == pytest.approx(lw.phase_velocity, rel=1e-4)
