"""Steady flows uniform along the slope (paper §3): solver, result object, families and maps."""
from .result import SteadyFlow
from .api import solve_steady, steady_tangent

__all__ = ["SteadyFlow", "solve_steady", "steady_tangent"]
