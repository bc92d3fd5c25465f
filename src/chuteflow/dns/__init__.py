"""Nonlinear time-dependent simulation of the chute flow in (x, y) (docs/dns.md).

The time-dependent equations (2.1)–(2.3) with the Lun et al. closures and the
Johnson–Jackson floor (2.9), (2.10), on a slope periodic in x over a length L, from the floor
to the dilute top of the steady flow. Unknowns s = ln ν, u, v, T; Fourier (x, 3/2-rule
padding) × Chebyshev (y) collocation; BDF2 steps solved by Newton–Krylov preconditioned by
the per-Fourier-mode linearisation about the x-averaged state in the linear phase and by
the Jacobian of each x-column at the local state (:mod:`.columns`) at large amplitude. The residual and the
linearisation are derived from :mod:`chuteflow.equations` (:mod:`.residual`).

``simulate(theta, nu0, length, ...)`` → :class:`xarray.Dataset` (ρ̄(x, t), Q(x, t), field
snapshots, measured growth rate and phase velocity against the eigenvalue of
:func:`chuteflow.stability.least_stable`, mass drift, status); ``summary(ds)`` → the
JSON scalars of ``chuteflow dns --json``.
"""

from .api import INITS, DnsSetup, bdf2_eigenvalue, measure_mode, relax_steady, simulate, summary
from .columns import ColumnPreconditioner
from .discretisation import Discretisation
from .residual import compiled_residuals, evaluate_residuals
from .stepper import NewtonSettings, StepInfo, Stepper

__all__ = [
    "INITS",
    "ColumnPreconditioner",
    "DnsSetup",
    "Discretisation",
    "NewtonSettings",
    "StepInfo",
    "Stepper",
    "bdf2_eigenvalue",
    "compiled_residuals",
    "evaluate_residuals",
    "measure_mode",
    "relax_steady",
    "simulate",
    "summary",
]
