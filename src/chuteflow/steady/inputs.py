"""Checks of a steady problem's inputs (paper §3: θ, ν0(0), the top density ν_top)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError


def validate_point(theta, nu0, model, nu_top):
    """(θ, ν0(0)) as floats after checking θ ∈ (0, 90)°, ν0(0) ∈ (0, ν_m), ``nu_top`` ∈ (0, 1e-3 ν0(0)).

    Raises :class:`~chuteflow.errors.ParameterError` naming the parameter and its range.
    """
    try:
        theta = float(theta)
        nu0 = float(nu0)
    except (TypeError, ValueError):
        raise ParameterError("theta and nu0 must be numbers") from None
    if not (0.0 < theta < 90.0) or not math.isfinite(theta):
        raise ParameterError(
            f"theta = {theta!r} is outside (0, 90) degrees: the slope "
            "angle must be positive for a flow down the incline"
        )
    if not (0.0 < nu0 < model.nu_max):
        raise ParameterError(
            f"nu0 = {nu0!r} is outside (0, nu_max = {model.nu_max:g}): the "
            "floor packing fraction must be positive and below maximum packing"
        )
    if not (0.0 < nu_top < 1e-3 * nu0):
        raise ParameterError(
            f"nu_top = {nu_top!r} must lie in (0, 1e-3·nu0): it is the "
            "density at which the domain ends (paper: 1e-9)"
        )
    return theta, nu0


def check_nu0(nu0_values, model) -> np.ndarray:
    """Validated floor densities: a non-empty, strictly increasing 1-D array in (0, ν_m)."""
    nus = np.atleast_1d(np.asarray(nu0_values, dtype=float))
    if nus.ndim != 1 or len(nus) == 0:
        raise ParameterError("nu0_values: expected a non-empty 1-D sequence of floor densities")
    if len(nus) > 1 and not (np.all(np.diff(nus) > 0)):
        raise ParameterError("nu0_values must be strictly increasing (continuation walks along them)")
    for v in nus:
        validate_point(20.0, v, model, min(1e-9, 1e-4 * nus.min()))
    return nus
