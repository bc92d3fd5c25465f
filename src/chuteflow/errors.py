"""Exceptions with messages a user can act on."""


class ChuteflowError(Exception):
    """Base class of chuteflow's errors."""


class ParameterError(ChuteflowError, ValueError):
    """A parameter is outside its allowed range; the message names it, the range and why."""


class NoSteadyFlowError(ChuteflowError):
    """No steady flow exists (or none was found) for these parameters; the message says why."""


class ConvergenceError(ChuteflowError):
    """A solver did not converge; the message says which and how far it got."""
