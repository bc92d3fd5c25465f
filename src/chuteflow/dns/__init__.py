"""Nonlinear time-dependent simulation of the chute flow in (x, y) (docs/dns.md).

The time-dependent equations (2.1)–(2.3) with the Lun et al. closures and the
Johnson–Jackson floor (2.9), (2.10), on a slope periodic in x over a length L, from the floor
to the dilute top of the steady flow. Unknowns s = ln ν, u, v, T; Fourier (x, 3/2-rule
padding) × Chebyshev (y) collocation; BDF2 steps solved by Newton–Krylov preconditioned by
the per-Fourier-mode linearisation about the x-averaged state in the linear phase and by
the Jacobian of each x-column at the local state (:mod:`.columns`) at large amplitude, or, as an
option, by the local Jacobian with neighbouring Fourier modes coupled (:mod:`.coupled`). The
residual and the linearisation are derived from :mod:`chuteflow.equations` (:mod:`.residual`).

``DnsSimulation(flow, length, ...).run(trackers)`` → a :class:`DnsState` (saves and loads
itself; trackers from :mod:`chuteflow.trackers`, shared with the 1D model);
``simulate(flow, length, ...)`` → :class:`xarray.Dataset` (ρ̄(x, t), Q(x, t), field snapshots,
measured growth rate and phase velocity against the eigenvalue of
:func:`chuteflow.stability.least_stable`, the wave at the end and its verdict, resolution
tails, mass drift, status); ``summary(ds)`` → the JSON scalars of ``chuteflow dns --json``.
"""

from .api import simulate, summary
from .columns import ColumnPreconditioner
from .coupled import CoupledPreconditioner
from .diagnostics import VERDICTS, WavePolicy, bdf2_eigenvalue, measure_mode, resolution_tails, wave_measures
from .discretisation import Discretisation
from .residual import compiled_residuals, evaluate_residuals
from .setup import INITS, DnsSetup, relax_steady
from .simulation import DnsSimulation, DnsState, DnsStep
from .stepper import NewtonSettings, StepInfo, Stepper
from .waves import WaveMapSettings, map_waves

__all__ = [
    "INITS",
    "ColumnPreconditioner",
    "CoupledPreconditioner",
    "DnsSetup",
    "DnsSimulation",
    "WaveMapSettings",
    "map_waves",
    "DnsState",
    "DnsStep",
    "VERDICTS",
    "WavePolicy",
    "resolution_tails",
    "wave_measures",
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
