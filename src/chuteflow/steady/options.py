"""Solver settings of a steady point, family or map (:class:`Options`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

#: Newton settings from a continuation guess (a good guess needs 2–5 full steps): failing
#: fast matters because beyond the existence boundary every point fails.
_CONT_MAXITER = 10
_CONT_LAM_MIN = 1.0 / 16
#: Newton settings of an isolated solve (a cold start, :func:`~chuteflow.steady.solve_steady`):
#: iterations, and the smallest step length of the line search.
_ISOLATED_MAXITER = 60
_ISOLATED_LAM_MIN = 1e-6


@dataclass(frozen=True)
class Options:
    """Solver settings shared by every point of a family or map, and of one point's resolution
    ladder (:func:`~chuteflow.steady.ladder.solve_point`: ``nu_top``, ``n`` its first rung,
    ``rtol``, ``n_max``, ``min_thickness``, Newton's ``maxiter`` and ``lam_min``,
    ``noise_exit``; paper §3).

    ``noise_exit``: a point's resolution ladder stops (the point is not converged) once the
    change between resolutions is at the solver's round-off floor, which grows with n, instead
    of climbing to n_max (:func:`~chuteflow.steady.ladder.solve_point`); on the 40 × 40 quick
    stability diagrams of both φ this changes no status and no value.

    Continuation steps take Newton's chord steps from the LUs of the row's last solve
    (:func:`~chuteflow.steady.continuation_step._continue`) at the first rung of their ladder;
    ``beta_tangents`` (the default) keeps a fresh LU at the finer rungs, whose exact dX/dβ each
    flow then carries for :func:`~chuteflow.steady.tangent.steady_tangent` (the long-wave theory
    and the sweep's metrics of the same flows use it). A map, whose flows are only summarised,
    sets it False: every rung starts from the neighbour's LU (no factorisation where its chord
    steps converge), and steady_tangent would factorise.
    """

    nu_top: float = 1e-9
    n: int = 64
    rtol: float = 1e-8
    n_max: int = 384
    min_thickness: float = 1.0
    tangent: bool = True
    substeps: int = 1
    max_cold: int = 4
    max_cold_seeded: int = 1
    maxiter: int = _CONT_MAXITER
    lam_min: float = _CONT_LAM_MIN
    decide: bool = True
    noise_exit: bool = True
    beta_tangents: bool = True

    def isolated(self) -> Options:
        """These settings with Newton's for an isolated solve (a cold start, or
        :func:`~chuteflow.steady.solve_steady`'s roads): up to 60 iterations, step lengths
        down to 1e-6, instead of a continuation step's fail-fast 10 and 1/16."""
        return dataclasses.replace(self, maxiter=_ISOLATED_MAXITER, lam_min=_ISOLATED_LAM_MIN)
