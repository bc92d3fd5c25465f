"""The least-stable branch α(k), tracked from k = 0 (paper §4.2, figures 7–9, 13).

At k = 0 the mass-conservation mode has α = 0 exactly: its right null vector is the
tangent ∂X0/∂β of the steady family and its left null vector the total-mass functional
(Appendix B). The mass balance then gives α ≈ α1 k (eq. B 11), which seeds the
continuation; every later step predicts α from the previous points (quadratic
extrapolation) and takes the eigenvalue nearest the prediction by shift-invert. A step is
accepted when the answer lies within a quarter of the step from the prediction and its
eigenvector is resolved (Chebyshev tail); otherwise it is halved, so the branch is not lost
to the near-neutral continuum α ≈ −ik u0(y) of the dilute top, which crowds it at small k.
Each point is then checked at N' = round(0.8 N) (drift) and by the paper's tail test; N is
raised along the branch when a point fails.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..continuation import StepRules, Trial, continue_to
from ..conventions import RATE_UNITS, WAVENUMBER_UNITS
from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow, steady_tangent
from .eigen import ShiftInvert
from .modes import (
    K_DIRECT,
    Mode,
    OperatorCache,
    check_hydrodynamic_k,
    direct_mode,
    drift_of,
    interp_vector,
    join_notes,
    make_mode,
    mode_near,
    mode_score,
    nearest_eigenpair,
    resolve_policy,
    spectrum,
    stability_operator,
    tail,
)
from .operator import Pencil, StabilityOperator, validate_k, validate_n
from .policy import DEFAULT_POLICY, RejectionPolicy

#: First continuation step from k = 0.
FIRST_STEP = 1e-5
#: Smallest first step that must pass the predictor test. From k = 0 the predictor is α1 k
#: (eq. (B 2)), good while |α2| k² ≪ |α1| k. Where the k² regime is narrower than
#: :data:`FIRST_STEP` the first step is halved until α1 k predicts it (θ = 16.475°, ν0(0) =
#: 0.02, φ = 0.05: α = 9.86e-5 + 9.95e-5i at k = 1e-5 against α1 k = 1.94e-4i, the
#: k² regime ends near k ~ 1e-6); accepting the first point off the prediction left the
#: next predictor (the quadratic with slope α1 at k = 0) with the wrong slope, every
#: shorter step missed by the same 41 % of the step, and the branch was "lost" at k = 1e-5.
#: Below this step (1e-5/2¹⁰ ≈ 1e-8), or where α1 = 0 (a wavevector along z: no
#: advection), the nearest resolved eigenvector is accepted as before.
FIRST_STEP_MIN = FIRST_STEP / 1024
#: |α1| k below this is no predictor: the eigenvalue's round-off near α = 0 is ~1e-12.
FIRST_PREDICTOR_MIN = 1e-9
#: Resolution of the coarse continuation that seeds single-k solves.
COARSE_N = 48
#: Largest Chebyshev tail a tracked eigenvector may have (the physical test is stricter;
#: the continuum's tails are ~1e-4): ``RejectionPolicy.track_tail_tol``.
ACCEPT_TAIL = DEFAULT_POLICY.track_tail_tol


def _growth(ratio: float | None) -> float:
    """Step factor after an accepted step whose predictor missed by ``ratio`` of the step:
    ×3 while it hits well, ×1.5 when fair, held when off by more than 5 %."""
    assert ratio is not None  # every accepted step of the tracker reports its miss
    return 3.0 if ratio < 0.02 else 1.5 if ratio < 0.05 else 1.0


#: Smallest continuation step of the branch tracker, relative to the wavenumber it heads for.
#: A step h moves α by ~|dα/dk| h ~ |α| h/k; below h = 1e-9 k that is ~1e-9 |α|, the
#: eigenvalue's own round-off (~1e-12 absolute near the continuum, |α| ≳ 1e-4 on the
#: sweeps' k grid), so the acceptance test (miss < a quarter of the step) measures round-off.
#: Where the branch meets another eigenvalue (an exceptional point k*, dα/dk infinite) every
#: step across k* is rejected and accepted ever shorter steps creep up to it: at θ = 14.75°,
#: ν0(0) = 0.21, φ = 0.05 the tracker went down to steps of 4e-13 k, 352 rejected steps in all
#: (7.7 s of the growth metric's 12.4 s) before it gave up; 217 (5.3 s) with this bound. The
#: first step's 16 halvings (1e-5/2¹⁶) stay above it for every k ≤ 0.1.
TRACK_MIN_STEP = 1e-9


def _track_rules(max_halvings: int, s_target: float = 0.0) -> StepRules:
    """Retry rules of the branch in k (:func:`chuteflow.continuation.continue_to`): steps
    grow by :func:`_growth`, at most ×3 in k (a step at most twice the k reached), halved
    when rejected, at most ``max_halvings`` times per step, and never below
    :data:`TRACK_MIN_STEP` × ``s_target``."""
    return StepRules(
        grow=_growth,
        shrink=0.5,
        max_step_ratio=2.0,
        max_halvings=max_halvings,
        min_step=TRACK_MIN_STEP * s_target,
    )


@dataclass(frozen=True, eq=False)
class NullVectors:
    """The k = 0 eigenvalue α0 ≈ 0 of the mass mode with its right and left eigenvectors.

    Attributes
    ----------
    alpha0 : complex
        The computed eigenvalue (0 up to discretisation and round-off).
    right, left : ndarray
        A0 r = α0 B r and lᴴ A0 = α0 lᴴ B, normalised so that max |r| = 1 and lᴴ B r = 1.
    """

    alpha0: complex
    right: np.ndarray = field(repr=False)
    left: np.ndarray = field(repr=False)


def null_vectors(op: StabilityOperator) -> NullVectors:
    """Right and left eigenvectors of the k = 0 pencil for its eigenvalue nearest 0.

    Shift-invert at σ = 0 on the equilibrated pencil (the continuum nearest α0 sits at
    |α| ~ 1e-8, four decades further than the round-off of α0): right by Arnoldi, left by
    inverse iteration with the conjugate-transposed factors of the same LU. Returned for
    (A, B) itself, not the equilibrated pencil.
    """
    import scipy.linalg as sla

    if "null_vectors" in op.memo:  # a deterministic function of the operator
        return op.memo["null_vectors"]
    p = op.pencil(0.0)
    A, B = p.equilibrated()
    # nudged where α0 = 0 to the last bit (an exact zero pivot: a flow of the 60 × 60
    # φ = 0.05 diagram, θ = 17.19°, ν0(0) = 0.144, N = 160)
    si = ShiftInvert.nudged(A, B, 0.0, diagonal_B=True)
    alpha, W = si.nearest(1)
    a0, w = alpha[0], W[:, 0]
    ell = np.conj(B @ w)
    for _ in range(8):
        # (A − σB)ᴴ x = Bᴴ ℓ  ⇒  x ∝ left eigenvector for the eigenvalue nearest σ = 0
        x = sla.lu_solve(si.lu, B.T @ ell, trans=2, check_finite=False)
        ell = x / np.linalg.norm(x)
    r = p.unscale(w)
    r = r / r[np.argmax(np.abs(r))]
    left = op.row_eq * ell  # ℓᴴ R A C = 0  ⇒  (R ℓ)ᴴ A = 0
    left = left / np.conj(np.vdot(left, op.B @ r))  # lᴴ B r = 1
    nv = NullVectors(complex(a0), r, left)
    for a in (nv.right, nv.left):
        a.flags.writeable = False  # shared by every tracker on this operator
    op.memo["null_vectors"] = nv
    return nv


def first_order(op: StabilityOperator, nv: NullVectors, direction=(1.0, 0.0)) -> complex:
    """α1 = dα/ds at s = 0 along k = s·(k̂x, k̂z), from the mass balance (Appendix B).

    Integrating the linearised continuity equation over the layer (eq. B 8) with the k = 0
    eigenvector (ν̂0, û0, ŵ0) gives α1 = −i [k̂x ∫(ν0 û0 + u0 ν̂0) dy + k̂z ∫ ν0 ŵ0 dy] /
    ∫ ν̂0 dy (eq. B 11): the continuous problem's left null vector is the total-mass
    functional. It is used instead of the discrete left null vector, which the continuum
    within ~1e-8 of α = 0 makes ill-conditioned. For k along x it equals −i dQ0/dρ̄0
    (eq. B 2) up to the top truncation: measured 1.3e-5 (P1), 3e-7 (P5), 7e-8 (Q3) relative,
    independent of N.
    """
    kx, kz = direction
    norm = math.hypot(kx, kz)
    kx, kz = kx / norm, kz / norm
    r = op.pencil(0.0).split(nv.right)
    w, nu0, u0 = op.grid.weights, op.base["nu"], op.base["u"]
    flux = kx * (w @ (nu0 * r["u"] + u0 * r["nu"]))
    if "w" in r:
        flux = flux + kz * (w @ (nu0 * r["w"]))
    return complex(-1j * flux / (w @ r["nu"]))


#: The tail test's crossing rule (:meth:`BranchTracker._step`): a step rejected by the tail
#: alone, its eigenvalue on the prediction, from an accepted point whose tail is above
#: ``CROSSING_NEAR`` × the threshold, with a tail below ``CROSSING_JUMP`` × that point's,
#: is the branch's own eigenvector becoming unresolved (its tail rising through the
#: threshold), not a neighbour of the continuum (tails ≳ 10× the branch's): no shorter step
#: passes it, and the continuation stops there. Without the rule the steps crept up to the
#: crossing, halving until they fell below :data:`TRACK_MIN_STEP`: θ = 14.75°, ν0(0) = 0.217,
#: φ = 0.05 (growth metric, N = 48 … 160, tails 0.99e-5 … 1.2e-5 against 1e-5, and relaxed
#: 1.0e-3 against 1e-3): 193 of its 271 continuation steps, all rejected or crept.
CROSSING_NEAR = 0.5
CROSSING_JUMP = 2.0
#: The predictor's stall rule (:meth:`BranchTracker._step`): a step rejected because the
#: eigenvalue misses the prediction, :data:`STALL_REJECTIONS` times in a row with the miss
#: (relative to the step) falling by less than a factor ``STALL_FACTOR`` at each halving, is
#: a predictor that does not converge as the step shrinks (for a smooth branch the miss falls
#: as the step squared): the last accepted point is not on the branch's continuation, and no
#: shorter step passes. θ = 17.19°, ν0(0) = 0.144, φ = 0.05, N = 60 … 160: misses 0.36 …
#: 0.41 of the step at every step from 2.4e-9 down to 1.2e-9, 14 halvings per rung.
STALL_REJECTIONS = 3
STALL_FACTOR = 0.9

#: Largest memory (bytes of eigenvectors) that the continuation steps memoised on one
#: operator may hold (:class:`_Steps`); past it steps are solved without being kept.
STEP_MEMO_BYTES = 16 * 2**20


class _Steps:
    """The eigen-solves tried from one point of a continuation from k = 0, by the s tried.

    A continuation from k = 0 is a deterministic function of the operator, the direction,
    and its targets: :func:`~chuteflow.continuation.continue_to` picks each step from the
    steps before, and each solve (shift-invert from the predictor of the points accepted so
    far, started from the last eigenvector) depends on nothing else. Two continuations of
    the same branch therefore try the same steps until their targets or tail thresholds
    make them decide differently — after the branch is lost, the relaxed fallbacks
    (:func:`near_continuum_branch`, :func:`relaxed_branch_modes`) go from k = 0 again to
    each k of a grid, and every rung of :func:`~chuteflow.longwave.theory.eigen_sign` that
    loses it does so once strictly and twice relaxed. The solves are kept in a tree on the
    operator (``operator.memo``): a node per accepted point, its children by the s tried
    from it, each with the eigenpair found (None where none settled) and its child node.
    Replaying a tried step returns the same numbers bit for bit; only the acceptance test,
    which depends on the policy's tail threshold, is applied again. A tracker whose history
    is not a continuation from k = 0 (after :meth:`BranchTracker._raise_n`) memoises nothing:
    no other tracker can reach its steps.
    """

    __slots__ = ("tried", "budget")

    def __init__(self, budget: list[int]):
        self.tried: dict[float, _Tried] = {}
        self.budget = budget  # [bytes left], shared by the tree of one operator


@dataclass(eq=False)
class _Tried:
    """One memoised solve of :class:`_Steps`: the eigenpair (None if none settled), its
    eigenvector's tail by number of tail terms, and the node of the accepted point."""

    alpha: complex | None
    w: np.ndarray | None
    tails: dict = field(default_factory=dict)
    next: _Steps | None = None


