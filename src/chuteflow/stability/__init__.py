"""Linear stability of steady chute flows (paper §4, Appendices A–B).

Perturbations (ν̂, û, v̂, T̂)(y) exp(αt + ikx) (eq. (4.4)) of a :class:`SteadyFlow` solve
the generalized eigenproblem A V = α B V, with A and B derived from the one statement of the
equations in :mod:`chuteflow.equations` and collocated on N + 1 Chebyshev nodes of
[0, y_max]. Re α > 0 is growth; Im α < 0 a wave running down the slope.

Operator
    ``op = StabilityOperator(flow, n, three_d=False)`` — built once per (flow, N).
    ``op.pencil(k, kz=0)`` → :class:`Pencil` (``.A``, ``.B``, ``.grid``, ``.fields``,
    ``.slices()``, ``.split(V)``). ``op.series()`` → (A0, A1, A2) with
    A(k) = A0 + (ik) A1 + (ik)² A2 for k ≥ 0 (the top conditions' |k| folded into A1);
    ``op.B`` is independent of k; ``op.pieces[(b, d)]`` are the coefficients of
    (ik_x)^b (ik_z)^d in 3D. Rows: see :mod:`.operator`. ``pencil(flow, k, n=None)`` is
    the one-call form. ``stability_operator(flow, n, cache=None)`` returns a cached
    operator (:class:`OperatorCache`: per flow object, never shared between two flows).
    ``equation_terms(flow, name, fields, kx, kz, alpha)`` → each term of one linearised
    equation applied to a mode (e.g. the mass balance of an eigenfunction).
    Unknowns are the physical (ν̂, û, v̂, T̂); the solvers work on an internally equilibrated
    copy (``pencil.equilibrated()``, unknown ν̂/ν0; ``pencil.unscale`` maps back).

Solvers
    ``qz(A, B)`` — dense QZ, all finite eigenvalues (reference, fallback).
    ``ShiftInvert(A, B, σ)`` — one LU of A − σB reused: ``.iterate(v0)`` (inverse
    iteration), ``.nearest(nev)`` (Arnoldi on x ↦ (A − σB)⁻¹Bx; not ``eigs(M=B)``).

Rejection policy
    :class:`RejectionPolicy` — ``drift_tol``, ``tail_tol``, ``tail_terms``,
    ``track_tail_tol``, and the resolution ladder ``n_start``, ``n_max``, ``n_growth``
    (``.ladder()``, ``.next_n(n)``, ``.accepts(drift, tail)``); every solver below takes it
    as ``policy=`` (default :data:`DEFAULT_POLICY`, the paper's values). The keywords
    ``drift_tol``, ``tail_tol``, ``n_max`` remain as overrides of its fields. Its fields
    ``tracking`` (:class:`TrackingPolicy`: the continuation of the branch and its
    fallbacks) and ``search`` (:class:`SearchPolicy`: the resolver's search above an
    answer) hold every tuning knob.

Modes (every one carries its convergence estimate)
    :class:`Mode` — ``alpha``, ``k``, ``kz``, ``theta``, ``nu0``, ``n``, ``y``, ``fields``
    (dict of nodal values, largest component 1), ``drift`` (|α(N) − α(N')|,
    N' = round(0.8N)), ``tail`` (paper's Chebyshev-tail statistic), ``physical`` (both
    < 1e-7), ``to_dict()``, ``to_xarray()``.
    ``least_stable(flow, k, kz=0, n=None, sigma=None, method="branch"|"qz")`` → Mode
    (:mod:`.resolver`): the mode of largest Re α among the modes that pass both tests under
    refinement, at any wavevector — the tracked (or direct) answer, then one dense solve at
    N = 48 whose candidates above it are followed up the ladder until decided; an undecided
    one is returned flagged. N adaptive (80, 100, 125, …, 256) unless given; finite
    wavevectors on the sinh-mapped grid (:func:`~.modes.cache_for`).
    ``spectrum(flow, k, n=80)`` → all physical modes
    by QZ. ``mode_near(flow, k, σ, n=…)`` → the mode nearest a shift.

Branch α(0) = 0 (the kinematic-wave mode of Appendix B)
    ``null_vectors(op)`` → :class:`NullVectors` (``alpha0``, ``right`` ∝ ∂X0/∂β,
    ``left``; lᴴ B r = 1). ``BranchTracker(flow, n)`` — continuation
    in k with ``.advance(k)`` and ``.mode(k)`` (:mod:`.tracking`; where it loses the branch,
    the fallbacks of :mod:`.lost`). ``dispersion(flow, ks)`` →
    :class:`xarray.Dataset` (alpha_re, alpha_im, drift, tail, n, physical over k; the
    flow's parameters as attributes).

Branch scan, k_c and the peak (:mod:`.scan`, paper §4.2, figures 7–9)
    ``branch_scan(flow, k_max=0.05)`` → :class:`BranchScan` (k, alpha, drift, tail, n,
    physical per point; ``.k_c``, ``.peak()``, ``.cutoff()``, ``.converged``,
    ``.to_xarray()``): k_c is the first sign change of Re α when it goes from + to − (the
    upper edge of the long-wave unstable band), None for a flow long-wave stable on the
    scan. ``critical_k(flow, k_max=0.05)`` → that k_c; ``crossings(...)`` → all sign
    changes of Re α (:class:`Crossings`, with the scan's convergence).

Three dimensions (:mod:`.transverse`)
    ``least_stable_3d(flow, kx, kz)`` → the physical mode of largest Re α at any wavevector
    by a dense scan (real QZ at k_x = 0) with the same drift/tail rejection;
    ``transverse_mode``, ``transverse_dispersion(flow, kz)`` (k_x = 0) and
    ``growth_plane(flow, kx, kz)`` → xarray Dataset of Re α over (k_x, k_z) with its maximum.
    α2z and the transverse analysis are in :mod:`chuteflow.longwave.spanwise`.

Numerical notes (see also docs/errata.md): bulk rows are divided by μ0 or κ0, never by ν0
(which would put 1e9 into the dilute top's rows and bury the dense layer's eigenvalues in
round-off); the near-neutral continuum of the dilute top (α ≈ −ik u0(y) − 1e-8) passes the
drift test but fails the tail test, and shift-invert estimates near it carry round-off of
~1e-12 absolute.
"""

