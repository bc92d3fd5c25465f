"""When a computed eigenpair is accepted: one rejection policy for every solver (paper §4.1).

A :class:`RejectionPolicy` holds the paper's two tests of a physical mode — the *drift* of
the eigenvalue between the resolutions N and N' = round(0.8 N), and the *tail* of its
eigenvector (the highest ``tail_terms`` Chebyshev coefficients) — with their thresholds, and
the ladder of resolutions N tried until a mode passes them. Every function of
:mod:`chuteflow.stability` that judges modes takes it as ``policy=`` (default
:data:`DEFAULT_POLICY`, the paper's values).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..errors import ParameterError
from .operator import validate_n

__all__ = ["DEFAULT_POLICY", "RejectionPolicy", "SearchPolicy", "TrackingPolicy"]


def _require(owner: str, policy, names, ok, need: str, *, integer: bool = False) -> None:
    """:class:`ParameterError` naming the first field of ``names`` whose value is not a
    number (an integer with ``integer``) for which ``ok(value)`` holds."""
    kind = int if integer else (int, float)
    for name in names:
        v = getattr(policy, name)
        if isinstance(v, bool) or not (isinstance(v, kind) and ok(v)):
            raise ParameterError(f"{owner} {name} = {v!r}: need {need}")


@dataclass(frozen=True)
class SearchPolicy:
    """How the mode resolver looks for modes above an answer (:mod:`.resolver`).

    The contract of "least stable" (docs/numerics.md) is the largest Re α among the modes
    that pass the drift and tail tests under refinement. After the tracked or direct answer,
    the resolver solves the whole spectrum once (one dense eigensolve) at the coarse resolution ``n``
    on the grid of the question, and every eigenvalue above the answer whose eigenvector is
    nearly resolved there (Chebyshev tail below ``candidate_tail``) is a candidate; each is
    followed up the ladder ``n``, round(1.25 n), … by shift-invert until it is decided.

    Parameters
    ----------
    n : int
        Resolution of the one dense solve (48: a 245 × 245 pencil in 3D, 0.1–0.2 s; at P5,
        (k_x, k_z) = (0.002, 0.02), the resolved mode −0.00709 − 0.0179i has tail 2e-6 there
        on the mapped grid while the continuum of the dilute top has tails ≥ 7e-4).
    candidate_tail : float
        Largest tail at ``n`` of a candidate. The near-neutral continuum of the dilute top
        has tails ≥ 7e-4 there (P5, Q1 at (0.002, 0.02), mapped grid); modes that the
        ladder resolves only at N ≈ 150–250 can have 3e-4 (a flow at θ = 21.6°, ν0(0) =
        0.0143: −0.434 − 0.131i, tail 3e-4 at N = 48, 1e-10 at 256), and a critical-layer
        mode 9e-5 (Q1, (0.002, 0.02)).
    max_candidates : int
        Most candidates followed; beyond, the ones left above the answer stay undecided (the
        answer is then flagged).
    stall : float
        A candidate is decided not to be a mode (the continuum of the dilute top, or a
        spurious eigenvalue) when its eigenvector's tail, still above the tail threshold,
        falls by less than this factor over three rungs (N = 1.25³ N' ≈ 2 N'). A mode's tail
        decays fast with N, also where it converges only algebraically (a critical layer:
        Q1, (k_x, k_z) = (0.002, 0.02), −0.00677 − 0.00798i, tails 9e-5, 5e-5, 3e-5, 2e-5,
        7e-6, 3e-6, 1e-6, 2e-7 at N = 48, 60, …, 231: at most 0.22 over three rungs), while
        the near-neutral continuum's tails fall as ~1/N (P5, (0.002, 0.02): 1e-3, 8e-4,
        6e-4, 5e-4, 4e-4 …, 0.5 over three rungs) and the band of eigenvalues around it
        keeps tails of 1e-4 … 2e-5 (0.5 … 1). Its drift is no criterion: the continuum's is
        ~1e-9, and the critical-layer mode's drifts are 3e-4, 2e-4, 3e-4, 3e-4 up to N = 94
        before they fall. The rule judges only tails above the tracker's threshold
        (``track_tail_tol``): a mode beside the continuum converges slowly at first
        (θ = 16.648°, ν0(0) = 0.0192, φ = 0.0684, Φ = 0.388, (0.00615, 0.006292): tails
        2.1e-5, 1.4e-5, 8.0e-6, 8.4e-6 at N = 48 … 94, 0.40 over three rungs, then 4e-6,
        1.4e-6, 1.5e-7 at N = 118, 148, 231), as fast as a band member of an unresolved
        band falls at times (16.5°, 0.13, φ = 0.08, Φ = 0.30, k = 0.005: 3.4e-4 … 1.5e-4,
        0.44); their levels differ tenfold. Nor does it judge a candidate whose eigenvalue
        converges — its drift falling at every rung, fivefold over three, from well above
        the drift threshold — while its tail falls at every rung
        (:data:`~chuteflow.stability.resolver.CONVERGING_DRIFT_FALL`).
    hopeless : float
        A candidate whose tail fell at each of the last two rungs and whose drift,
        extrapolated to the top of the ladder at its own rate of
        fall or at ``fastest_fall`` a rung (the faster), stays above ``hopeless`` × the drift
        threshold is left undecided at once: the ladder cannot decide it (Q1, (0.002, 0.02):
        a critical-layer mode with drifts 3e-4, 2e-4, 3e-4, 3e-4, 2e-4, 4e-5 at N = 48 …
        148, 8e-6 at 256).
    fastest_fall : float
        See ``hopeless``.
    jump : float
        A shift-invert solve that lands farther than ``jump`` × max(|α|, 1e-3) from the
        candidate followed has lost it: no eigenvalue continues it at that N (spurious).
    """

    n: int = 48
    candidate_tail: float = 5e-4
    max_candidates: int = 8
    stall: float = 0.35
    hopeless: float = 100.0
    fastest_fall: float = 0.25
    jump: float = 0.2

    def __post_init__(self):
        try:
            object.__setattr__(self, "n", validate_n(self.n))
        except ParameterError as exc:
            raise ParameterError(f"search n: {exc}") from None
        _require("search", self, ("hopeless",), lambda v: v >= 1, "a number >= 1")
        _require(
            "search",
            self,
            ("candidate_tail", "stall", "jump", "fastest_fall"),
            lambda v: 0 < v < 1,
            "a number in (0, 1)",
        )
        _require("search", self, ("max_candidates",), lambda v: v >= 0, "an integer >= 0", integer=True)

    def ladder(self, n_max: int, growth: float) -> list[int]:
        """The rungs a candidate is followed on: ``n``, round(``growth`` n), … up to ``n_max``."""
        out = [min(self.n, n_max)]
        while out[-1] < n_max:
            out.append(min(n_max, round(out[-1] * growth)))
        return out


@dataclass(frozen=True)
class TrackingPolicy:
    """How the α(0) = 0 branch is followed from k = 0 and what replaces it where it is lost
    (:mod:`.tracking`, :mod:`.lost`, :mod:`.resolver`): the tuning of the continuation, its
    give-up rules and the fallbacks, with the measurements that chose each value. A field of
    :class:`RejectionPolicy` (``policy.tracking``); change one with
    ``DEFAULT_POLICY.replace(tracking=TrackingPolicy(coarse_n=64))``.

    Parameters
    ----------
    first_step : float
        First continuation step from k = 0.
    first_step_min : float
        Smallest first step that must pass the predictor test. From k = 0 the
        predictor is α1 k (eq. (B 2)), good while |α2| k² ≪ |α1| k. Where the k²
        regime is narrower than ``first_step`` the first step is halved until α1 k
        predicts it (θ = 16.475°, ν0(0) = 0.02, φ = 0.05: α = 9.86e-5 + 9.95e-5i at
        k = 1e-5 against α1 k = 1.94e-4i, the k² regime ends near k ~ 1e-6);
        accepting the first point off the prediction left the next predictor (the
        quadratic with slope α1 at k = 0) with the wrong slope, every shorter step
        missed by the same 41 % of the step, and the branch was "lost" at k = 1e-5.
        Below this step (1e-5/2¹⁰ ≈ 1e-8), or where α1 = 0 (a wavevector along z: no
        advection), the nearest resolved eigenvector is accepted as before.
    first_predictor_min : float
        |α1| k below this is no predictor: the eigenvalue's round-off near α = 0 is
        ~1e-12.
    coarse_n : int
        Resolution of the coarse continuation that seeds single-k solves.
    min_step : float
        Smallest continuation step of the branch tracker, relative to the wavenumber
        it heads for. A step h moves α by ~|dα/dk| h ~ |α| h/k; below h = 1e-9 k
        that is ~1e-9 |α|, the eigenvalue's own round-off (~1e-12 absolute near the
        continuum, |α| ≳ 1e-4 on the sweeps' k grid), so the acceptance test (miss <
        a quarter of the step) measures round-off. Where the branch meets another
        eigenvalue (an exceptional point k*, dα/dk infinite) every step across k* is
        rejected and accepted ever shorter steps creep up to it: at θ = 14.75°,
        ν0(0) = 0.21, φ = 0.05 the tracker went down to steps of 4e-13 k, 352
        rejected steps in all (7.7 s of the growth metric's 12.4 s) before it gave
        up; 217 (5.3 s) with this bound. The first step's 16 halvings (1e-5/2¹⁶)
        stay above it for every k ≤ 0.1.
    crossing_near : float
        The tail test's crossing rule (the tracker's step): a step rejected by the
        tail alone, its eigenvalue on the prediction, from an accepted point whose
        tail is above ``crossing_near`` × the threshold, with a tail below
        ``crossing_jump`` × that point's, is the branch's own eigenvector becoming
        unresolved (its tail rising through the threshold), not a neighbour of the
        continuum (tails ≳ 10× the branch's): no shorter step passes it, and the
        continuation stops there. Without the rule the steps crept up to the
        crossing, halving until they fell below ``min_step``: θ = 14.75°, ν0(0) =
        0.217, φ = 0.05 (growth metric, N = 48 … 160, tails 0.99e-5 … 1.2e-5 against
        1e-5, and relaxed 1.0e-3 against 1e-3): 193 of its 271 continuation steps,
        all rejected or crept.
    crossing_jump : float
        See ``crossing_near``.
    stall_rejections : int
        The predictor's stall rule (the tracker's step): a step rejected because the
        eigenvalue misses the prediction, ``stall_rejections`` times in a row with
        the miss (relative to the step) falling by less than a factor
        ``stall_factor`` at each halving, is a predictor that does not converge as
        the step shrinks (for a smooth branch the miss falls as the step squared):
        the last accepted point is not on the branch's continuation, and no shorter
        step passes. θ = 17.19°, ν0(0) = 0.144, φ = 0.05, N = 60 … 160: misses 0.36
        … 0.41 of the step at every step from 2.4e-9 down to 1.2e-9, 14 halvings per
        rung.
    stall_factor : float
        See ``stall_rejections``.
    restarts : int
        ARPACK restarts (per Krylov size) of one continuation step of the branch
        tracker. Where inverse iteration from the previous step's eigenvector does
        not settle, the prediction usually sits in the continuum of the dilute top,
        and a failed step is only halved: the default 60 restarts (2 × ~1100 solves)
        then buy nothing (thick dilute layer θ = 23.347°, ν0(0) = 0.0087, φ =
        0.0918, Φ = 0.393: the k_c scan took 53.6 s with 60, 15.0 s with 10, the
        same outcome — branch lost near k = 2.0e-5; 22 of 41 Arnoldi calls gave up
        at 60).
    memo_bytes : int
        Largest memory (bytes of eigenvectors) that the continuation steps memoised
        on one operator may hold (the memo of steps); past it steps are solved
        without being kept.
    relaxed_tail : float
        Largest eigenvector tail accepted by the continuation of
        :func:`~chuteflow.stability.lost.near_continuum_branch`, the fallback after
        the branch was lost: where the branch's phase velocity −Im α/k enters the
        range of u0(y), its eigenvector has a critical layer and tails of 1e-6 …
        1e-4, which the tracking threshold (1e-5) rejects although the eigenvalue is
        still the branch.
    relaxed_splits : tuple
        Numbers of equal sub-targets of
        :func:`~chuteflow.stability.lost.near_continuum_branch`'s attempts (a finer
        sequence of targets keeps the predictor's steps short where the branch turns
        sharply).
    relaxed_drift : float
        Largest relative drift |α(N) − α(N')| / |α| of a relaxed branch value that
        is returned.
    band_radius : float
        Radius, in drifts of the relaxed value, of the neighbourhood searched for
        the branch among the band's eigenvalues (P4, k = 0.5, N = 200: the
        continuation lands 3.6e-3 (mapped) and 5.8e-3 (plain) from the branch, with
        drifts 3.0e-3 and 3.2e-3).
    band_tail_gain : float
        A band eigenvalue replaces the relaxed value only when its eigenvector's
        tail is this factor smaller (P4, k = 0.5, N = 200: 1.8e-5 against 7.1e-4
        mapped, 4.8e-5 against 7.0e-4 plain; the other band members have tails ≥
        1.4e-4).
    seed_drift : float
        A direct candidate that drifts less than this between N and N' is followed
        to the next rung by shift-invert near its eigenvalue instead of a new dense
        QZ (θ = 17.5°, ν0(0) = 0.11, φ = 0.075, Φ = 0.35, k = 0.005: the candidate
        drifts 1.2e-6, 2.4e-7, 2.8e-8 at N = 80, 100, 125; QZ costs 0.6, 1.2, 2.4 s
        there and 23 s at N = 256).
    top_check_below : float
        :func:`least_stable` checks a direct solve's physical mode past the
        continuum once more near the top of the ladder (the check past the
        continuum), at its first rung of at least this fraction of the top (244 of
        the default 80 … 244, 256), and only when the mode passed below that rung.
        Within 10 % of the top, a dense spectrum already shows every eigenvalue the
        top would resolve above the answer: one with a tail below 1e-7 at the top
        has a tail below the tracking threshold 1e-5 at ≤ 10 % fewer nodes (a
        Chebyshev tail falls by far less than 100× over 25 nodes), where
        :func:`~chuteflow.stability.modes.direct_mode` returns it as the flagged
        least-stable candidate. The check's N' = 0.8 N is then the rung below, whose
        eigenvalues the ladder may have computed already. P1, k = 3: the check at N
        = 256 after the mode passed at 244 cost 41 of 107 s.
    """

    first_step: float = 1e-5
    first_step_min: float = 1e-5 / 1024
    first_predictor_min: float = 1e-9
    coarse_n: int = 48
    min_step: float = 1e-9
    crossing_near: float = 0.5
    crossing_jump: float = 2.0
    stall_rejections: int = 3
    stall_factor: float = 0.9
    restarts: int = 10
    memo_bytes: int = 16 * 2**20
    relaxed_tail: float = 1e-3
    relaxed_splits: tuple[int, ...] = (1, 8)
    relaxed_drift: float = 0.05
    band_radius: float = 5.0
    band_tail_gain: float = 0.1
    seed_drift: float = 1e-4
    top_check_below: float = 0.9

    def __post_init__(self):
        ints = ("coarse_n", "stall_rejections", "restarts")
        _require("tracking", self, ints, lambda v: v >= 1, "an integer >= 1", integer=True)
        _require("tracking", self, ("memo_bytes",), lambda v: v >= 0, "an integer >= 0", integer=True)
        positive = (
            "first_step",
            "first_step_min",
            "first_predictor_min",
            "min_step",
            "crossing_near",
            "stall_factor",
            "relaxed_tail",
            "relaxed_drift",
            "band_radius",
            "band_tail_gain",
            "seed_drift",
            "top_check_below",
        )
        _require("tracking", self, positive, lambda v: v > 0, "a number > 0")
        _require("tracking", self, ("crossing_jump",), lambda v: v >= 0, "a number >= 0 (0: no rule)")
        if not (isinstance(self.relaxed_splits, tuple) and self.relaxed_splits) or not all(
            isinstance(m, int) and m >= 1 for m in self.relaxed_splits
        ):
            raise ParameterError(
                f"tracking relaxed_splits = {self.relaxed_splits!r}: need a tuple of integers >= 1"
            )


@dataclass(frozen=True)
class RejectionPolicy:
    """Thresholds of the physical-mode tests and the resolution ladder (paper §4.1).

    Parameters
    ----------
    drift_tol : float
        Largest accepted |α(N) − α(N')| (paper: 1e-7).
    tail_tol : float
        Largest accepted coefficient among the highest ``tail_terms`` Chebyshev
        coefficients of the normalised eigenvector (paper: 1e-7).
    tail_terms : int
        Number of highest Chebyshev coefficients of the tail test (paper: 10).
    track_tail_tol : float
        Largest tail of an eigenvector accepted as a continuation step of the branch
        α(0) = 0 (looser than ``tail_tol``; the near-neutral continuum of the dilute top
        has tails ~1e-4).
    n_start : int
        First resolution N of the adaptive choice (80; on the sinh-mapped grid the paper's
        1e-7 is reached at N = 40–64 for k ≤ 0.02 at the paper's points, against 56–160 on
        the plain grid, ``benchmarks/probes/n_table.py``, so the sweep metrics start at 48;
        the default stays 80 for the 3D solvers on the plain grid and for the k → 0 limits,
        which converge more slowly on the mapped grid).
    n_max : int
        Largest resolution N tried.
    n_growth : float
        Each rung of the ladder is round(``n_growth`` × the one before) (at most ``n_max``).
    tracking : TrackingPolicy
        How the α(0) = 0 branch is followed and what replaces it where it is lost.
    search : SearchPolicy
        How the resolver looks for less damped modes above an answer (the global solve and
        the following of its candidates, :mod:`.resolver`).
    relaxed_k_max : float
        Largest |k| at which a flagged value of the branch followed with the relaxed tail
        threshold (``method = "branch (relaxed)"``) always outranks a direct solve's mode
        (:meth:`direct_outranks_relaxed`). Below it the relaxed branch is the branch (at
        θ = 16.5°, ν0(0) = 0.13, φ = 0.08, Φ = 0.30, k = 0.005 its drift falls from 2.3e-4
        at N = 80 to 3.3e-6 at N = 244, where QZ finds the same eigenvalue). Above it the
        branch lies in a band of critical-layer eigenvalues (phase velocity inside the range
        of u0), the continuation may land on a neighbour in the band (P4, k = 0.5, N = 200:
        −0.0279 − 0.8199i mapped, −0.0350 − 0.8188i plain, against the branch's
        −0.0300 − 0.8171i), and a resolved direct mode competes with it
        (``benchmarks/probes/relaxed_branch.py``).
    """

    drift_tol: float = 1e-7
    tail_tol: float = 1e-7
    tail_terms: int = 10
    track_tail_tol: float = 1e-5
    n_start: int = 80
    n_max: int = 256
    n_growth: float = 1.25
    relaxed_k_max: float = 0.1
    search: SearchPolicy = SearchPolicy()
    tracking: TrackingPolicy = TrackingPolicy()

    def __post_init__(self):
        if isinstance(self.relaxed_k_max, bool) or not (
            isinstance(self.relaxed_k_max, (int, float)) and self.relaxed_k_max >= 0
        ):
            raise ParameterError(
                f"relaxed_k_max = {self.relaxed_k_max!r}: need a wavenumber >= 0 (where the "
                "relaxed branch stops outranking a direct solve)"
            )
        object.__setattr__(self, "relaxed_k_max", float(self.relaxed_k_max))
        for name in ("drift_tol", "tail_tol", "track_tail_tol"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and 0 < v < 1):
                raise ParameterError(
                    f"{name} = {v!r} is outside (0, 1): it is a threshold on "
                    "an eigenvalue change or a normalised Chebyshev "
                    "coefficient"
                )
            object.__setattr__(self, name, float(v))
        if isinstance(self.tail_terms, bool) or not (
            isinstance(self.tail_terms, int) and self.tail_terms >= 1
        ):
            raise ParameterError(f"tail_terms = {self.tail_terms!r}: need an integer >= 1")
        for name in ("n_start", "n_max"):
            try:
                object.__setattr__(self, name, validate_n(getattr(self, name)))
            except ParameterError as exc:
                raise ParameterError(f"{name}: {exc}") from None
        if not isinstance(self.tracking, TrackingPolicy):
            raise ParameterError(f"tracking = {self.tracking!r}: expected a TrackingPolicy")
        if not isinstance(self.search, SearchPolicy):
            raise ParameterError(f"search = {self.search!r}: expected a SearchPolicy")
        if not (isinstance(self.n_growth, (int, float)) and self.n_growth > 1):
            raise ParameterError(f"n_growth = {self.n_growth!r}: the ladder must grow (> 1)")

    def replace(self, **changes) -> RejectionPolicy:
        """A copy with the given fields changed; ``None`` values leave a field as it is."""
        changes = {k: v for k, v in changes.items() if v is not None}
        return dataclasses.replace(self, **changes) if changes else self

    def accepts(self, drift: float, tail: float) -> bool:
        """Both tests pass: drift < ``drift_tol`` and tail < ``tail_tol``."""
        return bool(drift < self.drift_tol and tail < self.tail_tol)

    def direct_outranks_relaxed(
        self,
        k: float,
        direct_re: float,
        direct_drift: float,
        direct_tail: float,
        relaxed_re: float,
        relaxed_drift: float,
    ) -> bool:
        """Whether a direct solve's mode (dense QZ at k; growth rate ``direct_re``) replaces a
        flagged value of the branch followed with the relaxed tail threshold (growth rate
        ``relaxed_re``) as the answer at wavenumber |k| = ``k``.

        Only beyond :attr:`relaxed_k_max` (where the branch has reached the continuum), and
        only when the direct mode is resolved (tail below :attr:`track_tail_tol`), agrees
        between the resolutions N and N' better than the relaxed value (``direct_drift <
        relaxed_drift``) and is at least as unstable (``direct_re >= relaxed_re``): a
        resolved but more damped mode never hides a less damped one that N does not yet
        resolve (P4, k = 0.5: the branch at −0.0300 − 0.8172i, drift 6.4e-4 at N = 200,
        against a resolved mode at −2.51 − 0.87i).

        Below :attr:`relaxed_k_max` the branch value wins unless the direct mode passes both
        of the paper's tests (:meth:`accepts`) and is less damped: the least-stable physical
        mode is then that mode, and the relaxed value, which the tests reject, is not (θ =
        17.5°, ν0(0) = 0.11, φ = 0.075, Φ = 0.35, k = 0.005: the relaxed branch wanders
        between −0.00530 and −0.00614 with drifts ≥ 1.8e-4 up to N = 256, while −0.00522663 −
        0.0310785i passes both tests from N = 125, drift 1.3e-11 at N = 256).
        """
        if k <= self.relaxed_k_max:
            return bool(self.accepts(direct_drift, direct_tail) and direct_re > relaxed_re)
        return bool(
            direct_tail < self.track_tail_tol and direct_drift < relaxed_drift and direct_re >= relaxed_re
        )

    def next_n(self, n: int) -> int:
        """The rung after N: min(``n_max``, round(``n_growth`` N))."""
        return min(self.n_max, round(n * self.n_growth))

    def ladder(self, start: int | None = None) -> list[int]:
        """Resolutions tried in turn: ``start`` (default ``n_start``, at most ``n_max``),
        then :meth:`next_n` until ``n_max`` (80, 100, 125, 156, 195, 244, 256 by default)."""
        out = [min(self.n_start if start is None else start, self.n_max)]
        while out[-1] < self.n_max:
            out.append(self.next_n(out[-1]))
        return out


#: The paper's thresholds (§4.1) and the default ladder 80 … 256.
DEFAULT_POLICY = RejectionPolicy()