def _step_root(op: StabilityOperator, direction) -> _Steps:
    """The root of the memoised steps from k = 0 along ``direction`` on ``op``."""
    roots = op.memo.setdefault("branch_steps", {})
    if direction not in roots:
        budget = op.memo.setdefault("branch_steps_budget", [STEP_MEMO_BYTES])
        roots[direction] = _Steps(budget)
    return roots[direction]


class BranchTracker:
    """Continuation of the α(0) = 0 branch along a ray k = s·(k̂x, k̂z), s ≥ 0.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    n : int, optional
        Starting resolution N (default ``policy.n_start``; raised along the policy's
        ladder when a point fails the drift or tail test).
    direction : (float, float)
        Unit direction (k̂x, k̂z) of the wavevector; (1, 0) for the paper's perturbations.
    policy : RejectionPolicy, optional
        Drift and tail thresholds and the resolution ladder (default: the paper's).
    n_max, drift_tol, tail_tol : optional
        Overrides of the policy's fields of the same names.
    cache : OperatorCache, optional
        Where the operators come from (default: the module's shared cache).
    """

    def __init__(
        self,
        flow: SteadyFlow,
        n: int | None = None,
        *,
        direction=(1.0, 0.0),
        policy: RejectionPolicy | None = None,
        n_max: int | None = None,
        drift_tol: float | None = None,
        tail_tol: float | None = None,
        cache: OperatorCache | None = None,
    ):
        kx, kz = (float(direction[0]), float(direction[1]))
        norm = math.hypot(kx, kz)
        if norm == 0 or kx < 0:
            raise ParameterError(
                f"direction = {direction!r}: need a nonzero wavevector direction with k̂x ≥ 0"
            )
        self.direction = (kx / norm, kz / norm)
        self.three_d = self.direction[1] != 0.0
        self.policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol, n_max=n_max)
        self.cache = cache
        self.flow = flow
        self.n = validate_n(self.policy.n_start if n is None else n)
        self.n_max = self.policy.n_max
        self._nv_n: int | None = None  # the resolution of _nv, _alpha1
        self._start(self.n)

    @property
    def drift_tol(self) -> float:
        """Drift threshold of the policy."""
        return self.policy.drift_tol

    @property
    def tail_tol(self) -> float:
        """Tail threshold of the policy."""
        return self.policy.tail_tol

    def _operator(self, n):
        return stability_operator(self.flow, n, self.three_d, cache=self.cache)

    def _start(self, n):
        op = self._operator(n)
        nv = self._null_vectors(n)
        # (s, α, eigenvector of the equilibrated pencil at N)
        self._reset(n, [(0.0, complex(nv.alpha0), nv.right / op.col_eq)])
        # the memoised solves from the last accepted point (a continuation from k = 0)
        self._node: _Steps | None = _step_root(op, self.direction)
        # tail of the last accepted point's eigenvector (the crossing rule)
        self._last_tail = tail(nv.right, len(op.fields), self.policy.tail_terms)

    def _reset(self, n, history):
        self.history = history
        self.n = n
        self._h = math.inf
        self._misses: list[float] = []  # predictor misses of the rejections since then
        self._final: str | None = None  # why no shorter step can pass (a final failure)
        self._final_at = 0.0  # and near which k

    def _null_vectors(self, n) -> NullVectors:
        if self._nv_n != n:
            op = self._operator(n)
            self._nv = null_vectors(op)
            self._alpha1 = first_order(op, self._nv, self.direction)
            self._nv_n = n
        return self._nv

    @property
    def nv(self) -> NullVectors:
        """The k = 0 null vectors at the current resolution N (:func:`null_vectors`)."""
        return self._null_vectors(self.n)

    @property
    def alpha1(self) -> complex:
        """α1 = dα/ds at s = 0 at the current resolution N (:func:`first_order`)."""
        self._null_vectors(self.n)
        return self._alpha1

    def _pencil(self, s, n=None):
        kx, kz = self.direction
        return self._operator(n or self.n).pencil(s * kx, s * kz)

    def _predict(self, s):
        h = self.history
        if len(h) == 1:
            return h[0][1] + self.alpha1 * s
        if len(h) == 2:
            (s0, a0, _), (s1, a1, _) = h
            # through the k = 0 point with slope α1, and the first point: quadratic
            c2 = (a1 - a0 - self.alpha1 * (s1 - s0)) / (s1 - s0) ** 2
            return a0 + self.alpha1 * (s - s0) + c2 * (s - s0) ** 2
        (s0, a0, _), (s1, a1, _), (s2, a2, _) = h[-3:]
        # quadratic through the last three points (Lagrange)
        return (
            a0 * (s - s1) * (s - s2) / ((s0 - s1) * (s0 - s2))
            + a1 * (s - s0) * (s - s2) / ((s1 - s0) * (s1 - s2))
            + a2 * (s - s0) * (s - s1) / ((s2 - s0) * (s2 - s1))
        )

    def _step(self, s):
        """Solve at s (> last s) from the prediction. Returns (alpha, w, ratio) with ratio =
        |miss| / |step| (how well the predictor did), or None if the answer is not
        trustworthy: too far from the prediction, or an unresolved eigenvector (the
        near-neutral continuum of the dilute top has Chebyshev tails ~1e-4)."""
        s_prev, a_prev, v_prev = self.history[-1]
        pred = self._predict(s)
        node = self._node  # None: not a continuation from k = 0, nothing to share
        tried = None if node is None else node.tried.get(s)
        if tried is None:
            try:
                alpha, w = nearest_eigenpair(self._pencil(s), pred, v0=v_prev, restarts=TRACK_RESTARTS)
            except ConvergenceError:  # no eigenvalue settled near the prediction
                alpha, w = None, None
            if w is not None:
                w = np.ascontiguousarray(w)
                w.flags.writeable = False  # shared by the trackers that replay this step
            tried = _Tried(alpha, w)
            size = 0 if w is None else w.nbytes
            if node is not None and node.budget[0] >= size:
                node.budget[0] -= size
                node.tried[s] = tried
        self._tried = tried
        if tried.alpha is None:
            self._misses = []
            return None
        alpha, w = tried.alpha, tried.w
        ratio = abs(alpha - pred) / max(abs(pred - a_prev), 1e-300)
        if len(self.history) == 1 and (
            s - s_prev <= FIRST_STEP_MIN or abs(pred - a_prev) < FIRST_PREDICTOR_MIN
        ):
            # from k = 0 the predictor α1 k may vanish (k along z: no advection), or miss at
            # the shortest first step; the nearest resolved eigenvector is the branch, as
            # the continuum fails the tail. Above it the first step must hit like any other
            # (FIRST_STEP_MIN: the next predictor's slope at k = 0 is α1)
            ratio = min(ratio, 0.25)
        if ratio > 0.25:
            self._misses.append(ratio)
            m = self._misses[-STALL_REJECTIONS:]
            if len(m) == STALL_REJECTIONS and all(b > STALL_FACTOR * a for a, b in zip(m, m[1:])):
                self._final_at = s_prev
                self._final = (
                    f"the eigenvalue misses the prediction by {ratio:.2g} of the step however short the step"
                )
            return None
        terms = self.policy.tail_terms
        if terms not in tried.tails:
            op = self._operator(self.n)
            tried.tails[terms] = tail(op.col_eq * w, len(op.fields), terms)
        t, tol = tried.tails[terms], self.policy.track_tail_tol
        if t > tol:
            self._misses = []
            t_a = self._last_tail
            if t_a > tol and t < CROSSING_JUMP * t_a:
                # (only from k = 0, whose null vector is accepted by construction)
                self._final_at = s_prev
                self._final = (
                    f"its eigenvector is not resolved at k = {s_prev:.4g} (Chebyshev tail "
                    f"{t_a:.1e} above the tracking threshold {tol:g})"
                )
            elif t_a > CROSSING_NEAR * tol and t < CROSSING_JUMP * t_a:
                # the branch's own tail rises through the threshold between s_prev and s:
                # log-linear estimate of the crossing (see CROSSING_NEAR)
                self._final_at = s_prev + (s - s_prev) * math.log(tol / t_a) / math.log(t / t_a)
                self._final = (
                    f"its eigenvector's Chebyshev tail rises through the tracking threshold {tol:g} there"
                )
            return None
        self._last_tail = t
        self._misses = []
        return alpha, w, ratio

    def _solve(self, state, s) -> Trial:
        """One continuation attempt at s; an accepted point joins the history (the
        predictor's memory)."""
        res = self._step(s)
        if res is None:
            return Trial(False, final=self._final is not None)
        alpha, w, ratio = res
        self.history.append((s, complex(alpha), w))
        tried, node = self._tried, self._node
        if node is not None:
            if tried.next is None:
                tried.next = _Steps(node.budget)
            self._node = tried.next
        return Trial(True, s, ratio)

    def advance(self, s_target: float, max_halvings: int = 16) -> tuple[complex, np.ndarray]:
        """Continue the branch up to s_target (≥ the last point); returns (alpha, w).

        Steps (:func:`chuteflow.continuation.continue_to`) start at 1e-5 from k = 0, grow
        geometrically (at most ×3 in k) while the predictor hits well, are held when it is
        off by more than 5 % of the step, and halved when a step is rejected (at most
        ``max_halvings`` times per step, then :class:`ConvergenceError`).
        """
        s_last = self.history[-1][0]
        if s_target < s_last:
            raise ParameterError("the branch is tracked in increasing k only")
        if s_target > s_last:
            # first step: α1 k predicts well while |α2| k² ≪ |α1| k; 1e-5 is inside the
            # quadratic regime of every flow checked (docs/errata.md: it narrows to ~1e-5)
            h = FIRST_STEP if s_last == 0.0 else self._h
            res = continue_to(
                self._solve, s_last, s_last, s_target, _track_rules(max_halvings, s_target), h=h, origin=0.0
            )
            self._h = res.h
            if res.reason == "final":
                why, self._final, self._misses = self._final, None, []
                raise ConvergenceError(
                    f"lost the branch near k = {self._final_at:.4g} (theta = {self.flow.theta:g}, "
                    f"nu0 = {self.flow.nu0:g}, N = {self.n}): {why}"
                )
            if not res.reached:
                raise ConvergenceError(
                    f"lost the branch near k = {res.steps[-1].s:.4g} (theta = "
                    f"{self.flow.theta:g}, nu0 = {self.flow.nu0:g}, N = {self.n}): the "
                    "continuation step shrank below any useful size"
                )
        return self.history[-1][1], self.history[-1][2]

    def mode(self, s: float) -> Mode:
        """The tracked mode at s with drift and tail; raises N until physical."""
        while True:
            try:
                alpha, v = self.advance(s)
            except ConvergenceError:
                if self.n >= self.n_max:
                    raise
                self._raise_n()
                continue
            pencil = self._pencil(s)
            kx, kz = self.direction
            drift, n2 = drift_of(self.flow, alpha, v, self.n, s * kx, s * kz, self.three_d, cache=self.cache)
            mode = make_mode(pencil, alpha, v, drift, n2, self.policy)
            if mode.physical or self.n >= self.n_max:
                return mode
            self._raise_n()

    def _raise_n(self):
        """Move the branch to a finer grid: the k = 0 point and the last two points (all the
        predictor needs) are re-solved there; earlier points are dropped."""
        n_new = self.policy.next_n(self.n)
        old = self.history[1:][-2:]
        n_old = self.n
        if len(old) < 2:  # the predictor needs the k = 0 point's slope α1: start afresh
            self._start(n_new)
        else:
            # the predictor is the quadratic through k = 0 and the two points: the null
            # vectors at N_new are not needed (computed on demand: nv, alpha1), and the
            # k = 0 point keeps α0 ≈ 0 of the coarser grid (round-off, ~1e-9)
            self._reset(n_new, [(0.0, self.history[0][1], None)])
        op = self._operator(n_new)
        nf = len(op.fields)
        for s, a, v in old:
            pencil = self._pencil(s)
            alpha, v2 = nearest_eigenpair(pencil, a, v0=interp_vector(v, nf, n_old, n_new))
            self.history.append((s, complex(alpha), v2))
        if old:  # no longer a continuation from k = 0 on this grid: steps not memoised
            self._node = None
            self._last_tail = tail(op.col_eq * self.history[-1][2], nf, self.policy.tail_terms)


