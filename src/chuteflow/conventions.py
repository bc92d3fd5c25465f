"""Sign conventions and unit strings shared by every module (stated once, docs/conventions.md).

Normal modes are perturbations ∝ exp(αt + ikx) with x down the slope and k ≥ 0 (the paper's
eq. (4.4)): Re α is the growth rate and the phase velocity is

    c = −Im α / k,     positive: the wave travels down the slope.

As k → 0, c → dQ0/dρ̄0 (appendix B, eq. (B 2): α1 = −i dQ0/dρ̄0), the kinematic-wave speed.
Every phase velocity or wave speed chuteflow reports is computed by :func:`phase_velocity`
or :func:`long_wave_phase_velocity`. Units are those of the paper's scaling (lengths in σ,
times in √(σ/g)); the strings below are the ``units`` attributes of xarray variables.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "PHASE_VELOCITY_CONVENTION",
    "VELOCITY_UNITS",
    "RATE_UNITS",
    "WAVENUMBER_UNITS",
    "LENGTH_UNITS",
    "phase_velocity",
    "long_wave_phase_velocity",
]

#: One line for attrs and help texts.
PHASE_VELOCITY_CONVENTION = (
    "perturbations ~ exp(alpha t + i k x), x down the slope; phase "
    "velocity c = -Im(alpha)/k, positive down the slope"
)
#: Velocities (u0, phase velocities, dQ0/dρ̄0): √(gσ).
VELOCITY_UNITS = "sqrt(g sigma)"
#: Rates (Re α, Im α, drag coefficient a): √(g/σ).
RATE_UNITS = "sqrt(g/sigma)"
#: Wavenumbers k: 1/σ.
WAVENUMBER_UNITS = "1/sigma"
#: Lengths (y, h, wavelengths): σ.
LENGTH_UNITS = "sigma"


def phase_velocity(alpha, k):
    """Phase velocity c = −Im α / k of a mode ∝ exp(αt + ikx) (> 0: down the slope).

    Scalars give a float (NaN at k = 0); arrays give an array (NaN where k = 0).
    """
    a = np.asarray(alpha)
    kk = np.asarray(k, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(kk != 0, -np.imag(a) / np.where(kk != 0, kk, 1.0), np.nan)
    return float(c) if c.ndim == 0 else c


def long_wave_phase_velocity(alpha1) -> float:
    """The k → 0 limit of :func:`phase_velocity`, −Im α1, for α = α1 k + O(k²)."""
    return float(-np.imag(alpha1))
