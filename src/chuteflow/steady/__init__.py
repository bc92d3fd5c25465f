"""Steady flows uniform along the slope (paper §3): solver, result object, families and maps.

One concept per module (docs/numerics.md, "Where the steady solver lives"): the inputs
(:mod:`.inputs`), the grid (:mod:`.grid`), the Newton unknowns (:mod:`.state`), the rows of the
system (:mod:`.layout`), its residual and Jacobian (:mod:`.system`), the linear solves
(:mod:`.linear`), Newton (:mod:`.newton`), the cold start (:mod:`.cold_start`), a solve at one
resolution (:mod:`.one_grid`), the resolution ladder (:mod:`.ladder`), the tangents
(:mod:`.tangent`), branch following (:mod:`.follow`), the user-facing fallback chain
(:mod:`.solve`), the shooting scan (:mod:`.shooting`), and for families and maps the settings
(:mod:`.options`), the continuation step (:mod:`.continuation_step`), the scan's verdicts in a
row (:mod:`.proofs`), the row scheduler (:mod:`.rows`), the Dataset schema (:mod:`.schema`),
families (:mod:`.family`), maps (:mod:`.maps`), the flux minimum (:mod:`.flux`) and
the separatrix of the θ contours (:mod:`.contours`).
"""

from .contours import Separatrix, separatrix
from .family import steady_family, steady_row
from .flux import FluxMinimum, flux_minimum
from .maps import steady_map
from .options import Options
from .result import SteadyFlow
from .shooting import ExistenceVerdict, steady_existence
from .solve import solve_steady
from .tangent import steady_tangent

__all__ = [
    "SteadyFlow",
    "solve_steady",
    "steady_tangent",
    "steady_family",
    "steady_row",
    "steady_map",
    "flux_minimum",
    "FluxMinimum",
    "separatrix",
    "Separatrix",
    "steady_existence",
    "ExistenceVerdict",
    "Options",
]