def branch_mode(
    flow: SteadyFlow,
    k: float,
    *,
    kz: float = 0.0,
    n: int | None = None,
    policy: RejectionPolicy | None = None,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    cache: OperatorCache | None = None,
) -> Mode:
    """The mode of the α(0) = 0 branch at (k, kz), tracked from k = 0, at resolution N.

    The continuation runs on a coarse grid (N_c = 48, an LU ~10× cheaper), whose eigenvalue
    (accurate to ~1e-4 relative) is the shift of a single solve at N, followed by the drift
    check at N'. If the coarse branch is lost, or the fine solve does not land on a resolved
    eigenvector close to it, the continuation is redone at N. ``n`` defaults to
    ``policy.n_start``; the mode is judged by ``policy`` (``drift_tol``, ``tail_tol``:
    overrides of its thresholds).
    """
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol)
    n = validate_n(policy.n_start if n is None else n)
    kk = math.hypot(k, kz)
    direction = (k, kz) if kk else (1.0, 0.0)
    if kk > 0 and n > COARSE_N + 16:
        try:
            coarse = BranchTracker(
                flow, COARSE_N, direction=direction, policy=policy, n_max=COARSE_N, cache=cache
            )
            a_c, w_c = coarse.advance(kk)
            op = stability_operator(flow, n, coarse.three_d, cache=cache)
            pencil = op.pencil(k, kz)
            alpha, w = nearest_eigenpair(pencil, a_c, v0=interp_vector(w_c, len(op.fields), COARSE_N, n))
            if abs(alpha - a_c) < 1e-2 * abs(a_c):
                drift, n2 = drift_of(flow, alpha, w, n, k, kz, coarse.three_d, cache=cache)
                mode = make_mode(pencil, alpha, w, drift, n2, policy)
                if mode.physical:
                    return mode
        except ConvergenceError:
            pass
    tr = BranchTracker(flow, n, direction=direction, policy=policy, n_max=n, cache=cache)
    return tr.mode(kk)


