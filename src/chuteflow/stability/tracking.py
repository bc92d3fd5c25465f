"""The α(0) = 0 branch tracked from k = 0 (paper §4.2, Appendix B).

At k = 0 the mass-conservation mode has α = 0 exactly: its right null vector is the
tangent ∂X0/∂β of the steady family and its left null vector the total-mass functional
(Appendix B). The mass balance then gives α ≈ α1 k (eq. B 11), which seeds the
continuation; every later step predicts α from the previous points (quadratic
extrapolation) and takes the eigenvalue nearest the prediction by shift-invert. A step is
accepted when the answer lies within a quarter of the step from the prediction and its
eigenvector is resolved (Chebyshev tail); otherwise it is halved, so the branch is not lost
to the near-neutral continuum α ≈ −ik u0(y) of the dilute top, which crowds it at small k.
Each point is then checked at N' = round(0.8 N) (drift) and by the paper's tail test; N is
raised along the branch when a point fails. The continuation runs on
:func:`chuteflow.continuation.continue_to` along any ray k = s·(k̂x, k̂z).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..continuation import StepRules, Trial, continue_to
from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow
from .eigen import ShiftInvert
from .modes import (
    Mode,
    OperatorCache,
    drift_of,
    interp_vector,
    make_mode,
    nearest_eigenpair,
    resolve_policy,
    stability_operator,
    tail,
)
from .operator import StabilityOperator, validate_n
from .policy import RejectionPolicy, TrackingPolicy


def _growth(ratio: float | None) -> float:
    """Step factor after an accepted step whose predictor missed by ``ratio`` of the step:
    ×3 while it hits well, ×1.5 when fair, held when off by more than 5 %."""
    assert ratio is not None  # every accepted step of the tracker reports its miss
    return 3.0 if ratio < 0.02 else 1.5 if ratio < 0.05 else 1.0


def _track_rules(max_halvings: int, s_target: float = 0.0, min_step: float = 1e-9) -> StepRules:
    """Retry rules of the branch in k (:func:`chuteflow.continuation.continue_to`): steps
    grow by :func:`_growth`, at most ×3 in k (a step at most twice the k reached), halved
    when rejected, at most ``max_halvings`` times per step, and never below ``min_step`` ×
    ``s_target`` (``TrackingPolicy.min_step``)."""
    return StepRules(
        grow=_growth,
        shrink=0.5,
        max_step_ratio=2.0,
        max_halvings=max_halvings,
        min_step=min_step * s_target,
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


def _step_root(op: StabilityOperator, direction, tracking: TrackingPolicy) -> _Steps:
    """The root of the memoised steps from k = 0 along ``direction`` on ``op`` (one tree per
    number of ARPACK restarts, which the solves depend on; at most
    ``tracking.memo_bytes`` of eigenvectors per operator)."""
    roots = op.memo.setdefault("branch_steps", {})
    key = (direction, tracking.restarts)
    if key not in roots:
        budget = op.memo.setdefault("branch_steps_budget", [tracking.memo_bytes])
        roots[key] = _Steps(budget)
    return roots[key]


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
        self._node: _Steps | None = _step_root(op, self.direction, self.policy.tracking)
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
        knobs = self.policy.tracking
        pred = self._predict(s)
        node = self._node  # None: not a continuation from k = 0, nothing to share
        tried = None if node is None else node.tried.get(s)
        if tried is None:
            try:
                alpha, w = nearest_eigenpair(
                    self._pencil(s), pred, v0=v_prev, restarts=self.policy.tracking.restarts
                )
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
            s - s_prev <= knobs.first_step_min or abs(pred - a_prev) < knobs.first_predictor_min
        ):
            # from k = 0 the predictor α1 k may vanish (k along z: no advection), or miss at
            # the shortest first step; the nearest resolved eigenvector is the branch, as
            # the continuum fails the tail. Above it the first step must hit like any other
            # (first_step_min: the next predictor's slope at k = 0 is α1)
            ratio = min(ratio, 0.25)
        if ratio > 0.25:
            self._misses.append(ratio)
            m = self._misses[-knobs.stall_rejections :]
            if len(m) == knobs.stall_rejections and all(b > knobs.stall_factor * a for a, b in zip(m, m[1:])):
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
            if t_a > tol and t < knobs.crossing_jump * t_a:
                # (only from k = 0, whose null vector is accepted by construction)
                self._final_at = s_prev
                self._final = (
                    f"its eigenvector is not resolved at k = {s_prev:.4g} (Chebyshev tail "
                    f"{t_a:.1e} above the tracking threshold {tol:g})"
                )
            elif t_a > knobs.crossing_near * tol and t < knobs.crossing_jump * t_a:
                # the branch's own tail rises through the threshold between s_prev and s:
                # log-linear estimate of the crossing (TrackingPolicy.crossing_near)
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
            h = self.policy.tracking.first_step if s_last == 0.0 else self._h
            res = continue_to(
                self._solve,
                s_last,
                s_last,
                s_target,
                _track_rules(max_halvings, s_target, self.policy.tracking.min_step),
                h=h,
                origin=0.0,
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
    retrack: bool = True,
) -> Mode:
    """The mode of the α(0) = 0 branch at (k, kz), tracked from k = 0, at resolution N.

    The continuation runs on a coarse grid (N_c = 48, an LU ~10× cheaper), whose eigenvalue
    (accurate to ~1e-4 relative) is the shift of a single solve at N, followed by the drift
    check at N'. If the coarse branch is lost, or the fine solve does not land on a resolved
    eigenvector close to it, the continuation is redone at N. ``n`` defaults to
    ``policy.n_start``; the mode is judged by ``policy`` (``drift_tol``, ``tail_tol``:
    overrides of its thresholds). With ``retrack=False`` the continuation is never redone at
    N: a fine solve that lands close to the coarse branch with an eigenvector below the
    tracking threshold is returned even where it fails the paper's tests (the branch, not
    yet resolved at N: the next rung of the ladder resolves it), and where the coarse branch
    is lost or the fine solve leaves it, :class:`ConvergenceError` is raised — what the
    resolver does in 3D, where its search is the global check (P1, (0.002, 0.02): three
    continuations at N = 80, 100, 125 took 4.4 of 6.3 s).
    """
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol)
    n = validate_n(policy.n_start if n is None else n)
    kk = math.hypot(k, kz)
    direction = (k, kz) if kk else (1.0, 0.0)
    coarse_n = policy.tracking.coarse_n
    why = f"the coarse branch (N = {coarse_n}) does not continue to N = {n}"
    if kk > 0 and n > coarse_n + 16:
        try:
            coarse = BranchTracker(
                flow, coarse_n, direction=direction, policy=policy, n_max=coarse_n, cache=cache
            )
            a_c, w_c = coarse.advance(kk)
            op = stability_operator(flow, n, coarse.three_d, cache=cache)
            pencil = op.pencil(k, kz)
            alpha, w = nearest_eigenpair(pencil, a_c, v0=interp_vector(w_c, len(op.fields), coarse_n, n))
            if abs(alpha - a_c) < 1e-2 * abs(a_c):
                drift, n2 = drift_of(flow, alpha, w, n, k, kz, coarse.three_d, cache=cache)
                mode = make_mode(pencil, alpha, w, drift, n2, policy)
                if mode.physical or (not retrack and mode.tail < policy.track_tail_tol):
                    return mode
        except ConvergenceError as exc:
            why = str(exc).split(" (theta")[0]
        if not retrack:
            # no continuation at N: the caller's global search takes over (the resolver in
            # 3D; a flow at θ = 19.537°, ν0(0) = 0.0153, φ = 0.085, Φ = 0.327, (k_x, k_z) =
            # (0.00913, 0.042): 413 continuation steps at N = 80 … 256, 47 of 52 s)
            raise ConvergenceError(f"{why} (theta = {flow.theta:g}, nu0 = {flow.nu0:g}, N = {n})")
    tr = BranchTracker(flow, n, direction=direction, policy=policy, n_max=n, cache=cache)
    return tr.mode(kk)
