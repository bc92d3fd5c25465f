"""Continuation in one scalar parameter, with one set of retry rules for every user.

The package follows solutions along a parameter in several places: steady flows along the
floor density ν0(0) or the inclination θ (paper §3.2; :mod:`chuteflow.steady.family`,
:func:`chuteflow.steady.follow.follow`), the least-stable eigenvalue along the wavenumber k
(§4.2; :class:`chuteflow.stability.BranchTracker`) and the steady flows of the 1D model's
diagrams (:mod:`chuteflow.reduced.diagram`). Each supplies only ``solve(state, s)``, the
solution at parameter ``s`` from the last accepted ``state`` (predictor and corrector are
the caller's: a tangent predictor for the steady flows, a quadratic extrapolation for α(k));
:func:`continue_to` decides which parameters are tried, by the rules of a :class:`StepRules`:

* ``retry="halve"`` (adaptive natural-parameter continuation): from the last accepted
  point, steps of ``h``; after a success the step is multiplied by ``grow`` (a number, or a
  function of the success's *quality*, e.g. how well the predictor hit), at most
  ``max_step``, and at most ``max_step_ratio`` times the distance from ``origin``; after a
  failure it is multiplied by ``shrink``. The continuation stops, unreached, when the step
  falls below ``min_step``, after more than ``max_halvings`` consecutive failures of one
  step, after ``max_attempts`` attempts in all, or at a failure the solver marks
  :attr:`Trial.final` (no shorter step can pass it).
* ``retry="subdivide"``: the whole interval in one step; if it fails, again from the start
  in 2, then 4, … equal steps (at most ``2**max_depth``), each attempt of a depth stopping at
  its first failure.

A step never passes the target: it lands exactly on it when the step reaches it. Every
attempt is recorded as a :class:`Step` in the :class:`Continuation` returned;
:func:`march` walks a list of grid points, each from the last, until the first failure.

Which neighbour seeds which point of a (θ, ν0(0)) row — the point below or above in ν0, the
neighbouring θ row, spread-out cold starts — is decided by one row scheduler,
:func:`chuteflow.steady.rows.continue_row`, shared by steady families, maps
(:mod:`chuteflow.steady.maps`) and sweep rows (:mod:`chuteflow.sweep.runner`); each single
continuation it starts goes through :func:`continue_to`.

This module is the bottom of the layer order (it imports nothing from chuteflow).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Continuation", "Step", "StepRules", "Trial", "continue_to", "march"]

RETRIES = ("halve", "subdivide")


@dataclass(frozen=True)
class StepRules:
    """Retry rules of a continuation (see the module docstring).

    Parameters
    ----------
    retry : {"halve", "subdivide"}
        Adaptive steps from the last accepted point, or equal subdivisions of the whole
        interval restarted from its start.
    grow : float or callable
        Factor applied to the step after a success (``"halve"``); a callable receives the
        success's :attr:`Trial.quality` and returns the factor.
    shrink : float
        Factor applied to the step after a failure (``"halve"``).
    max_step : float
        Largest step reached by growth (a larger starting step is kept for its first try).
    max_step_ratio : float
        A step is at most this multiple of the distance of the last accepted point from
        ``origin`` (not applied at the origin itself); ``inf``: no such limit.
    min_step : float
        The continuation stops when a failure shrinks the step below this.
    max_halvings : int or None
        The continuation stops after more than this many consecutive failures of one step.
    max_attempts : int or None
        The continuation stops after this many attempts in all.
    clip : bool
        Cut a step to the remaining distance before it is tried, so that a failure shrinks
        the step actually tried (True), or keep the nominal step, so that a failed step
        onto the target is retried there with the shrunk nominal step until that falls
        short of it (False).
    max_depth : int
        ``"subdivide"``: the finest subdivision is into ``2**max_depth`` steps.
    scale : float
        Units of the step sizes ``max_step`` and ``min_step`` per unit of the parameter
        (e.g. degrees per unit of a path parameter s ∈ [0, 1]).
    """

    retry: str = "halve"
    grow: float | Callable[[float | None], float] = 1.5
    shrink: float = 0.5
    max_step: float = math.inf
    max_step_ratio: float = math.inf
    min_step: float = 0.0
    max_halvings: int | None = None
    max_attempts: int | None = None
    clip: bool = True
    max_depth: int = 0
    scale: float = 1.0

    def __post_init__(self):
        if self.retry not in RETRIES:
            raise ValueError(f"retry = {self.retry!r}: choose one of {RETRIES}")
        if not 0 < self.shrink < 1:
            raise ValueError(f"shrink = {self.shrink!r}: a failed step must shrink (0 < shrink < 1)")
        if self.max_depth < 0:
            raise ValueError(f"max_depth = {self.max_depth!r} must be >= 0")

    def growth(self, quality: float | None) -> float:
        """Factor applied to the step after a success of the given quality."""
        return float(self.grow(quality)) if callable(self.grow) else float(self.grow)


@dataclass(frozen=True)
class Trial:
    """What ``solve(state, s)`` returns: success or failure, and what it produced.

    Attributes
    ----------
    ok : bool
        The step is accepted.
    value : object
        The new state when accepted (passed to the next ``solve``), else whatever explains
        the failure (an error message, a failed point).
    quality : float or None
        Optional measure of an accepted step for :attr:`StepRules.grow` (e.g. the miss of
        the predictor relative to the step).
    final : bool
        A failure that no shorter step can mend (the solver knows the solution cannot be
        continued past the accepted state): the continuation stops at once, reason
        ``"final"``, instead of shrinking the step.
    """

    ok: bool
    value: Any = None
    quality: float | None = None
    final: bool = False


@dataclass(frozen=True)
class Step:
    """One attempt of a continuation."""

    #: Parameter tried.
    s: float
    #: Step from the accepted point it started from.
    h: float
    #: Whether it was accepted.
    accepted: bool
    #: :attr:`Trial.value` of the attempt.
    value: Any = field(default=None, repr=False)


@dataclass
class Continuation:
    """Result of :func:`continue_to`.

    Attributes
    ----------
    state : object
        The last accepted state (the start state if no step was accepted).
    s : float
        Its parameter.
    reached : bool
        Whether ``s`` is the target.
    reason : str
        ``"reached"``, ``"min_step"``, ``"max_halvings"``, ``"max_attempts"``,
        ``"max_depth"`` or ``"final"`` (a :attr:`Trial.final` failure) (why it stopped).
    h : float
        Step to continue with (``"halve"``): pass it as ``h`` to the next call.
    steps : list of Step
        Every attempt, in order.
    """

    state: Any
    s: float
    reached: bool
    reason: str
    h: float
    steps: list = field(default_factory=list)

    @property
    def accepted(self) -> list:
        """The accepted steps."""
        return [st for st in self.steps if st.accepted]

    @property
    def last(self) -> Step | None:
        """The last attempt (None if there was none)."""
        return self.steps[-1] if self.steps else None

    def last_at(self, s: float) -> Step | None:
        """The last attempt at parameter ``s`` (e.g. the target), or None."""
        return next((st for st in reversed(self.steps) if st.s == s), None)


def _land(s: float, h: float, target: float, sign: float) -> float:
    """s + h in the direction of the target, exactly the target once h reaches it."""
    return target if h >= sign * (target - s) else s + sign * h


def continue_to(
    solve: Callable[[Any, float], Trial],
    state: Any,
    s0: float,
    target: float,
    rules: StepRules,
    *,
    h: float | None = None,
    origin: float | None = None,
) -> Continuation:
    """Continue ``state`` (the solution at ``s0``) to the parameter ``target``.

    Parameters
    ----------
    solve : callable
        ``solve(state, s) -> Trial``: the solution at ``s`` from the accepted ``state``.
    state : object
        Solution at ``s0``.
    s0, target : float
        Start and end of the parameter interval (either order).
    rules : StepRules
        How steps are chosen and retried.
    h : float, optional
        First step (``"halve"``; default: the whole interval).
    origin : float, optional
        Reference point of :attr:`StepRules.max_step_ratio` (default ``s0``).

    Returns
    -------
    Continuation
    """
    if rules.retry == "subdivide":
        return _subdivide(solve, state, s0, target, rules)
    sign = 1.0 if target >= s0 else -1.0
    origin = s0 if origin is None else origin
    h_next = abs(target - s0) if h is None else float(h)
    s, attempts = s0, 0
    steps: list[Step] = []

    def stop(reason):
        return Continuation(state, s, s == target, reason, h_next, steps)

    while sign * (target - s) > 0:
        h = h_next
        if s != origin and math.isfinite(rules.max_step_ratio):
            h = min(h, rules.max_step_ratio * abs(s - origin))
        if rules.clip:
            h = min(h, sign * (target - s))
        failures = 0
        while True:
            if rules.max_attempts is not None and attempts >= rules.max_attempts:
                h_next = h
                return stop("max_attempts")
            s_new = _land(s, h, target, sign)
            attempts += 1
            trial = solve(state, s_new)
            steps.append(Step(s_new, h, bool(trial.ok), trial.value))
            if trial.ok:
                break
            if trial.final:
                h_next = h
                return stop("final")
            failures += 1
            if rules.max_halvings is not None and failures > rules.max_halvings:
                h_next = h
                return stop("max_halvings")
            h *= rules.shrink
            h_next = h
            if h * rules.scale < rules.min_step:
                return stop("min_step")
        state, s = trial.value, s_new
        h_next = min(rules.max_step / rules.scale, h * rules.growth(trial.quality))
    return stop("reached")


def _subdivide(solve, state, s0, target, rules) -> Continuation:
    steps: list[Step] = []
    for depth in range(rules.max_depth + 1):
        k = 2**depth
        cur, s = state, s0
        for j in range(1, k + 1):
            s_new = target if j == k else s0 + (target - s0) * (j / k)
            trial = solve(cur, s_new)
            steps.append(Step(s_new, s_new - s, bool(trial.ok), trial.value))
            if not trial.ok and trial.final:
                return Continuation(state, s0, s0 == target, "final", abs(target - s0), steps)
            if not trial.ok:
                break
            cur, s = trial.value, s_new
        else:
            return Continuation(cur, target, True, "reached", abs(target - s0) / k, steps)
    return Continuation(state, s0, s0 == target, "max_depth", abs(target - s0), steps)


def march(solve: Callable[[Any, int], Trial], state: Any, indices) -> list:
    """Walk along grid points: ``solve(state, i)`` for each index in turn, each from the
    previous accepted value, stopping at the first failure.

    Returns
    -------
    list of (int, object)
        The accepted (index, value) pairs, in order.
    """
    out: list = []
    for i in indices:
        trial = solve(state, i)
        if not trial.ok:
            break
        state = trial.value
        out.append((i, state))
    return out