#: Largest eigenvector tail accepted by the continuation of :func:`near_continuum_branch`,
#: the fallback after the branch was lost: where the branch's phase velocity −Im α/k enters
#: the range of u0(y), its eigenvector has a critical layer and tails of 1e-6 … 1e-4, which
#: the tracking threshold (1e-5) rejects although the eigenvalue is still the branch.
RELAXED_TAIL = 1e-3
#: Numbers of equal sub-targets of :func:`near_continuum_branch`'s attempts (a finer sequence
#: of targets keeps the predictor's steps short where the branch turns sharply).
RELAXED_SPLITS = (1, 8)
#: Largest relative drift |α(N) − α(N')| / |α| of a relaxed branch value that is returned.
RELAXED_DRIFT = 0.05


def near_continuum_branch(
    flow: SteadyFlow,
    k: float,
    *,
    kz: float = 0.0,
    n: int,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
) -> Mode | None:
    """The α(0) = 0 branch at (k, kz) and N, tracked with the tail threshold relaxed to
    :data:`RELAXED_TAIL`: the fallback where :class:`BranchTracker` lost the branch.

    The tracker loses the branch where its phase velocity −Im α/k enters the range of the
    base velocity u0(y) (e.g. θ = 16.5°, ν0(0) = 0.13, φ = 0.08, Φ = 0.30 at k ≈ 0.0036:
    Im α/k ≈ −3.8 against u0 ∈ [2.92, 3.88]): the eigenvector develops a critical layer
    whose Chebyshev tail (1e-6 … 1e-4) exceeds the tracking threshold, and the steps halve
    until they stall. The continuation is redone from k = 0 with the threshold
    :data:`RELAXED_TAIL`, to the targets k/m, 2k/m, …, k for m in :data:`RELAXED_SPLITS`
    (the predictor still has to hit within a quarter of each step, so the answer is the
    continuous continuation of the branch). The mode is judged by ``policy`` (the paper's
    drift and tail tests: it is returned flagged when it fails them, with its drift
    |α(N) − α(N')| as the convergence estimate) and ``method = "branch (relaxed)"``.

    Returns None when no attempt reaches k, or the drift exceeds :data:`RELAXED_DRIFT`
    |α| (no eigenvalue at N' continues it: not a trustworthy branch value).
    """
    policy = resolve_policy(policy)
    kk = math.hypot(k, kz)
    if kk == 0:
        return None
    direction = (k, kz)
    relaxed = policy.replace(track_tail_tol=max(RELAXED_TAIL, policy.track_tail_tol), n_start=n, n_max=n)
    for m in RELAXED_SPLITS:
        tr = BranchTracker(flow, n, direction=direction, policy=relaxed, cache=cache)
        try:
            for target in np.linspace(0.0, kk, m + 1)[1:]:
                alpha, w = tr.advance(float(target))
            pencil = tr._pencil(kk)
            drift, n2 = drift_of(flow, alpha, w, n, k, kz, tr.three_d, cache=cache)
        except ConvergenceError:
            continue
        if not drift <= RELAXED_DRIFT * abs(alpha):
            continue
        mode = make_mode(pencil, alpha, w, drift, n2, policy)
        u = tr._operator(n).base["u"]
        note = _relaxed_note(alpha, kk, (float(np.min(u)), float(np.max(u))), policy)
        return dataclasses.replace(mode, method="branch (relaxed)", note=note)
    return None


def _relaxed_note(alpha: complex, k: float, u_range: tuple[float, float], policy: RejectionPolicy) -> str:
    """The note of a branch value followed with the relaxed tail threshold."""
    return (
        f"branch followed with eigenvector tails up to {RELAXED_TAIL:g} (the tracking "
        f"threshold {policy.track_tail_tol:g} lost it): phase velocity −Im α/k = "
        f"{-alpha.imag / k:.4g} against u0 in [{u_range[0]:.4g}, {u_range[1]:.4g}]"
    )


def relaxed_branch_modes(
    flow: SteadyFlow,
    ks,
    *,
    n: int,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    lost: str = "",
) -> list[Mode]:
    """The α(0) = 0 branch at the increasing wavenumbers ``ks`` (along x) and N after
    :class:`BranchTracker` lost it: the fallback of a k grid.

    How far the branch reaches comes from one continuation from k = 0 through every k in
    turn with the tail threshold relaxed to :data:`RELAXED_TAIL`; it stops at the first k
    not reached, or where the drift exceeds :data:`RELAXED_DRIFT` |α| (no eigenvalue at N'
    continues it). A value that passes the paper's tests there is resolved and kept; each
    value that fails them is recomputed by its own continuation from k = 0
    (:func:`near_continuum_branch`), and where that does not reach k the list ends. Near a
    critical layer the relaxed branch runs through a band of unresolved eigenvalues, and
    which one a continuation lands on depends on its steps: one continuation through a k
    grid lands farther from the branch than a continuation from k = 0 to each k, with a
    drift that hides its error (θ = 16.5°, ν0(0) = 0.13, φ = 0.08, Φ = 0.30, k = 0.006
    against N = 244: from k = 0 at N = 80, 100, 125 errors 2.0e-4, 3.2e-4, 4.0e-4 with drifts
    1.4e-4 … 2.1e-4; through 12 k of a grid 1.8e-3, 2.6e-3, 7.2e-4 with drifts ~1e-4).

    Returns
    -------
    list of Mode
        The modes at ``ks[:len(result)]`` (a prefix of the grid, empty when not even the
        first k is reached), judged by ``policy``, ``method = "branch (relaxed)"``, notes
        headed by ``lost``.
    """
    policy = resolve_policy(policy)
    relaxed = policy.replace(track_tail_tol=max(RELAXED_TAIL, policy.track_tail_tol), n_start=n, n_max=n)
    out: list[Mode] = []
    tr = BranchTracker(flow, n, policy=relaxed, cache=cache)
    u = tr._operator(n).base["u"]
    u_range = (float(np.min(u)), float(np.max(u)))
    for k in ks:
        k = float(k)
        try:
            alpha, w = tr.advance(k)
            drift, n2 = drift_of(flow, alpha, w, n, k, 0.0, False, cache=cache)
        except ConvergenceError:
            break
        if not drift <= RELAXED_DRIFT * abs(alpha):
            break
        mode = make_mode(tr._pencil(k), alpha, w, drift, n2, policy)
        if not mode.physical:
            again = near_continuum_branch(flow, k, n=n, policy=policy, cache=cache)
            if again is None:
                break
            mode = again
        else:
            mode = dataclasses.replace(
                mode, method="branch (relaxed)", note=_relaxed_note(alpha, k, u_range, policy)
            )
        out.append(dataclasses.replace(mode, note=join_notes(lost, mode.note)))
    return out


