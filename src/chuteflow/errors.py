"""Exceptions with messages a user can act on."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # annotations only: errors import nothing of the package at run time
    from .steady.result import SteadyFlow


class ChuteflowError(Exception):
    """Base class of chuteflow's errors."""


class ParameterError(ChuteflowError, ValueError):
    """A parameter is outside its allowed range; the message names it, the range and why."""


class NoSteadyFlowError(ChuteflowError):
    """No steady flow exists (or none was found) for these parameters; the message says why."""


class ConvergenceError(ChuteflowError):
    """A solver did not converge; the message says which and how far it got."""


class ResolutionError(ConvergenceError):
    """Newton converged at every resolution up to ``n_max``, but the steady flow's scalars
    still changed by more than ``rtol`` between the last two (paper §3; the resolution
    ladder of :func:`chuteflow.steady.ladder.solve_point`); ``.h`` is the thickness at the
    finest and ``.flow`` the flow there (``converged`` False, ``convergence`` the last
    change)."""

    def __init__(self, message: str, h: float = float("nan"), flow: SteadyFlow | None = None):
        super().__init__(message)
        self.h = h
        self.flow = flow


class ThinLayerError(NoSteadyFlowError):
    """A converged steady solution thinner than ``min_thickness`` (paper §3.2: below one
    particle diameter the hydrodynamics does not apply); ``.flow`` keeps it (e.g. as a
    continuation guess)."""

    def __init__(self, message: str, flow: SteadyFlow):
        super().__init__(message)
        self.flow = flow
