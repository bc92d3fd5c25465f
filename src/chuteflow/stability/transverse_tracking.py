"""The α(0) = 0 branch followed across the slope (k_x = 0) in k_z (paper §5.3).

The fast path of the transverse analysis: :class:`TransverseTracker` starts from the k = 0
null vector ∂X0/∂β, predicts α ≈ α2z k_z² (the perturbation theory of
:mod:`chuteflow.longwave.spanwise`) for the first steps and by quadratic extrapolation of
the last three points after that, and solves each step by real inverse iteration (one real
LU of A' − σB' per k_z, the pencil made real by ŵ → iŵ, :mod:`chuteflow.stability.realform`).
The steps are chosen by :func:`chuteflow.continuation.continue_to`: the first one from k = 0
(:attr:`TransverseTrackingPolicy.first_step`) halved in k_z while rejected, every later one
a ratio :attr:`~TransverseTrackingPolicy.max_ratio` in k_z halved in ln k_z while rejected.
At P1 the branch rises to α ~ 6e-5 at k_z ~ 2e-3, falls back through the near-neutral
continuum of the dilute top at k_z ≈ 3.25e-3 and is lost in it (its eigenvector is no longer
resolved); the least-stable physical mode at larger k_z is another one
(:func:`chuteflow.stability.transverse_dispersion` with ``beyond=True``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..continuation import StepRules, Trial, continue_to
from ..steady import SteadyFlow
from .modes import Mode, OperatorCache, check_n, interp_vector, make_mode, stability_operator, tail
from .policy import DEFAULT_POLICY, RejectionPolicy
from .realform import _inverse_iteration, _real_lu, _real_null_vector, _real_pencil

__all__ = ["DEFAULT_TRANSVERSE", "TransverseTracker", "TransverseTrackingPolicy"]


@dataclass(frozen=True)
class TransverseTrackingPolicy:
    """Tuning of the transverse branch (:class:`TransverseTracker`) and of the candidate
    modes followed past it (:func:`chuteflow.stability.transverse_dispersion`, ``beyond``).

    Attributes
    ----------
    first_step : float
        The first step from k_z = 0 (halved while rejected).
    max_ratio : float
        Largest step ratio k_z(next)/k_z(last) of the continuation (halved in ln k_z while
        rejected, back to this ratio after each accepted step).
    max_halvings : int
        Tries of one step (the first and its halvings) before the branch is called lost.
        The branch is real and its step's acceptance (a miss below ``miss_fraction`` of the
        predicted change plus ``miss_rtol`` |α|) tightens where Re α is flat, at its
        maximum: the miss falls with the step and the threshold to ``miss_rtol`` |α|, so
        short steps pass. With 6 tries, flows a round-off apart were followed over P1's
        maximum (k_z ≈ 1.9e-3) or "lost" there; 10 cross it whatever the round-off
        (tests/stability/test_transverse.py::test_p1_branch_followed_past_its_maximum_whatever_the_round_off).
    miss_fraction, miss_rtol, miss_atol : float
        A step is accepted when |α − prediction| ≤ ``miss_fraction`` |prediction − α_last| +
        ``miss_rtol`` |prediction| + ``miss_atol`` (and its eigenvector is resolved:
        Chebyshev tail below ``RejectionPolicy.track_tail_tol``).
    seed_n : int
        Resolution of the coarse dense scan that seeds the candidate modes past the branch.
    candidates : int
        How many candidate modes are followed past the branch.
    seed_match : float
        A seed (N = ``seed_n``) within this relative distance of an eigenvalue already
        followed at N is taken to be that eigenvalue and is not solved again (P1, k_z =
        0.01–3: resolved seeds differ from their N = 80 eigenvalues by 6e-8 to 1.1e-3
        relative; two distinct eigenvalues that close would rank the same to that accuracy).
    seed_shift : float
        Shift of the dense shift-invert that seeds the candidates past the branch
        (:func:`chuteflow.stability.realform._seed_spectrum`): to the right of the decaying
        spectrum there.
    reseed_ratio : float
        Past the branch the candidates are re-seeded by a coarse dense scan every time k_z
        has grown by this factor (modes resolved only at larger k_z join the race).
    """

    first_step: float = 1e-5
    max_ratio: float = 1.6
    max_halvings: int = 10
    miss_fraction: float = 0.25
    miss_rtol: float = 1e-3
    miss_atol: float = 1e-14
    seed_n: int = 48
    candidates: int = 2
    seed_match: float = 2e-3
    seed_shift: float = 0.5
    reseed_ratio: float = 2.0

    def __post_init__(self):
        if not self.max_ratio > 1 or not self.first_step > 0:
            raise ValueError("TransverseTrackingPolicy: need max_ratio > 1 and first_step > 0")
        if self.max_halvings < 1 or self.candidates < 1 or self.seed_n < 8:
            raise ValueError("TransverseTrackingPolicy: need max_halvings ≥ 1, candidates ≥ 1, seed_n ≥ 8")


#: The default tuning of the transverse branch.
DEFAULT_TRANSVERSE = TransverseTrackingPolicy()


@dataclass(frozen=True, eq=False)
class _Point:
    """One tracked point: k_z, α, the real-form eigenvector at N and N."""

    kz: float
    alpha: complex
    vec: np.ndarray = field(repr=False)
    n: int


class TransverseTracker:
    """Continuation of the α(0) = 0 branch across the slope (k_x = 0) in k_z ≥ 0.

    The fast path of the transverse analysis (module docstring): real arithmetic (the k_x = 0
    pencil made real by ŵ → iŵ, :func:`~chuteflow.stability.realform.real_form`), one real
    LU and a few solves per step, the steps chosen by
    :func:`chuteflow.continuation.continue_to`.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    alpha2z : float, optional
        α2z of α(0, k_z) ≈ α2z k_z² (:func:`chuteflow.longwave.transverse_longwave`), the
        predictor of the first steps; without it the first step takes the resolved eigenvalue
        nearest 0.
    n : int, optional
        Resolution N (default ``policy.n_start``).
    policy : RejectionPolicy
        Drift and tail thresholds (the branch is lost when its eigenvector's tail exceeds
        ``policy.track_tail_tol``) and the resolution ladder.
    cache : OperatorCache, optional
        Where the operators come from.
    max_ratio : float, optional
        Largest step ratio k_z(next)/k_z(last) of the continuation (default
        ``tracking.max_ratio``).
    tracking : TransverseTrackingPolicy, optional
        The continuation's tuning (default :data:`DEFAULT_TRANSVERSE`).
    """

    def __init__(
        self,
        flow: SteadyFlow,
        *,
        alpha2z: float | None = None,
        n: int | None = None,
        policy: RejectionPolicy = DEFAULT_POLICY,
        cache: OperatorCache | None = None,
        max_ratio: float | None = None,
        tracking: TransverseTrackingPolicy | None = None,
    ):
        tracking = tracking or DEFAULT_TRANSVERSE
        if max_ratio is not None:
            tracking = dataclasses.replace(tracking, max_ratio=float(max_ratio))
        self.flow, self.policy, self.cache, self.tracking = flow, policy, cache, tracking
        self.alpha2z = None if alpha2z is None else float(alpha2z)
        self.n = int(policy.n_start if n is None else n)
        self.max_ratio = tracking.max_ratio
        w = _real_null_vector(self._op(self.n))  # eigenvector of the equilibrated pencil at k = 0
        w = w / w[np.argmax(np.abs(w))]
        self.history: list[_Point] = [_Point(0.0, 0.0, np.ascontiguousarray(w.real), self.n)]
        self.lost_at: float | None = None

    def _op(self, n):
        return stability_operator(self.flow, n, True, cache=self.cache)

    def _real(self, n, kz):
        return _real_pencil(self._op(n), kz)

    def _predict(self, kz: float) -> float:
        h = self.history
        if len(h) == 1:
            return self.alpha2z * kz**2 if self.alpha2z is not None else 0.0
        if len(h) == 2 and self.alpha2z is None:
            # α ∝ k_z² through the first point (no O(k_z) term across the slope)
            return h[1].alpha.real * (kz / h[1].kz) ** 2
        if len(h) == 2 and self.alpha2z is not None:
            # α2z k² + c3 k³ through the first point (the next term is O(|k_z|³))
            k1, a1 = h[1].kz, h[1].alpha.real
            c3 = (a1 - self.alpha2z * k1**2) / k1**3
            return self.alpha2z * kz**2 + c3 * kz**3
        pts = h[-3:] if len(h) >= 3 else h
        xs = [p.kz for p in pts]
        ys = [p.alpha.real for p in pts]
        out = 0.0
        for i, (xi, yi) in enumerate(zip(xs, ys)):
            li = 1.0
            for j, xj in enumerate(xs):
                if j != i:
                    li *= (kz - xj) / (xi - xj)
            out += yi * li
        return out

    def _eigenpair(self, kz, sigma, v0, n=None):
        """Eigenpair nearest σ at (0, k_z) by real inverse iteration from v0, with its tail:
        (α, real-form vector, pencil, s, tail) or None."""
        n = self.n if n is None else n
        p, A, bd, s = self._real(n, kz)
        try:
            lu = _real_lu(A, bd, sigma)
        except (ValueError, np.linalg.LinAlgError):  # pragma: no cover - exact hit
            sigma = sigma * (1 + 1e-10) + 1e-14
            lu = _real_lu(A, bd, sigma)
        found = _inverse_iteration(lu, bd, sigma, v0)
        if found is None:
            return None
        alpha, v = found
        t = tail(p.unscale(s * v), len(p.fields), self.policy.tail_terms)
        return alpha, v, p, s, t

    def _solve(self, last: _Point, kz: float) -> Trial:
        """One continuation attempt at k_z from the last accepted point: accepted (the new
        :class:`_Point`, which joins the history) when the eigenvalue nearest the prediction
        lies close to it and its eigenvector is resolved; a failure's value is k_z."""
        pred = self._predict(kz)
        res = self._eigenpair(kz, pred, last.vec)
        if res is None:
            return Trial(False, kz)
        alpha, v, _, _, t = res
        knobs = self.tracking
        miss = abs(alpha - pred)
        if len(self.history) > 1 or self.alpha2z is not None:
            bound = knobs.miss_fraction * abs(pred - last.alpha.real) + knobs.miss_rtol * abs(pred)
            if miss > bound + knobs.miss_atol:
                return Trial(False, kz)
        if t > self.policy.track_tail_tol:
            return Trial(False, kz)
        pt = _Point(float(kz), complex(alpha), v, self.n)
        self.history.append(pt)
        return Trial(True, pt)

    def _solve_log(self, kz_target: float, s_target: float, tries: int):
        """:meth:`_solve` in the parameter s = ln k_z. The k_z tried from a point k0 are
        t0 = min(k_z target, k0 × max_ratio) and its halvings in ln k_z, t_{j+1} = √(k0 t_j):
        the parameter s of :func:`~chuteflow.continuation.continue_to` stands for the one
        whose logarithm it is (to round-off), computed by those products, so that the
        branch's points do not depend on the round-off of ln and exp."""

        def solve(last, s):
            if s == s_target:
                return self._solve(last, kz_target)
            t = min(kz_target, last.kz * self.max_ratio)
            for _ in range(tries):
                if abs(math.log(t) - s) <= 1e-12 * max(1.0, abs(s)):
                    return self._solve(last, t)
                t = math.sqrt(last.kz * t)
            return self._solve(last, math.exp(s))  # pragma: no cover - not a step of ours

        return solve

    def advance(self, kz: float, max_halvings: int | None = None) -> _Point | None:
        """Continue the branch to k_z (≥ the last point); None once it is lost (the reason:
        :attr:`lost_at`, the k_z where the continuation could not step on).

        The steps (:func:`chuteflow.continuation.continue_to`): from k_z = 0 the first one is
        ``tracking.first_step`` (at most k_z), halved while rejected; after it each step is at
        most the ratio ``max_ratio`` in k_z, halved in ln k_z while rejected and back to that
        ratio after each accepted step. A step is tried at most ``max_halvings`` times (default
        ``tracking.max_halvings``; see :class:`TransverseTrackingPolicy`)."""
        if self.lost_at is not None and kz >= self.lost_at:
            return None
        tries = self.tracking.max_halvings if max_halvings is None else int(max_halvings)
        k0 = self.history[-1].kz
        if k0 < kz and k0 == 0:
            # from k = 0: one step, tracking.first_step (at most k_z), halved while rejected;
            # the continuation ends at its first accepted point (the steps after it are in
            # ln k_z, below: a final failure stops continue_to there)
            def first(last, s):
                return Trial(False, s, final=True) if len(self.history) > 1 else self._solve(last, s)

            target = min(kz, self.tracking.first_step)
            rules = StepRules(shrink=0.5, max_halvings=tries - 1)
            res = continue_to(first, self.history[-1], 0.0, target, rules)
            if len(self.history) == 1:
                self.lost_at = float(0.5 * res.steps[-1].value)
                return None
        k0 = self.history[-1].kz
        if k0 < kz:
            # on in ln k_z: steps of ln(max_ratio), halved while rejected; a step lands on k_z
            # itself when k_z ≤ max_ratio × the last point up to round-off of the logarithms
            # (~1e-14: no second step of that size to it)
            s0, s1 = math.log(k0), math.log(kz)
            step = math.log(self.max_ratio) * (1.0 + 1e-13)
            rules = StepRules(grow=math.inf, shrink=0.5, max_step=step, max_halvings=tries - 1)
            res = continue_to(self._solve_log(kz, s1, tries), self.history[-1], s0, s1, rules, h=step)
            if not res.reached:
                # the step the continuation would try next, halved in ln k_z
                self.lost_at = float(math.sqrt(res.state.kz * res.steps[-1].value))
                return None
        return self.history[-1] if self.history[-1].kz == kz else self._near(kz)

    def _near(self, kz):
        for p in reversed(self.history):
            if p.kz == kz:
                return p
        return None  # pragma: no cover

    def at(self, kz: float) -> complex | None:
        """α of the branch at k_z inside the tracked range, solved from the nearest tracked
        point (the history is not changed): for bracketed searches. None if it does not land
        on a resolved eigenvector near the interpolated prediction."""
        pt = self.point_at(kz)
        return None if pt is None else pt.alpha

    def point_at(self, kz: float) -> _Point | None:
        """The branch's point at k_z inside the tracked range (as :meth:`at`, with its
        eigenvector, for :meth:`judge`); the history is not changed."""
        h = [p for p in self.history if p.kz > 0]
        if not h or kz > h[-1].kz * self.max_ratio:
            return None
        i = int(np.argmin([abs(math.log(p.kz / kz)) for p in h]))
        j = max(0, min(len(h) - 3, i - 1))
        pts = h[j : j + 3]
        xs, ys = [p.kz for p in pts], [p.alpha.real for p in pts]
        pred = float(np.polyval(np.polyfit(xs, ys, len(xs) - 1), kz)) if len(xs) > 1 else ys[0]
        res = self._eigenpair(kz, pred, h[i].vec, n=h[i].n)
        if res is None or res[4] > self.policy.track_tail_tol:
            return None
        return _Point(float(kz), complex(res[0]), res[1], h[i].n)

    def mode(self, kz: float) -> Mode | None:
        """The tracked mode at k_z with its drift (N' = 0.8 N) and tail, N raised along the
        policy's ladder while it is not physical; None where the branch is lost."""
        pt = self.advance(kz)
        if pt is None:
            return None
        return self.judge(pt)

    def judge(self, pt: _Point) -> Mode:
        """The mode of a tracked point (from :meth:`advance` or :meth:`point_at`) with its
        drift |α(N) − α(N')| (N' = 0.8 N) and tail, N raised along the policy's ladder while
        it is not physical."""
        nf = 5
        alpha, v, n = pt.alpha.real, pt.vec, pt.n
        mode = None
        for nn in self.policy.ladder(n):
            if nn != n:
                res = self._eigenpair(pt.kz, alpha, interp_vector(v, nf, n, nn), n=nn)
                if res is None:
                    break
                alpha, v, n = res[0], res[1], nn
            p, _, _, s = self._real(n, pt.kz)
            n2 = check_n(n)
            res2 = self._eigenpair(pt.kz, alpha, interp_vector(v, nf, n, n2), n=n2)
            drift = abs(res2[0] - alpha) if res2 is not None else math.inf
            mode = dataclasses.replace(make_mode(p, alpha, s * v, drift, n2, self.policy), method="branch")
            if mode.physical:
                break
        return mode  # type: ignore[return-value]