def _outranked(
    relaxed: Mode,
    cand: Mode | None,
    k: float,
    policy: RejectionPolicy,
    where: str = "",
    *,
    base: str | None = None,
    why: Callable[[Mode], str] | None = None,
) -> Mode:
    """``cand``, a direct solve's mode, in place of the flagged relaxed branch value where
    :meth:`RejectionPolicy.direct_outranks_relaxed` says so (``method = "qz (branch lost)"``,
    the relaxed value and its drift in the note); else ``relaxed``. The note starts with
    ``base`` (default: the relaxed value's note), then ``why(cand)`` (default: below the
    continuum, the relaxed value rejected by the paper's tests), then ``cand``'s note."""
    if cand is None or not policy.direct_outranks_relaxed(
        k, cand.alpha.real, cand.drift, cand.tail, relaxed.alpha.real, relaxed.drift
    ):
        return relaxed
    text = (
        why(cand)
        if why is not None
        else f"the branch, near the continuum of the dilute top, followed with relaxed tails "
        f"reaches α = {relaxed.alpha:.6g} with drift {relaxed.drift:.1e}{where} (rejected by "
        "the paper's tests); this mode passes both and is less damped"
    )
    return dataclasses.replace(
        cand,
        method="qz (branch lost)",
        note=join_notes(relaxed.note if base is None else base, text, cand.note),
    )


#: ARPACK restarts (per Krylov size) of one continuation step of the branch tracker. Where
#: inverse iteration from the previous step's eigenvector does not settle, the prediction
#: usually sits in the continuum of the dilute top, and a failed step is only halved: the
#: default 60 restarts (2 × ~1100 solves) then buy nothing (thick dilute layer θ = 23.347°,
#: ν0(0) = 0.0087, φ = 0.0918, Φ = 0.393: the k_c scan took 53.6 s with 60, 15.0 s with 10,
#: the same outcome — branch lost near k = 2.0e-5; 22 of 41 Arnoldi calls gave up at 60).
TRACK_RESTARTS = 10

#: Radius, in drifts of the relaxed value, of the neighbourhood searched for the branch among
#: the band's eigenvalues (P4, k = 0.5, N = 200: the continuation lands 3.6e-3 (mapped) and
#: 5.8e-3 (plain) from the branch, with drifts 3.0e-3 and 3.2e-3).
BAND_RADIUS = 5.0
#: A band eigenvalue replaces the relaxed value only when its eigenvector's tail is this
#: factor smaller (P4, k = 0.5, N = 200: 1.8e-5 against 7.1e-4 mapped, 4.8e-5 against
#: 7.0e-4 plain; the other band members have tails ≥ 1.4e-4).
BAND_TAIL_GAIN = 0.1


def after_lost_branch(
    flow: SteadyFlow,
    k: float,
    *,
    kz: float = 0.0,
    n: int,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    lost: str = "",
    check_direct: bool = True,
) -> Mode | None:
    """The answer at (k, kz) and N after the continuation lost the branch: the branch followed
    with the relaxed tail threshold (:func:`near_continuum_branch`), or a direct solve where
    the policy prefers it (:meth:`RejectionPolicy.direct_outranks_relaxed`).

    A relaxed value that passes the paper's tests, or one at |k| ≤ ``policy.relaxed_k_max``,
    is returned as it is. Beyond, the branch lies in a band of critical-layer eigenvalues
    whose eigenvectors are not resolved (tails ~1e-3), and the continuation may land on a
    neighbour: the dense spectrum at N (:func:`spectrum`) is searched within
    :data:`BAND_RADIUS` drifts of the relaxed value, and the eigenvalue there whose tail is
    smallest, by at least :data:`BAND_TAIL_GAIN`, replaces it (the branch: at P4, k = 0.5 it
    converges with N, drift 6.4e-4 at N = 200 to 9.1e-6 at N = 360, while the band's
    members do not). Then the least-stable mode of the same spectrum (:func:`direct_mode`)
    replaces the (flagged) branch value when it is resolved, drifts less and is at least as
    unstable (``method = "qz (branch lost)"``, the branch value and its drift in the note).
    ``lost`` (where the branch was lost) heads the note. None when the relaxed continuation
    does not reach k. With ``check_direct=False`` the dense spectrum is skipped (the band search and
    the direct mode): the relaxed value is returned as it is (:func:`least_stable` at the
    rungs of its ladder below the last, where an unresolved answer only leads to the next
    rung: the two dense QZ at N and N' per rung cost 4 times the relaxed continuation at
    N ≥ 195; P4, k = 0.2: 77 s before, the dense spectrum at the last rung only).
    """
    policy = resolve_policy(policy)
    relaxed = near_continuum_branch(flow, k, kz=kz, n=n, policy=policy, cache=cache)
    if relaxed is None:
        return None
    relaxed = dataclasses.replace(relaxed, note=join_notes(lost, relaxed.note))
    kk = math.hypot(k, kz)
    if relaxed.physical or kk <= policy.relaxed_k_max or not check_direct:
        return relaxed
    modes = spectrum(flow, k, kz=kz, n=n, policy=policy, physical_only=False, cache=cache)
    radius = BAND_RADIUS * relaxed.drift
    band = [m for m in modes if abs(m.alpha - relaxed.alpha) <= radius]
    if band:
        best = min(band, key=lambda m: m.tail)
        if best.tail <= BAND_TAIL_GAIN * relaxed.tail:
            relaxed = dataclasses.replace(
                best,
                method="branch (relaxed)",
                note=join_notes(
                    relaxed.note,
                    f"the continuation landed on {relaxed.alpha:.6g} (tail {relaxed.tail:.1e}) in a "
                    f"band of unresolved eigenvalues; the branch is the one of least tail within "
                    f"{BAND_RADIUS:g} drifts",
                ),
            )
    direct = direct_mode(flow, k, kz=kz, n=n, policy=policy, cache=cache, modes=modes)
    return _outranked(
        relaxed,
        direct,
        kk,
        policy,
        base=lost,
        why=lambda d: (
            f"the branch followed with relaxed tails reaches α = {relaxed.alpha:.6g} with "
            f"drift {relaxed.drift:.1e} (|k| > {policy.relaxed_k_max:g}); the direct solve's mode is "
            f"less damped and drifts {d.drift:.1e}"
        ),
    )


