"""The least-stable mode at any wavevector: one contract, one resolver (paper §4.1–4.2).

Contract
    The least-stable mode at (k_x, k_z) is the mode of largest Re α among the modes that
    pass the paper's two tests under refinement (§4.1: drift |α(N) − α(N')| and Chebyshev
    tail below 1e-7, :class:`~.policy.RejectionPolicy`). An eigenvalue above the answer
    that fails a test is not discarded while its drift and tail keep falling: it is followed
    up the ladder of resolutions until it is decided — a mode (it passes both tests, and
    then it is the answer), or not one (the near-neutral continuum of the dilute top, a
    point of a continuous spectrum, or a spurious eigenvalue: its drift or tail stops
    falling, or no eigenvalue at the next N continues it), or below the answer. Where the
    ladder ends with such a candidate undecided, the answer is that candidate, flagged
    ``converged = False`` with its drift and tail, and the note names the least-stable
    resolved mode below it (such a candidate, left undecided before the ladder's top where
    its drift cannot pass the threshold by then, is followed on to the top: the estimate is
    the ladder's best). A damped mode is never reported as converged while a less damped
    one that passes the tests exists at the resolutions tried — or, where its eigenvector
    resolves only beyond them, while it is found there (step 3).

Resolver (:func:`least_stable`)
    1. *Tracked or direct answer*: the α(0) = 0 branch (the kinematic-wave mode of
       Appendix B) followed from k = 0 by continuation, with the relaxed-tail and direct
       fallbacks where the continuation loses it near the continuum
       (:mod:`.tracking`, :mod:`.lost`); or the dense spectrum at each rung (``method="qz"``, and
       |k| > 1).
    2. *Search above it* (:func:`search_above`): one dense eigensolve of the whole spectrum
       (:func:`~.eigen.shifted_spectrum`: one LU and a standard eigenproblem) at the
       coarse resolution ``policy.search.n`` (48) on the grid of the question; every
       eigenvalue above the answer whose eigenvector is nearly resolved there, or whose
       tail falls fast enough through the next two rungs (:data:`SCREEN_RATE_RUNGS`), is a
       candidate, followed by shift-invert on the rungs 48, 60, 75, 94, … (each rung's
       α(N') is the rung below) until decided (:func:`follow_candidate`); one that settles
       at the dilute top's continuum, α = −i k_x u0(y_max), is not a mode
       (:data:`CONTINUUM_NEAR`). Where the answer needed more than twice the screen's N,
       or is flagged, the screen is repeated at that N (twice the flagged answer's).
    3. *Beyond the ladder* (:func:`beyond_the_ladder`): where the answer needed more than
       twice the screen's N, the screen is repeated there, and the eigenvalues above the
       answer whose tails are below the band beside them (:data:`SUSPECT_TAIL`) are
       followed past the ladder's top: one whose eigenvector resolves there is a mode, and
       the answer, flagged unless it passes both tests.

    Finite wavevectors, 2D and 3D, are solved on the sinh-mapped grid
    (:func:`~.modes.cache_for`, the one place where the grid is chosen).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow
from .eigen import qz, shifted_spectrum
from .lost import _better, _direct_candidate, _outranked, after_lost_branch
from .modes import (
    K_DIRECT,
    Mode,
    OperatorCache,
    cache_for,
    check_hydrodynamic_k,
    check_n,
    direct_mode,
    drift_of,
    interp_vector,
    join_notes,
    make_mode,
    mode_near,
    nearest_eigenpair,
    resolve_policy,
    stability_operator,
    tails,
)
from .operator import Pencil, StabilityOperator, validate_k, validate_n
from .policy import RejectionPolicy
from .tracking import branch_mode

__all__ = ["choose_n", "follow_candidate", "least_stable", "pencil", "search_above"]


def _top_check_n(ladder: list[int], policy: RejectionPolicy) -> int:
    """The first rung of at least ``policy.tracking.top_check_below`` of the top: a direct
    solve's physical mode past the continuum is checked once more there (P1, k = 3: the check
    at N = 256 after the mode passed at 244 cost 41 of 107 s)."""
    return next(r for r in ladder if r >= policy.tracking.top_check_below * ladder[-1])


def _check_above_continuum(flow, k, kz, n_top, mode: Mode, policy, cache, lost: str) -> Mode:
    """A direct solve's physical mode past the continuum (k > ``policy.relaxed_k_max``) with
    unresolved eigenvalues above it, checked once more near the top of the ladder (at
    ``n_top``, ``policy.tracking.top_check_below``): there a branch in the band of critical-layer
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
    """The least-stable mode at the wavevector (``k``, ``kz``), by the contract of this
    module: the mode of largest Re α among the modes that pass the paper's drift and tail
    tests under refinement (§4.1). Step 1 below gives the tracked (or direct) answer; step 2
    (:func:`search_above`) follows every nearly resolved eigenvalue above it, from one dense
    solve at ``policy.search.n``, until each is decided; an undecided candidate above the
    least-stable resolved mode is returned flagged (``converged = False``), the resolved
    mode named in its note. With ``sigma`` the question is another one (the mode nearest σ)
    and step 2 is skipped.

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
    k, kz = validate_k(k, "k"), validate_k(kz, "kz", signed=True)
    check_hydrodynamic_k(k, kz)
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol, n_max=n_max)
    if method not in ("branch", "qz"):
        raise ParameterError(
            f"method = {method!r}: choose 'branch' (continuation from k = 0) "
            "or 'qz' (dense scan of the whole spectrum)"
        )
    cache = cache_for(kz, cache)
    ns = [validate_n(n)] if n is not None else policy.ladder()
    # the search's own ladder from its coarse N, up to the given N where one is given
    rungs = policy.search.ladder(policy.n_max if n is None else ns[-1], policy.n_growth)
    # in 3D the search from scratch replaces the fallbacks after a lost branch (a dense QZ
    # of the 3D pencil at every rung: P1, (0.002, 0.1) took 31 s that way)
    found, lost = _tracked_or_direct(flow, k, kz, ns, sigma, method, policy, cache, stop_when_lost=bool(kz))
    if found is None and lost is not None:
        found = search_above(flow, k, kz, None, policy, cache, rungs)
        if found is not None:
            # the lost branch is how the search was reached, not a defect of this answer
            found = dataclasses.replace(
                found,
                note=join_notes(
                    f"found by the global search: the continuation from k = 0 {lost}", found.note
                ),
            )
        else:
            # nothing above a mode there: the fallbacks' answer, searched above like any
            # other (its repeated screen, and the note of what was set aside above it)
            found, _ = _tracked_or_direct(flow, k, kz, ns, sigma, method, policy, cache)
            if sigma is None and found is not None:
                found = search_above(flow, k, kz, found, policy, cache, rungs)
    elif sigma is None and found is not None:
        found = search_above(flow, k, kz, found, policy, cache, rungs)
    if found is not None and not found.physical and not strict and not found.note:
        # the flag says why: the tests' numbers against the thresholds at the ladder's top
        found = dataclasses.replace(
            found,
            note=f"the tests' thresholds not reached up to N = {ns[-1]}: raise n_max (chuteflow eig "
            "--n) to go further",
        )
    if found is not None and (found.physical or not strict):
        return found
    what = (
        "no physical mode"
        if found is None
        else f"best candidate α = {found.alpha:.6g} with drift {found.drift:.1e}, tail {found.tail:.1e}"
    )
    raise ConvergenceError(
        f"least-stable mode at theta = {flow.theta:g}, nu0 = {flow.nu0:g}, k = {k:g}: "
        f"{what} (thresholds drift {policy.drift_tol:g}, tail {policy.tail_tol:g}) up to N = "
        f"{ns[-1]}; raise n_max or relax the thresholds"
    )


def _tracked_or_direct(
    flow, k, kz, ns, sigma, method, policy, cache, stop_when_lost: bool = False
) -> tuple[Mode | None, str | None]:
    """Step 1 of the resolver (module docstring): (the first mode along the resolutions
    ``ns`` that passes both tests, else the best candidate (:func:`_better`), else None;
    where the continuation lost the branch, why). With ``stop_when_lost`` it returns
    (None, why) as soon as the branch is lost."""
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
                    mode = branch_mode(flow, k, kz=kz, n=nn, policy=policy, cache=cache, retrack=not kz)
                except ConvergenceError as exc:
                    # the continuation lost the branch: from now on followed with the tail
                    # threshold relaxed (near_continuum_branch), at every rung
                    lost, how = str(exc).split(" (theta")[0], "relaxed"
                    if stop_when_lost:
                        return None, lost
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
                and nn < (n_top := _top_check_n(ns, policy))
            ):
                mode = _check_above_continuum(flow, k, kz, n_top, mode, policy, cache, lost or "")
            return mode, lost
        if mode is not None and _better(mode, best, policy):
            best = mode
    return best, lost


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


def pencil(flow: SteadyFlow, k: float, n: int | None = None, kz: float = 0.0) -> Pencil:
    """The pencil A V = α B V of ``flow`` at wavenumber ``k`` (and ``kz``) on N = ``n``.

    ``n=None`` uses :func:`chuteflow.stability.choose_n` (resolution from the convergence
    estimate of the least-stable mode).
    """
    if n is None:
        n = choose_n(flow, k)
    return StabilityOperator(flow, n, three_d=bool(kz)).pencil(k, kz)


# -- the search above an answer ----------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Followed:
    """One candidate of :func:`search_above` after :func:`follow_candidate`.

    Attributes
    ----------
    start : complex
        The eigenvalue at the coarse resolution where the candidate was found.
    mode : Mode or None
        The candidate at the last resolution it was followed to (None: lost at the first).
    verdict : str
        ``"mode"`` (passes both tests), ``"below"`` (below the answer), ``"same"`` (it
        converges onto the answer: the same eigenvalue), ``"not a mode"``
        (drift or tail stops falling, or no eigenvalue continues it), ``"undecided"``
        (the ladder ended first).
    why : str
        The evidence for the verdict, in words.
    """

    start: complex
    mode: Mode | None
    verdict: str
    why: str


class _Candidate:
    """One eigenpair followed up the ladder by shift-invert (:func:`follow_candidate`):
    its last eigenpair, the mode at the last rung, the tails seen, and once decided its
    :class:`Followed`."""

    def __init__(
        self,
        flow,
        kx,
        kz,
        alpha: complex,
        v: np.ndarray,
        n_from: int,
        policy,
        cache,
        tail: float | None = None,
        top: int | None = None,
    ):
        self.flow, self.kx, self.kz, self.policy, self.cache = flow, kx, kz, policy, cache
        self.top = policy.n_max if top is None else top  # the ladder's top
        self.start = self.alpha = complex(alpha)
        self.v, self.n_from = v, n_from
        self.tail0 = tail  # the tail of ``v`` at N = n_from, where the screen measured it
        self.mode: Mode | None = None
        self.tails: list[float] = []
        self.drifts: list[float] = []  # the drift at each rung where the tail was recorded
        self.done: Followed | None = None
        self.answer: Mode | None = None  # the answer the search is above (search_above)
        self.hopeless = False  # left undecided by the hopeless rule, before the ladder's top
        self.finishing = False  # followed on past that verdict (finish): the rule is off

    def _decide(self, verdict: str, why: str) -> Followed:
        self.done = Followed(self.start, self.mode, verdict, why)
        return self.done

    def step(self, nn: int, floor: float, rungs_left: int = 0) -> Followed | None:
        """Solve at N = ``nn``; the verdict once decided, else None (``rungs_left``: the
        rungs of the ladder above ``nn``)."""
        flow, kx, kz, policy, search = self.flow, self.kx, self.kz, self.policy, self.policy.search
        three_d = bool(kz)
        p = stability_operator(flow, nn, three_d, cache=self.cache).pencil(kx, kz)
        nf = len(p.fields)
        v0 = self.v if nn == self.n_from else interp_vector(self.v, nf, self.n_from, nn)
        try:
            a, w = nearest_eigenpair(p, self.alpha, v0=v0)
        except ConvergenceError:
            return self._decide("not a mode", f"no eigenvalue settles near {self.alpha:.6g} at N = {nn}")
        if abs(a - self.alpha) > search.jump * max(abs(self.alpha), 1e-3):
            return self._decide(
                "not a mode", f"no eigenvalue at N = {nn} continues {self.alpha:.6g} (nearest {a:.6g})"
            )
        n2 = check_n(nn)
        prev = self.mode
        if prev is not None and prev.n == n2:
            drift = abs(a - prev.alpha)  # the rung below is N' = round(0.8 N)
        else:
            try:
                drift, _ = drift_of(flow, a, w, nn, kx, kz, three_d, cache=self.cache)
            except ConvergenceError:
                drift = math.inf
        tail_before = self.tails[-1] if self.tails else None
        n_before = prev.n if prev is not None else self.n_from  # where tail_before was measured
        if tail_before is None and self.mode is None and nn != self.n_from:
            # the tail of the eigenvector followed, at N = n_from (the screen's, where it ran)
            if self.tail0 is None:
                p0 = stability_operator(flow, self.n_from, three_d, cache=self.cache).pencil(kx, kz)
                self.tail0 = float(tails(p0, self.v[:, None], policy.tail_terms)[0])
            tail_before = self.tail0
        self.mode = mode = make_mode(p, a, w, drift, n2, policy)
        self.alpha, self.v, self.n_from = complex(a), w, nn
        ans = self.answer
        if ans is not None and abs(a - ans.alpha) <= 2 * max(drift, ans.drift, policy.drift_tol):
            # the candidate converges onto the answer (its coarse eigenvalue lay farther off)
            return self._decide("same", f"it converges onto the answer {ans.alpha:.6g} (N = {nn})")
        if mode.physical:
            return self._decide("mode", f"passes both tests at N = {nn}")
        # (a candidate that passes both tests is a mode, near α_top or not)
        a_top, near = _top_continuum(flow, kx, kz)
        if (
            abs(a - a_top) <= near
            and drift < CONTINUUM_DRIFT * max(1.0, abs(a))
            # its eigenvector is unresolved (CONTINUUM_RESOLVED) ...
            and mode.tail >= CONTINUUM_RESOLVED
            # ... and its tail does not fall as a mode's from a coarser N; at the first rung, where
            # none was seen, only an eigenvalue pinned far below its tail (CONTINUUM_PINNED)
            and (
                not _tail_converges(tail_before, n_before, mode.tail, nn, self.top, policy.tail_tol)
                if tail_before is not None
                else drift <= CONTINUUM_PINNED * mode.tail
            )
        ):
            return self._decide(
                "not a mode",
                f"the dilute top's continuum: settled (drift {drift:.1e}) within {abs(a - a_top):.1e} "
                f"of α = −i k_x u0(top) = {a_top:.6g} at N = {nn}",
            )
        if mode.alpha.real + mode.drift < floor:
            return self._decide("below", f"Re α = {mode.alpha.real:.6g} at N = {nn}")
        self.tails.append(mode.tail)
        self.drifts.append(drift)
        t, d = self.tails, self.drifts
        decaying = len(t) >= 4 and t[-1] < t[-2] < t[-3]
        # an eigenvalue whose drift falls at every rung, and by CONVERGING_DRIFT_FALL over
        # three, while its eigenvector's tail falls at every rung converges, if slowly (an
        # eigenfunction with a weak singularity): a mode not yet resolved, not a member of a
        # band, whose drift is the band's spacing and shrinks no faster than it
        converging = (
            decaying
            and len(d) >= 4
            and d[-1] < d[-2] < d[-3] < d[-4]
            and d[-1] <= CONVERGING_DRIFT_FALL * d[-4]
            and d[-4] >= 10 * policy.drift_tol  # (a settled continuum's drift is round-off)
        )
        if (
            len(self.tails) >= 4
            and mode.tail >= max(policy.tail_tol, policy.track_tail_tol)
            and mode.tail > search.stall * self.tails[-4]
            and not converging
        ):
            return self._decide(
                "not a mode",
                f"its eigenvector's tail does not converge ({self.tails[-4]:.1e} → {mode.tail:.1e} over "
                f"three rungs up to N = {nn}: ×{mode.tail / self.tails[-4]:.2g}, above ×{search.stall:g}): "
                "no resolved eigenfunction (the dilute top's continuum, a point of a continuous "
                "spectrum, or a spurious eigenvalue)",
            )
        if decaying and prev is not None and 0 < prev.drift < math.inf and math.isfinite(drift):
            # a candidate whose tail decays at every rung (the stall rule above has had three
            # rungs; the continuum's band wanders: Q2, (0.005, 0.1), tails 2.6e-4, 8.7e-5,
            # 1.0e-4, 1.2e-4 at N = 60 … 118) with a drift that, extrapolated to the ladder's
            # top at its own rate or the fastest plausible one, stays far above the
            # threshold: the ladder cannot decide it
            rate = max(drift / prev.drift, search.fastest_fall)
            if not self.finishing and drift * rate**rungs_left > search.hopeless * policy.drift_tol:
                self.hopeless = rungs_left > 0
                return self._decide(
                    "undecided",
                    f"its drift {drift:.1e} at N = {nn}, falling ×{rate:.2g} a rung, stays above "
                    f"{search.hopeless:g} × the threshold by the top of the ladder",
                )
        return None

    def finish(self, rungs: list[int]) -> Followed:
        """A candidate the hopeless rule left undecided, the search's flagged answer, followed
        on over the ``rungs`` above its last to the ladder's top (the rule off): the answer's
        estimate is the ladder's best. Its verdict there: a mode, not one, or undecided with
        the drift and tail at the top. Measured (try_random_points
        seed 389533): θ = 22.867°, ν0(0) = 0.0106, φ = 0.0947, Φ = 0.465 at (k_x, k_z) =
        (0.001491, 0.020654), a candidate with drifts 3.2e-3, 3.5e-3, 6.6e-4, 2.4e-3 at N = 48
        … 94 (tails 1.4e-4 … 1.2e-5) was left undecided at N = 94 and answered, flagged, as
        −0.0374368 − 0.0223830i, 8.4e-4 from the dense QZ at N = 250 (−0.0373596 −
        0.0232151i); followed on, −0.0373595 − 0.0232103i at N = 256 (drift 2.6e-5, tail
        6.2e-9: 4.8e-6 from it), still flagged."""
        assert self.done is not None
        assert self.mode is not None
        why, self.done, self.finishing = self.done.why, None, True
        rest = [r for r in rungs if r > self.n_from]
        for i, nn in enumerate(rest):
            if self.step(nn, -math.inf, len(rest) - 1 - i) is not None:
                return self.done  # type: ignore[return-value]
        m = self.mode
        return self._decide(
            "undecided", f"{why}; followed on to the ladder's top (N = {m.n}) for the estimate"
        )

    def result(self) -> Followed:
        """The verdict, ``"undecided"`` while none."""
        if self.done is not None:
            return self.done
        where = f"N = {self.mode.n}" if self.mode is not None else "the first rung"
        return Followed(self.start, self.mode, "undecided", f"not decided by {where}")


def follow_candidate(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    alpha: complex,
    v: np.ndarray,
    n_from: int,
    rungs: list[int],
    policy: RejectionPolicy,
    cache: OperatorCache,
    floor: float = -math.inf,
) -> Followed:
    """Follow the eigenpair (α, v) found at N = ``n_from`` up the resolutions ``rungs`` by
    shift-invert until it is decided (module docstring; ``floor``: the growth rate of the
    answer, below which a candidate is decided ``"below"``). A rung's α(N') is the α just
    solved on the rung below when that is N' = round(0.8 N), else a solve at N'."""
    c = _Candidate(flow, kx, kz, alpha, v, n_from, policy, cache, top=max(rungs, default=n_from))
    for i, nn in enumerate(rungs):
        if c.step(nn, floor, len(rungs) - 1 - i) is not None:
            break
    return c.result()


def _spectrum_above(p: Pencil, answer: Mode | None, floor: float | None):
    """The dense spectrum of the pencil ``p`` (:func:`~.eigen.shifted_spectrum`, QZ where σ
    lies on an eigenvalue), shifted to the right of the answer, with the eigenvectors where
    some eigenvalue is above ``floor`` (None: always, without the eigenvalues-only solve
    that decides it): (α, V) or None where none is above."""
    # one LU and a standard eigensolve, shifted to the right of the answer (accurate where
    # the candidates are): 3–4.5 × faster than QZ at N = 48
    sigma = 0.5 if answer is None else complex(max(answer.alpha.real, 0.0) + 0.5, answer.alpha.imag)
    A, B = p.equilibrated()
    got = shifted_spectrum(A, np.real(np.diag(B)), sigma, vectors_above=floor)
    w, V = qz(A, B) if got is None else got
    return None if V is None else (w, V)


#: The rate rule of the screen (:func:`global_candidates`). An eigenvalue whose tail at the
#: screen's N (48) is above ``candidate_tail`` is still a candidate where, followed through
#: dense solves on the next SCREEN_RATE_RUNGS rungs (60, 75), its tail falls at each, fast
#: enough that, continued at the slowest of those geometric rates, it reaches the tail
#: threshold by the top of the ladder. A mode's tail falls geometrically in N; the
#: eigenvalues of the dilute top's continuum fall slowly or unevenly. Measured: θ = 21.373°,
#: ν0(0) = 0.0082, φ = 0.1076, Φ = 0.313 at (k_x, k_z) = (0.019049, 0.155868): the mode
#: −0.3814 − 0.2499i (dense QZ at N = 250 … 450: drift 7.9e-6 … 2.3e-11) has tails 9.9e-4,
#: 3.1e-4, 9.6e-5, 3.0e-5 at N = 48, 60, 75, 94 (×0.31 a rung; projected to pass at
#: N ≈ 155) and was no candidate, so −2.1465 − 0.2834i was reported as converged. At
#: (0.001326, 0.061321) of the same flow the continuum's −0.214 − 0.018i falls ×0.32 from
#: 48 to 60 but ×0.75 from 60 to 75 (projected N > 400): not a candidate; see also
#: :data:`CONTINUUM_NEAR`.
SCREEN_RATE_RUNGS = 2
#: The dilute top's continuum is not a mode. Where ν0 → ν_top the perturbations are only
#: carried by the flow, so the continuum clusters at α_top = −i k_x u0(y_max): eigenvalues
#: pinned there (drift ~1e-10 … 1e-6) while their tails stay unresolved, some of them
#: falling ×0.36 a rung (θ = 21.373° … at (0.001326, 0.061321): 1.2e-2, 4.8e-3, 1.7e-3 at
#: N = 48, 60, 75; drift 5e-11 and tail 7e-6 at N = 256). The smoothest nearly passes the
#: tests at high N: on the unmapped grid at P1, k = 0.5, N = 200, −1.3e-8 − 4.959346i
#: (α_top = −4.959346i; drift 9e-12, tail 9.7e-6, below the repeated screen's 1.3e-5); at
#: P3, k = 0.002, the cluster's arc reaches −1.3e-5 − 0.0186683i (α_top = −0.0186684i;
#: drift 1.6e-6, tail 9.2e-5 at N = 94). A candidate within CONTINUUM_NEAR × |k| u0(y_max)
#: of α_top whose eigenvalue has settled (drift < CONTINUUM_DRIFT × max(1, |α|), the
#: rule of :func:`~.modes.direct_mode`) is decided not a mode (:func:`_top_continuum`);
#: and the rate rule admits no eigenvalue that moves less than that from one screen to the
#: next, nor one that moves by half the distance to its nearest neighbour or more (not
#: followed unambiguously). The slow modes the rate rule is for move by 1e-3 … 1e-2 (the
#: mode above by 3e-3 and 2e-3, its neighbours 0.02 … 0.03 away; P2, k = 0.5,
#: −0.5187 − 4.6606i: 1e-2, 0.52 from α_top = −4.6377i against the radius 0.046).
CONTINUUM_NEAR = 1e-2
CONTINUUM_DRIFT = 1e-4
#: ... and it is the continuum only where its tail is unresolved: one that falls by this
#: factor or more from one rung to the next converges as a mode's does, however little
#: the eigenvalue moves (a mode converging fast moves little too). The continuum's tails
#: fall ×0.36 a rung at most (above); measured: θ = 19.166°, ν0(0) = 0.0103, φ = 0.049,
#: Φ = 0.399 at (k_x, k_z) = (0.003284, 0.070959), the mode −0.0022020 − 0.2156592i (dense
#: QZ at N = 250: drift 1e-12, tail 1e-14) lies 0.023 from α_top = −0.2383i, inside the
#: radius 0.052 (k_z ≫ k_x), with drift 5.4e-5 at N = 60 and tails 5.6e-5, 2.4e-6, 1.0e-7
#: at N = 48, 60, 75 (×0.04 a rung): it was decided the continuum, and −0.0834 − 0.2131i
#: was answered, flagged.
CONTINUUM_TAIL_FALL = 0.1
#: ... nor one whose tail, falling on at the power of N it fell by over the last rung, passes
#: the tail test by the top of the ladder (:func:`_tail_converges`). The continuum's
#: eigenfunctions are singular at the top, so their tails fall as a power of N: the member
#: above, 1.2e-2, 4.8e-3, 1.7e-3 at N = 48, 60, 75 and 7e-6 at 256, as N^-4.1 … N^-4.5
#: (from 4.8e-3 at N = 60 at that power: 1.3e-5 at 256, far above 1e-7); a mode's
#: eigenfunction is analytic and its tail falls exponentially in N, ever faster in powers of
#: N. Measured: θ = 22.393°, ν0(0) = 0.0947, φ = 0.094, Φ = 0.436 at (k_x, k_z) = (0.001278,
#: 0.00738) (try_random_points seed 645549) the unstable mode +0.0015222 − 0.0627026i (dense
#: QZ at N = 75 … 300: the same to 1e-10; tails 1.7e-5, 2.1e-6, 8.7e-8, 1.9e-9 at N = 48, 60,
#: 75, 94: N^-9.3, then N^-14) lies 2.5e-3 from α_top = −0.0646412i (radius 3.8e-3); its tail
#: fell ×0.125 from N = 48 to 60 (not tenfold): it was decided the continuum, and the stable
#: −0.0068978 − 0.0722538i was reported as converged. At N^-9.3 from 2.1e-6 at N = 60 it
#: passes 1e-7 by N = 60 × 1.39: a mode's fall.
#: ... and at a candidate's first rung (the screen's N, or the repeated screen's), where no
#: coarser tail of its eigenvector has been seen, it is the continuum only where its
#: eigenvalue is pinned: drift ≤ CONTINUUM_PINNED × tail (the continuum's settle to
#: round-off while their eigenvectors stay unresolved: −1.3e-8 − 4.959346i on the unmapped
#: grid at P1, k = 0.5, N = 200, drift 9e-12 at tail 9.7e-6; a converging mode's drift goes
#: with its tail). Measured: θ = 16.651°, ν0(0) = 0.1948, φ = 0.0547, Φ = 0.322 at
#: (k_x, k_z) = (0.001763, 0.022022) (try_random_points seed 292615) the mode −0.0033977 −
#: 0.0294616i lies 3.8e-3 from α_top = −0.0311261i (radius 3.9e-3) and was decided the
#: continuum at its first rung N = 48 (drift 1.3e-5, tail 1.1e-4: 0.12) and again at the
#: repeated screen's N = 118 (drift 4.3e-8, tail 4.7e-7: 0.09), and the three times more
#: damped −0.0101237 − 0.0782398i was answered as converged; followed on, it passes both
#: tests at N = 148 (a candidate that does is a mode, near α_top or not).
CONTINUUM_PINNED = 1e-3
#: ... and only where its eigenvector is unresolved: a tail below CONTINUUM_RESOLVED is a
#: mode's, however the eigenvalue got there (the continuum's smoothest members measured:
#: tail 9.7e-6 on the unmapped grid at P1, k = 0.5, N = 200; 7e-6 at θ = 21.373°,
#: (0.001326, 0.061321), N = 256 — seven times above). Measured: θ = 25.066°, ν0(0) =
#: 0.021, φ = 0.1022, Φ = 0.488 at (k_x, k_z) = (0.004359, 0.02695) (try_random_points seed
#: 102136) the mode −0.0089518 − 0.1938240i (dense QZ: tails 2e-6, 4e-9, 3e-12 at N = 48,
#: 94, 150, the same eigenvalue to 1e-7) lies 4.8e-3 from α_top = −0.18940i (radius
#: 1.2e-2); at N = 60 its drift was 5.5e-6 and its tail 3.8e-7, a fall of ×0.18 from N = 48
#: (not the tenfold of CONTINUUM_TAIL_FALL): it was decided the continuum, and −0.0101821 −
#: 0.1048210i, more damped, was reported as converged.
CONTINUUM_RESOLVED = 1e-6


#: The stall rule (:attr:`SearchPolicy.stall`) leaves alone a candidate whose tail falls at
#: every rung and whose drift falls at every rung and by this factor or more over three
#: rungs (N × 1.95): an eigenvalue converging at order ≥ 2.4 in N. A band's member moves by
#: about the band's spacing, which shrinks as N⁻¹ … N⁻² (× 0.51 … 0.26 over three rungs).
#: Measured: at θ 12.092, ν0 0.1675, φ 0.0484, Φ 0.31, (k_x, k_z) = (0.001702, 0.018843) the
#: drift 2.4e-5, 1.0e-5, 4.1e-6, 2.4e-6 (× 0.10) and tail 7.0e-5 … 2.7e-5 at N = 48 … 94 of
#: an eigenvalue that dense QZ finds at every N up to 350 with its tail falling to 1.5e-7
#: (a mode; the stall rule had set it aside and a 540 times more damped mode was answered
#: as converged); a member of the band at (16.5°, 0.13, φ 0.08, Φ 0.30), k = 0.005, drifts
#: 4.1e-4, 2.9e-4, 1.7e-4, 1.4e-4 (× 0.34) with its eigenvalue swinging back and forth.
CONVERGING_DRIFT_FALL = 0.2


def _tail_converges(t0: float, n0: int, t1: float, n1: int, top: int, tol: float) -> bool:
    """Whether an eigenvector's tail ``t0`` at N = ``n0`` → ``t1`` at N = ``n1`` falls as a
    mode's does, not as the dilute top's continuum's: tenfold or more
    (:data:`CONTINUUM_TAIL_FALL`), or fast enough that, falling on at the same power of N,
    it reaches ``tol`` by N = ``top``."""
    if t1 <= CONTINUUM_TAIL_FALL * t0:
        return True
    if not (0 < t1 < t0) or n1 <= n0 or top <= n1:
        return False
    power = math.log(t1 / t0) / math.log(n1 / n0)  # < 0
    return t1 * (top / n1) ** power <= tol


def _top_continuum(flow: SteadyFlow, kx: float, kz: float) -> tuple[complex, float]:
    """(α_top, radius): where the dilute top's continuum clusters, α_top = −i k_x u0(y_max),
    and the distance within which a settled candidate is taken to be it
    (:data:`CONTINUUM_NEAR`)."""
    u_top = float(flow.u[-1])
    return complex(0.0, -kx * u_top), CONTINUUM_NEAR * math.hypot(kx, kz) * max(abs(u_top), 1.0)


def global_candidates(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    answer: Mode | None,
    policy: RejectionPolicy,
    cache: OperatorCache,
    finer: list[int] | None = None,
    top: int | None = None,
    suspects: list | None = None,
) -> list[tuple[complex, np.ndarray, float]]:
    """Eigenpairs above ``answer`` from one dense eigensolve at ``policy.search.n``
    (:func:`~.eigen.shifted_spectrum`), best first, each with its eigenvector's tail:
    eigenvectors nearly resolved there (tail < ``policy.search.candidate_tail``), Re α above
    the answer's by more than its uncertainty (its drift, at least the drift threshold),
    neither the answer itself nor, in a real pencil (k_x = 0), the conjugate of one kept.

    With finer resolutions ``finer`` (the next rungs) and the ladder's ``top``, an
    eigenvalue above the answer whose tail is not below ``candidate_tail`` is a candidate
    too where its tail falls fast enough (:data:`SCREEN_RATE_RUNGS`): it continues as the
    mutually nearest eigenvalue of a dense solve at each of them, its tail falls at each,
    and at the slowest of those geometric rates it reaches ``policy.tail_tol`` by
    N = ``top``. With a list ``suspects``, the eigenpairs above the answer that are not
    candidates but whose tail is below :data:`SUSPECT_TAIL`, away from the dilute top's
    continuum, are appended to it (for :func:`beyond_the_ladder`)."""
    search = policy.search
    n = search.n
    p = stability_operator(flow, n, bool(kz), cache=cache).pencil(kx, kz)
    floor = -math.inf
    if answer is not None:
        floor = answer.alpha.real + max(
            answer.drift if math.isfinite(answer.drift) else 0.0, policy.drift_tol
        )
    got = _spectrum_above(p, answer, floor if math.isfinite(floor) else None)
    if got is None:
        return []
    w, V = got
    above = np.nonzero(w.real > floor)[0]
    if len(above) == 0:
        return []
    t = tails(p, V[:, above], policy.tail_terms)
    slow = t >= search.candidate_tail
    falls = np.zeros(len(above), dtype=bool)
    finer = [m for m in (finer or []) if m > n]
    if finer and top is not None and np.any(slow):
        falls = slow & _tail_falls_in_time(flow, kx, kz, answer, policy, cache, w[above], t, n, finer, top)
    out: list[tuple[complex, np.ndarray, float]] = []
    at, radius = _top_continuum(flow, kx, kz)
    unresolved: list[tuple[complex, int, float]] = []  # not candidates, outside the radius
    for j, tj, fj in zip(above, t, falls):
        a = complex(w[j])
        if tj >= search.candidate_tail and not fj:
            if abs(a - at) > radius:
                unresolved.append((a, int(j), float(tj)))
            continue
        if answer is not None and abs(a - answer.alpha) <= 1e-3 * max(abs(answer.alpha), 1e-3):
            continue
        if kx == 0 and any(abs(a - b.conjugate()) <= 1e-8 * max(abs(a), 1.0) for b, _, _ in out):
            continue
        out.append((a, V[:, j], float(tj)))
    if suspects is not None:
        # below the bands' tails, and alone there (a band's members have like tails)
        for i, (a_u, j_u, t_u) in enumerate(unresolved):
            others = [u[2] for k, u in enumerate(unresolved) if k != i]
            if t_u < SUSPECT_TAIL and t_u < SUSPECT_ALONE * min(others, default=math.inf):
                suspects.append((a_u, V[:, j_u], t_u))
    return out


def _tail_falls_in_time(
    flow, kx, kz, answer, policy, cache, a1: np.ndarray, t1: np.ndarray, n1: int, finer: list[int], top: int
) -> np.ndarray:
    """For the eigenvalues ``a1`` (tails ``t1``) of the screen at N = ``n1``: whether each
    continues, as the mutually nearest eigenvalue of a dense solve at each resolution of
    ``finer`` in turn, with a tail that falls at every step and that, falling on from the
    last at the slowest of those geometric rates in N, reaches ``policy.tail_tol`` by
    N = ``top`` (:data:`SCREEN_RATE_RUNGS`)."""
    ok = np.ones(len(a1), dtype=bool)
    alpha, tail, n_prev = a1.copy(), t1.copy(), n1
    rate = np.full(len(a1), -np.inf)  # the slowest ln(tail) per unit N so far (< 0)
    lo = float(np.min(a1.real))
    lo -= 0.5 * (abs(lo) + 1e-3)
    for n in finer:
        p = stability_operator(flow, n, bool(kz), cache=cache).pencil(kx, kz)
        got = _spectrum_above(p, answer, None)  # the eigenvalues followed lie above lo
        if got is None:
            return np.zeros(len(a1), dtype=bool)
        w, V = got
        near = np.nonzero(w.real > lo)[0]
        if len(near) == 0:
            return np.zeros(len(a1), dtype=bool)
        b, t = w[near], tails(p, V[:, near], policy.tail_terms)
        d = np.abs(alpha[:, None] - b[None, :])
        to_n = np.argmin(d, axis=1)  # nearest at n of each followed eigenvalue
        back = np.argmin(d, axis=0)  # nearest among those of each at n
        mutual = back[to_n] == np.arange(len(a1))
        falls = t[to_n] < tail
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.log(t[to_n] / tail) / (n - n_prev)
        # followed unambiguously only where it moves by less than half the distance to its
        # nearest neighbour at n; and an eigenvalue pinned while its tail is unresolved is
        # the dilute top's continuum (modes.direct_mode's rule; CONTINUUM_NEAR)
        step = np.abs(b[to_n] - alpha)
        gap = np.abs(b[:, None] - b[None, :])
        gap[np.diag_indices_from(gap)] = np.inf
        alone = step < 0.5 * gap.min(axis=1)[to_n]
        # (a tail that falls tenfold a rung converges as a mode's does, pinned or not)
        moves = (step >= CONTINUUM_DRIFT * np.maximum(1.0, np.abs(alpha))) | (
            t[to_n] <= CONTINUUM_TAIL_FALL * tail
        )
        ok &= mutual & falls & alone & moves
        rate = np.maximum(rate, np.where(ok, r, 0.0))
        alpha, tail, n_prev = b[to_n], t[to_n], n
    with np.errstate(divide="ignore", invalid="ignore"):
        n_pass = n_prev + np.log(policy.tail_tol / tail) / rate
    return ok & ((tail <= policy.tail_tol) | (n_pass <= top))


#: The screen resolves what the answer needed. A mode's eigenvector tail falls about
#: exponentially in N, so one that passes the tail test (1e-7) only at N_a has a tail of
#: ~(1e-7)^(48/N_a) at the screen's N = 48: above the screen's candidate_tail (5e-4) once
#: N_a > 2 × 48. Where the least-stable mode found passes the tests only at N_a >
#: SCREEN_REPEAT × the screen's N, the screen is repeated at N_a itself, taking as
#: candidates the eigenvalues above it whose tail there is below tail_tol^SCREEN_TAIL_POWER
#: (1.3e-5: modes that pass the test by ~1.4 N_a), not the near-neutral band of the dilute
#: top, whose tails stay ~1e-4 … 1e-3 at such N. Measured: θ = 20.296°, ν0(0) = 0.0098,
#: φ = 0.0614, Φ = 0.371 at (k_x, k_z) = (0.005239, 0.165887) answered −1.01264 − 0.18236i
#: (passes at N = 148) while the mode −0.79359 − 0.26440i (dense QZ at N = 200 and 300,
#: tails 2e-7, 4e-9) had tails 2e-3 … 7e-3 at N = 48 and was no candidate.
SCREEN_REPEAT = 2.0
SCREEN_TAIL_POWER = 0.7
# The same for a flagged answer of the search (an undecided candidate at N_a, in
# search_above): the screen is repeated at the first rung ≥ SCREEN_REPEAT × N_a, and a less
# damped answer from there replaces it. Measured (try_random_points seeds 663316, 755525):
# at θ = 15.654°, ν0(0) = 0.0358, φ = 0.0649, Φ = 0.343, (0.009377, 0.055339) the mode
# −0.022472 − 0.032295i (dense QZ at N = 350, tail 6e-9) was lost by its follow at N = 94
# and −0.0867 − 0.0505i (undecided at N = 94) answered, flagged; now −0.0224719 −
# 0.0323141i, flagged (drift 6.9e-5 at N = 256), in 7.5 s instead of 0.6. At θ = 16.043°,
# ν0(0) = 0.009, φ = 0.0548, Φ = 0.4, (0.031534, 0.064652): −0.2202 − 0.3230i (N = 94) →
# −0.0890105 − 0.3291142i (N = 256, drift 1.6e-4; dense QZ at N = 250: −0.0890619 −
# 0.329074i), 7.2 s.


def search_above(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    answer: Mode | None,
    policy: RejectionPolicy,
    cache: OperatorCache,
    rungs: list[int] | None = None,
) -> Mode | None:
    """The least-stable mode by the contract of this module, given a tracked or direct
    ``answer``: candidates above it from one dense solve (:func:`global_candidates`),
    followed on ``rungs`` (default ``policy.search.ladder``) until decided
    (:func:`follow_candidate`). Returns the answer, a candidate that passes both tests and
    is less damped, or, where a candidate above the best resolved mode stays undecided,
    that candidate flagged (``physical = False``) with the resolved mode in its note.
    With ``answer=None`` (the search from scratch, where the continuation lost the branch
    in 3D) every candidate is above; None when the dense solve has none. Where the mode
    found passes the tests only at N > :data:`SCREEN_REPEAT` × the screen's N, the screen
    is repeated at that mode's check resolution (finer modes above it are candidates only
    there, with the tail a mode as fine as it would have)."""
    search = policy.search
    if search.max_candidates == 0:
        return answer
    if rungs is None:
        rungs = search.ladder(policy.n_max, policy.n_growth)
    # the rate rule's screens on the next rungs of the search's ladder (SCREEN_RATE_RUNGS)
    early: list[_Candidate] = []
    found = _search_once(
        flow, kx, kz, answer, policy, cache, rungs, rungs[1 : SCREEN_RATE_RUNGS + 1], early=early
    )
    screened = search.n
    while found is not None and found.physical and found.n > SCREEN_REPEAT * screened:
        n2 = found.n
        suspects: list = []
        found = _search_once(
            flow,
            kx,
            kz,
            found,
            _repeated(policy, n2),
            cache,
            [r for r in rungs if r >= n2] or [n2],
            suspects=suspects,
            early=early,
        )
        screened = n2
        if found is not None and found.physical and suspects:
            beyond = beyond_the_ladder(flow, kx, kz, found, suspects, n2, policy, cache, rungs[-1])
            if beyond is not found:
                return beyond  # (no screen is repeated beyond the ladder)
    if found is not None and not found.physical and found.method == "global":
        # a flagged answer of the search, decided at a coarse N: screened once more at the rung
        # of twice its N, where a mode that resolves slowly has a tail a mode as fine has
        # (SCREEN_REPEAT)
        n2 = next((r for r in rungs if r >= SCREEN_REPEAT * found.n), rungs[-1])
        if n2 > found.n:
            again = _search_once(
                flow, kx, kz, found, _repeated(policy, n2), cache, [r for r in rungs if r >= n2], early=early
            )
            if again is not None and again.alpha.real > found.alpha.real + max(found.drift, again.drift):
                found = again
        return _finished(found, early, rungs)
    return found


def _finished(found: Mode, early: list[_Candidate], rungs: list[int]) -> Mode:
    """The flagged answer ``found`` of the search, or, where it is a candidate the hopeless
    rule left undecided before the ladder's top (one of ``early``), that candidate followed on
    to the top (:meth:`_Candidate.finish`): its estimate there, flagged while undecided, the
    answer where it passes both tests. Where it is decided no mode or below the resolved mode
    on the way, the early estimate stays the answer, flagged, and its note says so: the
    search's rules that set a candidate aside are not proof that no mode lies near it (a
    candidate lost by a hop onto a neighbour, test_resolver's seed 663316), and a flagged
    answer is the conservative one."""
    c = next((c for c in early if c.mode is not None and c.mode.alpha == found.alpha), None)
    if c is None or c.finishing:
        return found
    f = c.finish(rungs)
    m = f.mode
    if m is not None and f.verdict in ("undecided", "mode"):
        how = "passes both tests" if f.verdict == "mode" else "is not decided"
        note = (
            f"followed on to N = {m.n}, it {how} (drift {m.drift:.1e}, tail {m.tail:.1e}): the estimate there"
        )
        return dataclasses.replace(m, method="global", note=join_notes(found.note, note))
    note = f"followed on, it was decided {f.verdict!r} ({f.why}); the answer stays flagged"
    return dataclasses.replace(found, note=join_notes(found.note, note))


#: Beyond the ladder (:func:`beyond_the_ladder`). At the repeated screen (:data:`SCREEN_REPEAT`)
#: the near-neutral band and the arcs of the dilute top's continuum have tails ~1e-4 … 1e-3
#: that stall (×0.8 … 0.9 a rung up to N ≈ 370), while a mode whose eigenvector needs
#: N ≈ 400–500 has a tail just below them that then falls ever faster. Measured: θ = 19.79°,
#: ν0(0) = 0.164, φ = 0.0901, Φ = 0.442 at (k_x, k_z) = (0.005189, 0.156833)
#: (try_random_points seed 906686; docs/numerics.md "A mode slower than the ladder"): at
#: the repeated screen's N = 118 the mode −0.0781 − 0.0201i has tail 7.8e-5, the band beside
#: it 2.9e-4, 3.1e-4 …; followed on at N = 150, 188, 235, 294, 367 the mode's tail is 6.4e-5,
#: 2.0e-5, 8.1e-6, 2.1e-6, 3.6e-7 (its eigenvalue −0.079675 − 0.023845i at 367, dense QZ
#: −0.079620 − 0.023865i at N = 550), the band members' 2.6e-4 … 8.8e-5 and 3.4e-4 …
#: 1.1e-4; the arc along Im α_top 1.8e-3 → 5.4e-4. The answer −0.106954 − 0.225388i had been
#: reported as converged. So the eigenvalues above the answer (outside the continuum's
#: radius) with a tail below SUSPECT_TAIL at the repeated screen are suspects, followed on
#: (at most SUSPECTS of them, the smallest tails first) on rungs × ``policy.n_growth`` up
#: to BEYOND × the ladder's top, never beyond N = BEYOND_MAX (a dense 3D pencil of 5 × 513
#: rows: 0.1 GB a matrix, 1.2 s a build and 1.8 s a shift-invert solve here). One whose
#: tail falls below CONTINUUM_RESOLVED is a mode (the answer, flagged unless it passes both
#: tests there); one whose tail has not fallen by STALL_FALL over three rungs while at a
#: band's level (BAND_TAIL) is not; the others are not decided (the answer flagged).
SUSPECT_TAIL = 1e-4
SUSPECTS = 2
BEYOND = 2.0
BEYOND_MAX = 512
STALL_FALL = 0.2
#: ... and only one whose tail is below SUSPECT_ALONE × every other unresolved eigenvalue's
#: above the answer (outside the continuum's radius) is a suspect: the mode above has
#: 7.8e-5 against 2.9e-4 (0.27), the suspect of BAND_TAIL 6.2e-5 against 1.5e-4 (0.41),
#: while at P1, (k_x, k_z) = (0.002, 0.02), N = 156 four members of one band have 6.5e-5,
#: 6.8e-5, 8.4e-5, 9.0e-5 (0.95): followed, they stall (not modes) at a cost of 2.7 s, which
#: made the question 5.0 s instead of 2.2 (benchmarks/bench_oblique.py).
SUSPECT_ALONE = 0.5
#: A suspect that stalls with its tail below BAND_TAIL is below every band member measured
#: (8.8e-5 … 5.4e-4 at N = 367 above) and not decided: θ = 20.575°, ν0(0) = 0.041,
#: φ = 0.0748, Φ = 0.452 at (0.004504, 0.107621) (try_random_points seed 663316), from
#: −0.12653 − 0.04291i (tail 6.2e-5 at N = 118) the tail is 4.7e-5, 1.4e-5, 1.2e-5, 5.8e-6,
#: 6.8e-6, 5.0e-6, 2.7e-6 at N = 148 … 512 (×0.4 … 0.5 over three rungs, a band's fall)
#: while the eigenvalue moves by 1.4e-3 … 7e-3 a rung (dense QZ −0.12706 − 0.04797i at
#: N = 250, −0.12817 − 0.04924i at 350): the answer −0.167924 − 0.260349i is flagged.
BAND_TAIL = 1e-5


def beyond_the_ladder(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    best: Mode,
    suspects: list,
    n_from: int,
    policy: RejectionPolicy,
    cache: OperatorCache,
    top: int,
) -> Mode:
    """The answer ``best`` (a mode that passes both tests), or what lies above it past the
    ladder's ``top``: the repeated screen's ``suspects`` (eigenpairs at N = ``n_from`` with
    their tails, :func:`global_candidates`) followed on (:data:`SUSPECT_TAIL`). A suspect
    whose eigenvector resolves is a mode, the answer, flagged unless it passes both tests;
    one left undecided (its tail below every band's, :data:`BAND_TAIL`, but not resolved)
    is the answer flagged, as a candidate undecided at the ladder's end is."""
    floor = best.alpha.real + max(best.drift, policy.drift_tol)
    picks = sorted((s for s in suspects if s[0].real > floor), key=lambda s: s[2])[:SUSPECTS]
    reach = min(int(BEYOND * top), BEYOND_MAX)
    found: list[tuple[Mode, str, complex]] = []
    for a, v, t in picks:
        verdict, m = _follow_beyond(flow, kx, kz, a, v, t, n_from, policy, cache, reach)
        if (
            m is not None
            and verdict != "not a mode"
            and m.alpha.real > best.alpha.real + max(best.drift, m.drift)
        ):
            found.append((m, verdict, a))
    if not found:
        return best
    m, verdict, start = max(found, key=lambda f: f[0].alpha.real)
    what = "a mode" if verdict == "mode" else "an eigenvalue, not decided,"
    note = (
        f"{what} above the least-stable resolved mode {best.alpha:.6g} (N = {best.n}) beyond the "
        f"ladder (N ≤ {top}): followed from {start:.6g} at N = {n_from} to N = {m.n} "
        f"(drift {m.drift:.1e}, tail {m.tail:.1e})"
    )
    return dataclasses.replace(m, method="global", note=join_notes(m.note, note))


def _follow_beyond(flow, kx, kz, a, v, t, n_from, policy, cache, reach) -> tuple[str, Mode | None]:
    """The eigenpair (``a``, ``v``) at N = ``n_from`` (tail ``t``) followed by shift-invert on
    rungs × ``policy.n_growth`` up to ``reach``: ("mode", its Mode at the last rung) once its
    tail has fallen below :data:`CONTINUUM_RESOLVED` (drift against the rung before);
    ("not a mode", None) where its tail stalls (:data:`STALL_FALL`) at a band's level
    (≥ :data:`BAND_TAIL`); otherwise ("undecided", its Mode at the last rung)."""
    seen, n_prev, mode = [t], n_from, None
    n, last = n_from, None
    while True:
        n = min(reach, round(n * policy.n_growth))
        if n <= n_prev:
            break
        p = stability_operator(flow, n, bool(kz), cache=cache).pencil(kx, kz)
        try:
            b, w = nearest_eigenpair(p, a, v0=interp_vector(v, len(p.fields), n_prev, n))
        except ConvergenceError:
            break
        m = make_mode(p, b, w, abs(b - a), n_prev, policy)
        seen.append(m.tail)
        last = m
        if m.tail < CONTINUUM_RESOLVED:
            mode = m
            if m.physical:
                return "mode", m
        elif mode is not None:
            return "mode", mode
        elif len(seen) >= 4 and seen[-1] > STALL_FALL * seen[-4] and m.tail >= BAND_TAIL:
            return "not a mode", None
        a, v, n_prev = b, w, n
    if mode is not None:
        return "mode", mode
    return "undecided", last


def _repeated(policy: RejectionPolicy, n: int) -> RejectionPolicy:
    """The policy of the screen repeated at N = ``n`` (:data:`SCREEN_REPEAT`): candidates are
    the eigenvalues whose tail there is below tail_tol^SCREEN_TAIL_POWER."""
    search = dataclasses.replace(policy.search, n=n, candidate_tail=policy.tail_tol**SCREEN_TAIL_POWER)
    return dataclasses.replace(policy, search=search)


def _search_once(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    answer: Mode | None,
    policy: RejectionPolicy,
    cache: OperatorCache,
    rungs: list[int],
    finer: list[int] | None = None,
    suspects: list | None = None,
    early: list | None = None,
) -> Mode | None:
    """One screen at ``policy.search.n`` (with the rate rule's ``finer`` resolutions, see
    :func:`global_candidates`, which appends to ``suspects``) and its candidates followed
    (:func:`search_above`). Where the answer is a candidate the hopeless rule left undecided
    before the ladder's top, its :class:`_Candidate` is appended to ``early``."""
    search = policy.search
    cands = global_candidates(flow, kx, kz, answer, policy, cache, finer, rungs[-1], suspects)
    if not cands:
        return answer
    # the least-stable mode that passes both tests, and the candidates not decided
    best = answer if answer is not None and answer.physical else None
    undecided: list[Followed] = []
    if answer is not None and not answer.physical:
        undecided.append(Followed(answer.alpha, answer, "undecided", ""))
    notes: list[str] = []
    active = [
        _Candidate(flow, kx, kz, a, v, search.n, policy, cache, tail=t, top=rungs[-1])
        for a, v, t in cands[: search.max_candidates]
    ]
    for c in active:
        c.answer = answer
    followed_all = list(active)
    rest = cands[search.max_candidates :]
    undecided += [Followed(a, None, "undecided", "not followed") for a, _, _ in rest]
    # every candidate advances rung by rung (each operator is built once), best first; a
    # candidate below the least-stable mode that passes both tests needs no more solves
    for i, nn in enumerate(rungs):
        if not active:
            break
        for c in sorted(active, key=lambda c: -c.alpha.real):
            err = c.mode.drift if c.mode is not None and math.isfinite(c.mode.drift) else 0.0
            if best is not None and c.alpha.real + err <= best.alpha.real:
                c._decide("below", f"Re α = {c.alpha.real:.6g} at N = {c.n_from}")
                continue
            f = c.step(nn, best.alpha.real if best is not None else -math.inf, len(rungs) - 1 - i)
            if (
                f is not None
                and f.verdict == "mode"
                and f.mode is not None
                and (best is None or f.mode.alpha.real > best.alpha.real)
            ):
                if answer is not None:
                    notes.append(
                        f"the tracked/direct answer {answer.alpha:.6g} (N = {answer.n}, "
                        f"{'passes' if answer.physical else 'fails'} the tests) is more damped than "
                        f"this mode, found by the global solve at N = {search.n}"
                    )
                best = f.mode
        undecided += [c.done for c in active if c.done is not None and c.done.verdict == "undecided"]
        active = [c for c in active if c.done is None]
    undecided += [c.result() for c in active]
    if best is None:
        # nothing passes the tests: the least damped of the undecided, flagged
        followed = [f for f in undecided if f.mode is not None]
        if not followed:
            return answer
        top = max(followed, key=lambda f: f.mode.alpha.real)  # type: ignore[union-attr]
        assert top.mode is not None
        if top.mode is answer:
            return answer
        _note_early(top, followed_all, early)
        return dataclasses.replace(
            top.mode,
            method="global",
            note=join_notes(
                top.mode.note,
                f"no mode passes both tests; this candidate is not decided by N = {top.mode.n} "
                f"(drift {top.mode.drift:.1e}, tail {top.mode.tail:.1e}): {top.why}"
                + (
                    f"; the tracked/direct answer {answer.alpha:.6g} is more damped"
                    if answer is not None
                    else ""
                ),
            ),
        )
    above = [
        f
        for f in undecided
        if f.mode is not None and f.mode.alpha.real > best.alpha.real + max(best.drift, f.mode.drift)
    ]
    not_followed = [f for f in undecided if f.mode is None and f.start.real > best.alpha.real]
    if above:
        top = max(above, key=lambda f: f.mode.alpha.real)  # type: ignore[union-attr]
        assert top.mode is not None
        _note_early(top, followed_all, early)
        note = join_notes(
            top.mode.note,
            f"a candidate above the least-stable resolved mode {best.alpha:.6g} (N = {best.n}) is not "
            f"decided by N = {top.mode.n} (drift {top.mode.drift:.1e}, tail {top.mode.tail:.1e})"
            + (f": {top.why}" if top.why and top.mode is not answer else ""),
        )
        return dataclasses.replace(
            top.mode, method=top.mode.method if top.mode is answer else "global", note=note
        )
    if not_followed:
        note = join_notes(
            best.note,
            *notes,
            f"{len(not_followed)} candidate(s) above it not followed (search.max_candidates = "
            f"{search.max_candidates}), e.g. {not_followed[0].start:.6g} at N = {search.n}",
        )
        return dataclasses.replace(best, physical=False, note=note)
    rejected = _rejected_above(followed_all, best)
    if best is answer and not rejected:
        return answer
    return dataclasses.replace(
        best, method=best.method if best is answer else "global", note=join_notes(best.note, *notes, rejected)
    )


def _note_early(top: Followed, followed: list[_Candidate], early: list | None) -> None:
    """Append to ``early`` the candidate whose verdict is ``top`` where the hopeless rule gave
    it before the ladder's top (:meth:`_Candidate.finish`)."""
    c = next((c for c in followed if c.done is top), None)
    if early is not None and c is not None and c.hopeless:
        early.append(c)


def _rejected_above(followed: list[_Candidate], best: Mode) -> str:
    """The note that names the eigenvalues above the answer decided "not a mode" (the least
    damped first, at most :data:`REJECTED_NAMED`, each with the evidence): by the contract
    they are no modes — the dilute top's continuum, an eigenvalue whose eigenvector's tail
    does not converge —, and a researcher sees what was set aside (e.g. an eigenvalue that
    settles while its eigenvector does not: a point of a continuous spectrum, which a band
    fills in as N grows)."""
    out = [
        c.done
        for c in followed
        if c.done is not None
        and c.done.verdict == "not a mode"
        and c.done.mode is not None
        and c.done.mode.alpha.real > best.alpha.real
    ]
    if not out:
        return ""
    out.sort(key=lambda f: -f.mode.alpha.real)  # type: ignore[union-attr]
    named = []
    for f in out[:REJECTED_NAMED]:
        m = f.mode
        assert m is not None
        named.append(f"{m.alpha:.6g} (N = {m.n}, drift {m.drift:.1e}, tail {m.tail:.1e}): {f.why}")
    more = f"; and {len(out) - REJECTED_NAMED} more" if len(out) > REJECTED_NAMED else ""
    return f"{len(out)} eigenvalue(s) above it decided not modes: " + "; ".join(named) + more


#: How many of the eigenvalues set aside above the answer its note names (the least damped).
REJECTED_NAMED = 3