from .dispersion_relation import dispersion
from .eigen import ShiftInvert, qz
from .modes import Mode, OperatorCache, mode_near, spectrum, stability_operator
from .operator import Pencil, StabilityOperator, equation_terms
from .policy import DEFAULT_POLICY, RejectionPolicy, SearchPolicy, TrackingPolicy
from .resolver import least_stable, pencil
from .scan import BranchScan, Crossings, Peak, branch_scan, critical_k, crossings
from .tracking import BranchTracker, NullVectors, branch_mode, null_vectors
from .transverse import (
    TransverseDispersion,
    growth_plane,
    least_stable_3d,
    transverse_dispersion,
    transverse_mode,
)
from .transverse_tracking import TransverseTracker, TransverseTrackingPolicy

# What users call: the operator, the solvers, the modes and results, the policies. Helpers
# of the solvers (resolution checks, direct solves, tails) are imported from their modules.
__all__ = [
    "StabilityOperator",
    "Pencil",
    "pencil",
    "equation_terms",
    "stability_operator",
    "OperatorCache",
    "qz",
    "ShiftInvert",
    "Mode",
    "least_stable",
    "spectrum",
    "mode_near",
    "dispersion",
    "BranchTracker",
    "branch_mode",
    "NullVectors",
    "null_vectors",
    "BranchScan",
    "Crossings",
    "Peak",
    "branch_scan",
    "critical_k",
    "crossings",
    "TransverseDispersion",
    "TransverseTracker",
    "growth_plane",
    "least_stable_3d",
    "transverse_dispersion",
    "transverse_mode",
    "RejectionPolicy",
    "DEFAULT_POLICY",
    "TrackingPolicy",
    "SearchPolicy",
    "TransverseTrackingPolicy",
]