# -- dispersion relation -----------------------------------------------------------------
def dispersion(
    flow: SteadyFlow,
    k,
    *,
    n: int | None = None,
    policy: RejectionPolicy | None = None,
    n_max: int | None = None,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    strict: bool = True,
    cache: OperatorCache | None = None,
):
    """Dispersion relation α(k) of the α(0) = 0 branch (figures 7–9, 13).

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    k : array_like
        Wavenumbers ≥ 0 (any order; computed in increasing order by continuation).
    n : int, optional
        Starting resolution (default ``policy.n_start``, 80); raised along the policy's
        ladder where a point fails.
    policy : RejectionPolicy, optional
        Drift and tail thresholds and the resolution ladder (default: the paper's, §4.1).
    n_max, drift_tol, tail_tol : optional
        Overrides of the policy's fields of the same names.
    strict : bool
        Raise :class:`ConvergenceError` when a point is not physical at N = ``n_max`` or
        the branch is lost (default); otherwise return such points flagged
        ``physical = False``. Where the continuation loses the branch (non-strict), that
        and every larger k up to ``policy.relaxed_k_max`` are followed once more from k = 0
        with the relaxed tail threshold (:func:`relaxed_branch_modes`, judged by the paper's
        tests), where a direct mode that passes both tests and is less damped outranks a
        rejected relaxed value (:meth:`RejectionPolicy.direct_outranks_relaxed`, as in
        :func:`least_stable`); beyond ``relaxed_k_max`` each k as :func:`after_lost_branch`
        answers; where none of these reaches k, solved directly at k (least-stable physical
        mode by dense QZ at the ladder's first rung, followed up the policy's ladder by
        shift-invert while it converges, :func:`_direct_ladder`). Direct answers are flagged
        ``direct = True`` and ``physical = False`` (a direct solve is not known to lie on
        the branch); the attribute ``branch_lost_at`` is the k where the branch was lost.

    Returns
    -------
    xarray.Dataset
        Over ``k``: ``alpha_re``, ``alpha_im``, ``drift`` (|α(N) − α(N')|), ``tail``, ``n``,
        ``physical``, ``direct`` (solved directly at k, not on the tracked branch);
        attributes: the flow's parameters, ``dQ_drho`` (dQ0/dρ̄0 of the
        steady family, eq. (B 6): the long-wave slope −Im α/k, figure 8) and ``alpha1_re``,
        ``alpha1_im`` (the continuation's first-order coefficient, α ≈ α1 k).
    """
    import xarray as xr

    ks = np.atleast_1d(np.asarray(k, dtype=float))
    if ks.ndim != 1 or len(ks) == 0:
        raise ParameterError("k: expected a non-empty 1-D array of wavenumbers")
    for kk in ks:
        validate_k(kk, "k")
        check_hydrodynamic_k(kk)
    order = np.argsort(ks, kind="stable")
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol, n_max=n_max)
    tr = BranchTracker(flow, n or None, policy=policy, cache=cache)
    out = {name: np.full(len(ks), np.nan) for name in ("alpha_re", "alpha_im", "drift", "tail")}
    nres = np.zeros(len(ks), dtype=int)
    phys = np.zeros(len(ks), dtype=bool)
    direct = np.zeros(len(ks), dtype=bool)
    lost_at = None
    followed: dict[int, Mode] = {}  # the relaxed continuation's modes, by index into ks
    for pos, i in enumerate(order):
        if lost_at is None:
            try:
                mode = _zero_mode(tr) if ks[i] == 0.0 else tr.mode(ks[i])
            except ConvergenceError:
                if strict:
                    raise
                lost_at = float(ks[i])
                # this and the larger k up to policy.relaxed_k_max: followed once more from
                # k = 0 with the relaxed tail threshold, up to the first k not reached
                below = [int(j) for j in order[pos:] if ks[j] <= policy.relaxed_k_max]
                reached = relaxed_branch_modes(
                    flow, [float(ks[j]) for j in below], n=tr.n, policy=policy, cache=cache
                )
                followed = dict(zip(below, reached))
        if lost_at is not None and i in followed:
            mode = followed[i]
            if not mode.physical:
                # as least_stable below policy.relaxed_k_max: a direct mode that passes both
                # of the paper's tests and is less damped outranks the flagged relaxed value
                # (one dense solve at the ladder's first rung: where the relaxed value is
                # rejected, the branch has dissolved and is strongly damped, e.g. Re α =
                # −0.023 with drift 8e-5 at k = 0.0079 against a resolved −0.0046 for θ =
                # 15.36°, ν0(0) = 0.12)
                cand = direct_mode(flow, float(ks[i]), n=policy.n_start, policy=policy, cache=cache)
                mode = _outranked(mode, cand, float(ks[i]), policy)
                direct[i] = mode.method != "branch (relaxed)"
        elif lost_at is not None:
            # branch lost and not reached by the relaxed continuation: past
            # policy.relaxed_k_max as least_stable answers there (after_lost_branch: the band
            # search and the direct mode); else solved directly at k (dense QZ at the
            # ladder's first rung, whose resolved modes need no more, then the candidate
            # followed up the ladder by shift-invert: _direct_ladder)
            relaxed = None
            if ks[i] > policy.relaxed_k_max:
                relaxed = after_lost_branch(flow, float(ks[i]), n=tr.n, policy=policy, cache=cache)
            if relaxed is not None:
                mode = relaxed
                direct[i] = relaxed.method != "branch (relaxed)"
            else:
                mode = _direct_ladder(flow, float(ks[i]), policy, cache)
                direct[i] = True
        if strict and not mode.physical:
            raise ConvergenceError(
                f"dispersion at theta = {flow.theta:g}, nu0 = {flow.nu0:g}: k = {ks[i]:g} not "
                f"converged at N = {mode.n} (drift {mode.drift:.1e}, tail {mode.tail:.1e}; "
                f"thresholds {policy.drift_tol:g}, {policy.tail_tol:g}); raise n_max or pass "
                "strict=False"
            )
        out["alpha_re"][i], out["alpha_im"][i] = mode.alpha.real, mode.alpha.imag
        out["drift"][i], out["tail"][i] = mode.drift, mode.tail
        # a direct solve is not known to lie on the tracked branch: flagged, not physical
        nres[i], phys[i] = mode.n, mode.physical and not direct[i]
    attrs = {
        "long_name": "dispersion relation of the alpha(0) = 0 branch",
        "source": "Mitarai & Nakanishi §4, eq. (4.4)",
        "theta": flow.theta,
        "nu0": flow.nu0,
        "nu_top": flow.nu_top,
        "y_max": flow.y_max,
        "dQ_drho": float(steady_tangent(flow)["dQ_drho"]),
        "alpha1_re": tr.alpha1.real,
        "alpha1_im": tr.alpha1.imag,
        "drift_tol": policy.drift_tol,
        "tail_tol": policy.tail_tol,
    }
    if lost_at is not None:
        attrs["branch_lost_at"] = lost_at
    attrs.update(flow.model.attrs())
    u = RATE_UNITS
    ds = xr.Dataset(
        {
            "alpha_re": ("k", out["alpha_re"], {"long_name": "growth rate Re alpha", "units": u}),
            "alpha_im": ("k", out["alpha_im"], {"long_name": "Im alpha", "units": u}),
            "drift": ("k", out["drift"], {"long_name": "|alpha(N) - alpha(N')|", "units": u}),
            "tail": (
                "k",
                out["tail"],
                {"long_name": "largest of the ten highest Chebyshev coefficients", "units": "1"},
            ),
            "n": ("k", nres, {"long_name": "Chebyshev intervals N"}),
            "physical": ("k", phys, {"long_name": "passes drift and tail tests"}),
            "direct": (
                "k",
                direct,
                {"long_name": "solved directly at k (dense QZ), not on the tracked branch"},
            ),
        },
        coords={"k": ("k", ks, {"long_name": "wavenumber", "units": WAVENUMBER_UNITS})},
        attrs=attrs,
    )
    return ds


def _zero_mode(tr: BranchTracker) -> Mode:
    """The k = 0 point: the null vector, with its own drift and tail."""
    a0 = tr.nv.alpha0
    v = tr.nv.right / tr._operator(tr.n).col_eq
    pencil = tr._pencil(0.0)
    drift, n2 = drift_of(tr.flow, a0, v, tr.n, 0.0, 0.0, tr.three_d, cache=tr.cache)
    return make_mode(pencil, a0, v, drift, n2, tr.policy)


# -- critical wavenumber -----------------------------------------------------------------
class Crossings(tuple):
    """The wavenumbers where Re α of the tracked branch changes sign (a tuple of floats, in
    increasing order), with the convergence of the scan that found them.

    Attributes
    ----------
    converged : bool
        Every grid point of the scan passed the drift and tail tests and the branch was
        followed up to ``k_max``.
    max_drift, max_tail : float
        Largest drift and tail over the scanned points.
    n : int
        Largest resolution N used.
    k_reached : float
        Largest k of the scan (< ``k_max`` when the branch was lost).
    message : str
        Empty when converged; else what was not reached.
    """

    converged: bool = True
    max_drift: float = 0.0
    max_tail: float = 0.0
    n: int = 0
    k_reached: float = math.nan
    message: str = ""

    def __new__(cls, ks=(), **info):
        obj = super().__new__(cls, tuple(ks))
        for name, value in info.items():
            setattr(obj, name, value)
        return obj


def critical_k(
    flow: SteadyFlow,
    *,
    k_max: float = 0.05,
    num: int = 40,
    n: int | None = None,
    n_max: int | None = None,
    xtol: float = 1e-10,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    strict: bool = False,
):
    """Critical wavenumber k_c where Re α of the α(0) = 0 branch changes sign (brentq).

    The branch is tracked on a grid of ``num`` points up to ``k_max`` (denser at small k);
    each sign change of Re α is refined by Brent's method on the tracked branch.

    Returns
    -------
    float or None
        The smallest crossing k_c (the upper edge of the long-wave unstable band 0 < k < k_c
        when the flow is long-wave unstable); None when Re α does not change sign in
        (0, k_max]. All crossings, with the convergence of the scan, are in
        :func:`crossings` (``strict``: see there).
    """
    found = crossings(
        flow, k_max=k_max, num=num, n=n, n_max=n_max, xtol=xtol, policy=policy, cache=cache, strict=strict
    )
    return found[0] if found else None


