"""Stability metrics of a sweep (long-wave coefficients, k_c, maximum growth rate, finite-k check).

The stability layer is imported inside ``compute`` so that registering these classes never
depends on it.
"""
from __future__ import annotations

from .points import PointFunction, Variable, register_point_function  # noqa: F401

__all__ = ["default_metrics"]


def default_metrics() -> list[str]:
    """Point functions of a default sweep, in evaluation order."""
    return ["steady", "kinematic"]
