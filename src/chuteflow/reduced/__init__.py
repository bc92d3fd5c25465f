"""The reduced one-dimensional model (§5.1.2) and nonlinear density waves (§5.2).

- :func:`reduced_model` / :class:`ReducedModel`: F(ρ̄), T̄(ρ̄), a(ρ̄), U(ρ̄), μ̄(ρ̄) over a steady
  family at fixed θ (eqs (5.10), (5.11)), with measured interpolation error.
- :class:`LocalCoefficients` / :func:`local_coefficients`: the linear theory at one uniform
  state: 2×2 dispersion relation, condition (errata-corrected), eqs (5.13), (5.14), k_c.
- :func:`reduced_diagram`, :func:`agreement`: 1D stability diagrams (figure 15) and their
  agreement with the full model's.
- :mod:`.equations`: the depth-averaged equations stated once; the uniform state, the
  linearisation, the finite-volume fluxes and their partials are derived from there.
- :class:`WaveSimulation` (time stepper with trackers: :class:`SnapshotTracker`,
  :class:`SaturationStop`, :class:`ProgressTracker`, :class:`LeaveFamilyStop`),
  :class:`WaveSolver` (the discrete system) and the wrapper :func:`simulate`: nonlinear
  waves on a periodic slope.
"""

from .diagram import Reduced1D, agreement, reduced_diagram, reduced_diagram_config
from .model import LocalCoefficients, ReducedModel, local_coefficients, reduced_model
from .wave_solver import (
    InitialState,
    LeaveFamilyStop,
    ProgressTracker,
    RunInfo,
    SaturationStop,
    SnapshotTracker,
    Step,
    Tracker,
    WaveSimulation,
    WaveSolver,
    default_cells,
    growth_rate_fit,
    simulate,
)

__all__ = [
    "LocalCoefficients",
    "ReducedModel",
    "local_coefficients",
    "reduced_model",
    "WaveSolver",
    "WaveSimulation",
    "InitialState",
    "RunInfo",
    "Step",
    "Tracker",
    "SnapshotTracker",
    "SaturationStop",
    "ProgressTracker",
    "LeaveFamilyStop",
    "default_cells",
    "growth_rate_fit",
    "simulate",
    "Reduced1D",
    "agreement",
    "reduced_diagram",
    "reduced_diagram_config",
]