def crossings(
    flow: SteadyFlow,
    *,
    k_max: float = 0.05,
    num: int = 40,
    n: int | None = None,
    n_max: int | None = None,
    xtol: float = 1e-10,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    strict: bool = False,
) -> Crossings:
    """All wavenumbers in (0, k_max] where Re α of the tracked branch changes sign
    (each grid point judged by ``policy``; ``n_max`` overrides its largest N).

    Returns a :class:`Crossings` (a tuple of floats with the scan's convergence). With
    ``strict=False`` (default) points that miss the paper's thresholds by N = ``n_max`` are
    used with their best estimate, and a lost branch ends the scan at the last point
    reached; ``.converged`` is then False and ``.message`` says why. ``strict=True`` raises
    :class:`ConvergenceError` instead.
    """
    from .._memory import brentq  # scipy's, without a reference cycle that keeps the operators

    k_max = validate_k(k_max, "k_max")
    if k_max == 0 or num < 3:
        raise ParameterError("k_max must be > 0 and num ≥ 3")
    check_hydrodynamic_k(k_max)
    # geometric start resolves the narrow quadratic regime, then uniform
    ks = np.unique(
        np.concatenate([np.geomspace(1e-5, k_max, num // 3), np.linspace(0, k_max, num - num // 3 + 1)[1:]])
    )
    tr = BranchTracker(flow, n or None, policy=policy, n_max=n_max, cache=cache)
    vals: list[tuple] = []  # (k, α, eigenvector of the equilibrated pencil, N) per grid point
    messages = []
    max_drift = max_tail = 0.0
    for kk in ks:
        try:
            mode = tr.mode(kk)
        except ConvergenceError as exc:
            if strict:
                raise
            messages.append(
                f"branch lost near k = {kk:g} ({exc}); scanned up to k = {vals[-1][0] if vals else 0.0:g}"
            )
            break
        max_drift, max_tail = max(max_drift, mode.drift), max(max_tail, mode.tail)
        if not mode.physical:
            msg = (
                f"the branch at k = {kk:g} is not converged at N = {mode.n} (drift "
                f"{mode.drift:.1e}, tail {mode.tail:.1e})"
            )
            if strict:
                raise ConvergenceError(
                    f"critical k at theta = {flow.theta:g}, nu0 = {flow.nu0:g}: {msg}; lower "
                    "k_max or raise n_max"
                )
            if not messages:
                messages.append(msg)
        vals.append((kk, mode.alpha, tr.history[-1][2], tr.n))
    out = []
    for (ka, aa, wa, na), (kb, ab, _, nb) in zip(vals[:-1], vals[1:]):
        if aa.real == 0 or np.sign(aa.real) == np.sign(ab.real):
            continue
        op = stability_operator(flow, nb, cache=cache)
        start = wa if na == nb else interp_vector(wa, len(op.fields), na, nb)

        def f(kk, ka=ka, kb=kb, aa=aa, ab=ab, start=start, op=op):
            pred = aa + (ab - aa) * (kk - ka) / (kb - ka)
            return nearest_eigenpair(op.pencil(kk), pred, v0=start)[0].real

        try:
            out.append(float(brentq(f, ka, kb, xtol=xtol * kb, rtol=1e-12)))
        except (ConvergenceError, ValueError) as exc:
            if strict:
                raise
            # the refinement left the branch: keep the bracket's linear estimate
            out.append(float(ka - aa.real * (kb - ka) / (ab.real - aa.real)))
            messages.append(f"crossing in [{ka:g}, {kb:g}] from linear interpolation ({exc})")
    return Crossings(
        out,
        converged=not messages,
        max_drift=max_drift,
        max_tail=max_tail,
        n=max((v[3] for v in vals), default=tr.n),
        k_reached=vals[-1][0] if vals else 0.0,
        message="; ".join(messages),
    )


#: :func:`least_stable` checks a direct solve's physical mode past the continuum once more
#: near the top of the ladder (:func:`_check_above_continuum`), at its first rung of at least
#: this fraction of the top (244 of the default 80 … 244, 256), and only when the mode passed
#: below that rung. Within 10 % of the top, a dense spectrum already shows every eigenvalue
#: the top would resolve above the answer: one with a tail below 1e-7 at the top has a tail
#: below the tracking threshold 1e-5 at ≤ 10 % fewer nodes (a Chebyshev tail falls by far
#: less than 100× over 25 nodes), where :func:`~chuteflow.stability.modes.direct_mode`
#: returns it as the flagged least-stable candidate. The check's N' = 0.8 N is then the rung
#: below, whose eigenvalues the ladder may have computed already. P1, k = 3: the check at
#: N = 256 after the mode passed at 244 cost 41 of 107 s.
TOP_CHECK_BELOW = 0.9


def _top_check_n(ladder: list[int]) -> int:
    """The rung of :data:`TOP_CHECK_BELOW`."""
    return next(r for r in ladder if r >= TOP_CHECK_BELOW * ladder[-1])


def _check_above_continuum(flow, k, kz, n_top, mode: Mode, policy, cache, lost: str) -> Mode:
    """A direct solve's physical mode past the continuum (k > ``policy.relaxed_k_max``) with
    unresolved eigenvalues above it, checked once more near the top of the ladder (at
    ``n_top``, :data:`TOP_CHECK_BELOW`): there a branch in the band of critical-layer
    eigenvalues may be nearly resolved and less damped (P4, k = 0.5: −2.51 − 0.87i passes
    both tests at N = 80, but the branch at −0.0300 − 0.8172i is picked out at N = 244 and
    256, drift ~1e-4, tail ~4e-6). The less damped answer wins, flagged if it does not pass
    the tests."""
    top = direct_mode(flow, k, kz=kz, n=n_top, policy=policy, cache=cache)
    if top is None or top.alpha.real <= mode.alpha.real + max(mode.drift, top.drift):
        return mode
    note = join_notes(
        lost,
        top.note,
        f"less damped than the mode {mode.alpha:.6g} that passes both tests at N = {mode.n}",
    )
    return dataclasses.replace(top, method=mode.method, note=note)


def least_stable(
    flow: SteadyFlow,
    k: float,
    *,
    kz: float = 0.0,
    n: int | None = None,
    sigma: complex | None = None,
    method: str = "branch",
    policy: RejectionPolicy | None = None,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    n_max: int | None = None,
    strict: bool = False,
    cache: OperatorCache | None = None,
) -> Mode:
    """The least-stable physical mode at wavenumber ``k``.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    k, kz : float
        Wavenumber(s); |k| ≤ :data:`K_HYDRO_MAX` = 2π (a wavelength of one particle
        diameter: beyond it the hydrodynamics does not apply and ParameterError is raised).
    n : int, optional
        Resolution N. Default: adaptive, along ``policy.ladder()`` (80, 100, 125, …, by
        factors 1.25) until the mode is physical, at most ``policy.n_max`` (256).
    sigma : complex, optional
        Shift: return the physical mode nearest σ (shift-invert Arnoldi at N, drift at N').
    method : {"branch", "qz"}
        Without ``sigma``: ``"branch"`` follows the branch with α(0) = 0 (the kinematic-wave
        mode of Appendix B, which the paper finds to be the least stable) from k = 0 by
        continuation — fast; ``"qz"`` scans the whole spectrum by dense QZ — the global
        reference, seconds. With ``"branch"``, k > :data:`K_DIRECT` (= 1) is solved
        directly (QZ at k). Where the continuation loses the branch (its phase velocity
        inside the range of u0, near the continuum of the dilute top), the branch is
        followed again with the tail threshold relaxed (:func:`near_continuum_branch`,
        ``method = "branch (relaxed)"``, at this and every further N of the ladder); only
        where that does not reach k either, the solver falls back to the direct solve at
        k. A value on the branch is preferred to a direct solve's candidate as the flagged
        answer, except beyond ``policy.relaxed_k_max`` (0.1), where the branch lies in a
        band of critical-layer eigenvalues: there the branch is picked out of the band by
        its tail, and a resolved direct mode that drifts less and is at least as unstable
        replaces it (:func:`after_lost_branch`,
        :meth:`RejectionPolicy.direct_outranks_relaxed`); the further rungs are then
        solved directly. Below ``policy.relaxed_k_max``, while the relaxed value is rejected
        by the paper's tests, each rung also solves directly (dense QZ, then the candidate
        followed by shift-invert, :func:`_direct_candidate`), and a mode that passes both
        tests and is less damped is the answer. :attr:`Mode.method` says which method
        answered.
    policy : RejectionPolicy, optional
        Thresholds of the drift and tail tests and the resolution ladder (default: the
        paper's, §4.1).
    drift_tol, tail_tol, n_max : optional
        Overrides of the policy's fields of the same names.
    strict : bool
        False (default): when no mode passes the tests by N = ``n_max``, return the best
        candidate flagged ``physical = False`` (:attr:`Mode.converged`) with its drift and
        tail. True: raise :class:`ConvergenceError` instead.
    cache : OperatorCache, optional
        Where the operators come from.

    Raises
    ------
    ConvergenceError
        Only with ``strict=True``: no physical mode reaches the thresholds by N = ``n_max``.
    """
    # the branch solver lives in the module above this one (it tracks the modes judged here)
    k, kz = validate_k(k, "k"), validate_k(kz, "kz", signed=True)
    check_hydrodynamic_k(k, kz)
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol, n_max=n_max)
    if method not in ("branch", "qz"):
        raise ParameterError(
            f"method = {method!r}: choose 'branch' (continuation from k = 0) "
            "or 'qz' (dense scan of the whole spectrum)"
        )
    ns = [validate_n(n)] if n is not None else policy.ladder()
    how = "qz" if (method == "qz" or (sigma is None and math.hypot(k, kz) > K_DIRECT)) else method
    best: Mode | None = None
    lost = None
    seed: Mode | None = None  # direct candidate below the continuum (_direct_candidate)
    kk = math.hypot(k, kz)
    for nn in ns:
        mode: Mode | None
        if sigma is not None:
            try:
                mode = dataclasses.replace(
                    mode_near(flow, k, sigma, kz=kz, n=nn, policy=policy, cache=cache), method="shift"
                )
            except ConvergenceError:
                mode = None
        elif how == "qz":
            mode = direct_mode(flow, k, kz=kz, n=nn, policy=policy, cache=cache)
            if mode is not None and lost is not None:
                mode = dataclasses.replace(mode, method="qz (branch lost)", note=join_notes(lost, mode.note))
        else:
            mode = None
            if how == "branch":
                try:
                    mode = branch_mode(flow, k, kz=kz, n=nn, policy=policy, cache=cache)
                except ConvergenceError as exc:
                    # the continuation lost the branch: from now on followed with the tail
                    # threshold relaxed (near_continuum_branch), at every rung
                    lost, how = str(exc).split(" (theta")[0], "relaxed"
            if mode is None:
                # the dense spectrum (band search, direct mode) only at the last rung: below
                # it an unresolved relaxed value only leads to the next rung
                mode = after_lost_branch(
                    flow,
                    k,
                    kz=kz,
                    n=nn,
                    policy=policy,
                    cache=cache,
                    lost=lost or "",
                    check_direct=nn == ns[-1],
                )
                if mode is not None:
                    if mode.method != "branch (relaxed)":
                        # the branch has dissolved into the continuum: direct solves from now on
                        how = "qz"
                    elif not mode.physical and kk <= policy.relaxed_k_max:
                        # below the continuum: a resolved, less damped mode outranks the
                        # flagged relaxed value (RejectionPolicy.direct_outranks_relaxed)
                        seed = _direct_candidate(flow, k, kz, nn, seed, policy, cache)
                        mode = _outranked(mode, seed, kk, policy, f" at N = {nn}")
                else:
                    # not even the relaxed continuation reaches k: a direct solve at k
                    how = "qz"
                    mode = direct_mode(flow, k, kz=kz, n=nn, policy=policy, cache=cache)
                    if mode is not None:
                        mode = dataclasses.replace(
                            mode, method="qz (branch lost)", note=join_notes(lost or "", mode.note)
                        )
        if mode is not None and mode.physical:
            if (
                mode.method.startswith("qz")
                and mode.continuum_re > mode.alpha.real  # False when NaN
                and math.hypot(k, kz) > policy.relaxed_k_max
                and nn < (n_top := _top_check_n(ns))
            ):
                mode = _check_above_continuum(flow, k, kz, n_top, mode, policy, cache, lost or "")
            return mode
        if mode is not None and _better(mode, best, policy):
            best = mode
    if best is not None and not strict:
        return best
    what = (
        "no physical mode"
        if best is None
        else f"best candidate α = {best.alpha:.6g} with drift {best.drift:.1e}, tail {best.tail:.1e}"
    )
    raise ConvergenceError(
        f"least-stable mode at theta = {flow.theta:g}, nu0 = {flow.nu0:g}, k = {k:g}: "
        f"{what} (thresholds drift {policy.drift_tol:g}, tail {policy.tail_tol:g}) up to N = "
        f"{ns[-1]}; raise n_max or relax the thresholds"
    )


#: A direct candidate that drifts less than this between N and N' is followed to the next
#: rung by shift-invert near its eigenvalue instead of a new dense QZ (θ = 17.5°, ν0(0) =
#: 0.11, φ = 0.075, Φ = 0.35, k = 0.005: the candidate drifts 1.2e-6, 2.4e-7, 2.8e-8 at
#: N = 80, 100, 125; QZ costs 0.6, 1.2, 2.4 s there and 23 s at N = 256).
SEED_DRIFT = 1e-4


def _direct_candidate(flow, k, kz, n, seed: Mode | None, policy, cache) -> Mode | None:
    """The least-stable mode of a direct solve at (k, kz) and N, for
    :func:`least_stable` below the continuum after the branch was lost: the previous rung's
    candidate ``seed`` followed by shift-invert near its eigenvalue when it was converging
    (drift below :data:`SEED_DRIFT`), else dense QZ (:func:`direct_mode`)."""
    if seed is not None and seed.drift < SEED_DRIFT:
        try:
            return mode_near(flow, k, seed.alpha, kz=kz, n=n, policy=policy, cache=cache)
        except ConvergenceError:
            pass
    return direct_mode(flow, k, kz=kz, n=n, policy=policy, cache=cache)


def _direct_ladder(flow: SteadyFlow, k: float, policy: RejectionPolicy, cache) -> Mode:
    """The least-stable mode at k ≤ ``policy.relaxed_k_max`` solved directly along the
    policy's ladder, for :func:`dispersion` where the branch was lost and the relaxed
    continuation does not reach k: dense QZ at the first rung (the whole spectrum), then the
    candidate followed to each further rung by shift-invert near its eigenvalue while it
    converges (:func:`_direct_candidate`, as :func:`least_stable` does below the continuum),
    instead of a dense QZ at every rung. Returns the first mode that passes the paper's
    tests, else the best candidate (:func:`_better`), flagged; where no rung gives one,
    :func:`least_stable` with ``method="qz"``.

    θ = 21.293°, ν0(0) = 0.0506, φ = 0.0878, Φ = 0.337, e_p = 0.685 (the branch lost near
    k = 4.5e-4, every k up to 0.02 solved directly): the k from 0.0127 on climb to N = 100 …
    256, where a QZ costs 1.2 … 20 s; ``chuteflow dispersion`` took 274 s, 260 s of them in
    163 QZ decompositions.
    """
    best = seed = None
    for nn in policy.ladder():
        seed = _direct_candidate(flow, k, 0.0, nn, seed, policy, cache)
        if seed is None:
            continue
        if seed.physical:
            return seed
        if _better(seed, best, policy):
            best = seed
    if best is not None:
        return best
    return least_stable(flow, k, method="qz", policy=policy, cache=cache)


def _better(mode: Mode, best: Mode | None, policy: RejectionPolicy) -> bool:
    """Whether ``mode`` replaces ``best`` as the flagged answer of :func:`least_stable`: a
    value on the branch (tracked, also with the relaxed tail threshold) beats a direct
    solve's candidate, which is not known to be the branch, except where the policy ranks a
    resolved direct mode above a relaxed value
    (:meth:`RejectionPolicy.direct_outranks_relaxed`); among equals, the smaller
    :func:`mode_score` (nearer to passing the paper's tests; later N on ties)."""
    if best is None:
        return True
    on_branch, best_on_branch = mode.method.startswith("branch"), best.method.startswith("branch")
    if on_branch != best_on_branch:
        branch, other = (mode, best) if on_branch else (best, mode)
        if branch.method == "branch (relaxed)" and policy.direct_outranks_relaxed(
            math.hypot(branch.k, branch.kz),
            other.alpha.real,
            other.drift,
            other.tail,
            branch.alpha.real,
            branch.drift,
        ):
            return not on_branch
        return on_branch
    return mode_score(mode, policy) <= mode_score(best, policy)


def choose_n(
    flow: SteadyFlow,
    k: float,
    *,
    kz: float = 0.0,
    policy: RejectionPolicy | None = None,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    n_max: int | None = None,
) -> int:
    """Smallest N of the policy's ladder (80, 100, 125, …) at which the least-stable
    (α(0) = 0 branch) mode at (k, kz) passes the drift and tail tests."""
    return least_stable(
        flow, k, kz=kz, policy=policy, drift_tol=drift_tol, tail_tol=tail_tol, n_max=n_max, strict=True
    ).n


def operator(flow: SteadyFlow, k: float, n: int | None = None, kz: float = 0.0) -> Pencil:
    """The pencil A V = α B V of ``flow`` at wavenumber ``k`` (and ``kz``) on N = ``n``.

    ``n=None`` uses :func:`chuteflow.stability.choose_n` (resolution from the convergence
    estimate of the least-stable mode).
    """
    if n is None:
        n = choose_n(flow, k)
    return StabilityOperator(flow, n, three_d=bool(kz)).pencil(k, kz)
