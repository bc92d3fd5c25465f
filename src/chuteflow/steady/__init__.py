"""Steady flows uniform along the slope (paper §3): solver, result object, families and maps."""

from .api import solve_steady, steady_tangent
from .existence import ExistenceVerdict, steady_existence
from .family import flux_minimum, steady_family, steady_row
from .maps import steady_map
from .result import SteadyFlow

__all__ = [
    "SteadyFlow",
    "solve_steady",
    "steady_tangent",
    "steady_family",
    "steady_row",
    "steady_map",
    "flux_minimum",
    "steady_existence",
    "ExistenceVerdict",
]
