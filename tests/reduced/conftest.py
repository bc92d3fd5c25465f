"""Shared fixtures: a short steady family at θ = 16° (φ = 0.05), built once per session."""

from __future__ import annotations

import warnings

import pytest


@pytest.fixture(scope="session")
def rm16():
    """The 1D model at θ = 16° on ν0(0) ∈ [0.08, 0.2]: ρ̄ ∈ [0.35, 1.28], about 11 knots.

    Every state on it is long-wave unstable with (ρ̄T̄)' > 0 except near the low end.
    """
    from chuteflow.closures import ChuteModel
    from chuteflow.reduced import reduced_model

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return reduced_model(16.0, ChuteModel(), nu0_min=0.08, nu0_max=0.2)


@pytest.fixture(scope="session")
def state16(rm16):
    """Uniform state ρ0 = ρ̄0(ν0(0) = 0.12) at 16°: unstable, k_c ≈ 0.443 (L_c ≈ 14.2)."""
    return rm16.coefficients(rm16.rho_at_nu0(0.12))
