"""After the tracker lost the α(0) = 0 branch (paper §4.1–4.2, docs/numerics.md).

Where the branch's phase velocity enters the range of the base velocity u0(y), its
eigenvector develops a critical layer and the continuation of :mod:`.tracking` loses it.
The fallbacks: the branch followed again with the tail threshold relaxed
(:func:`near_continuum_branch`, :func:`relaxed_branch_modes`), the band search past
``RejectionPolicy.relaxed_k_max`` (:func:`after_lost_branch`), and the direct solves at k
(:func:`_direct_ladder`), with the one rule of which answer outranks which
(:func:`_better`, :meth:`RejectionPolicy.direct_outranks_relaxed`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from ..errors import ConvergenceError
from ..steady import SteadyFlow
from .modes import (
    Mode,
    OperatorCache,
    direct_mode,
    drift_of,
    join_notes,
    make_mode,
    mode_near,
    mode_score,
    resolve_policy,
    spectrum,
)
from .policy import RejectionPolicy
from .tracking import BranchTracker


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
    ``policy.tracking.relaxed_tail``: the fallback where :class:`BranchTracker` lost the branch.

    The tracker loses the branch where its phase velocity −Im α/k enters the range of the
    base velocity u0(y) (e.g. θ = 16.5°, ν0(0) = 0.13, φ = 0.08, Φ = 0.30 at k ≈ 0.0036:
    Im α/k ≈ −3.8 against u0 ∈ [2.92, 3.88]): the eigenvector develops a critical layer
    whose Chebyshev tail (1e-6 … 1e-4) exceeds the tracking threshold, and the steps halve
    until they stall. The continuation is redone from k = 0 with the threshold
    ``policy.tracking.relaxed_tail``, to the targets k/m, 2k/m, …, k for m in
    ``policy.tracking.relaxed_splits``
    (the predictor still has to hit within a quarter of each step, so the answer is the
    continuous continuation of the branch). The mode is judged by ``policy`` (the paper's
    drift and tail tests: it is returned flagged when it fails them, with its drift
    |α(N) − α(N')| as the convergence estimate) and ``method = "branch (relaxed)"``.

    Returns None when no attempt reaches k, or the drift exceeds ``policy.tracking.relaxed_drift``
    |α| (no eigenvalue at N' continues it: not a trustworthy branch value).
    """
    policy = resolve_policy(policy)
    kk = math.hypot(k, kz)
    if kk == 0:
        return None
    direction = (k, kz)
    relaxed = policy.replace(
        track_tail_tol=max(policy.tracking.relaxed_tail, policy.track_tail_tol), n_start=n, n_max=n
    )
    for m in policy.tracking.relaxed_splits:
        tr = BranchTracker(flow, n, direction=direction, policy=relaxed, cache=cache)
        try:
            for target in np.linspace(0.0, kk, m + 1)[1:]:
                alpha, w = tr.advance(float(target))
            pencil = tr._pencil(kk)
            drift, n2 = drift_of(flow, alpha, w, n, k, kz, tr.three_d, cache=cache)
        except ConvergenceError:
            continue
        if not drift <= policy.tracking.relaxed_drift * abs(alpha):
            continue
        mode = make_mode(pencil, alpha, w, drift, n2, policy)
        u = tr._operator(n).base["u"]
        note = _relaxed_note(alpha, kk, (float(np.min(u)), float(np.max(u))), policy)
        return dataclasses.replace(mode, method="branch (relaxed)", note=note)
    return None


def _relaxed_note(alpha: complex, k: float, u_range: tuple[float, float], policy: RejectionPolicy) -> str:
    """The note of a branch value followed with the relaxed tail threshold."""
    return (
        f"branch followed with eigenvector tails up to {policy.tracking.relaxed_tail:g} (the tracking "
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
    turn with the tail threshold relaxed to ``policy.tracking.relaxed_tail``; it stops at the first k
    not reached, or where the drift exceeds ``policy.tracking.relaxed_drift`` |α| (no eigenvalue at N'
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
    relaxed = policy.replace(
        track_tail_tol=max(policy.tracking.relaxed_tail, policy.track_tail_tol), n_start=n, n_max=n
    )
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
        if not drift <= policy.tracking.relaxed_drift * abs(alpha):
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
    ``policy.tracking.band_radius`` drifts of the relaxed value, and the eigenvalue there whose tail is
    smallest, by at least ``policy.tracking.band_tail_gain``, replaces it (the branch: at P4, k = 0.5 it
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
    radius = policy.tracking.band_radius * relaxed.drift
    band = [m for m in modes if abs(m.alpha - relaxed.alpha) <= radius]
    if band:
        best = min(band, key=lambda m: m.tail)
        if best.tail <= policy.tracking.band_tail_gain * relaxed.tail:
            relaxed = dataclasses.replace(
                best,
                method="branch (relaxed)",
                note=join_notes(
                    relaxed.note,
                    f"the continuation landed on {relaxed.alpha:.6g} (tail {relaxed.tail:.1e}) in a "
                    f"band of unresolved eigenvalues; the branch is the one of least tail within "
                    f"{policy.tracking.band_radius:g} drifts",
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


def _direct_candidate(flow, k, kz, n, seed: Mode | None, policy, cache) -> Mode | None:
    """The least-stable mode of a direct solve at (k, kz) and N, for
    :func:`least_stable` below the continuum after the branch was lost: the previous rung's
    candidate ``seed`` followed by shift-invert near its eigenvalue when it was converging
    (drift below ``policy.tracking.seed_drift``), else dense QZ (:func:`direct_mode`)."""
    if seed is not None and seed.drift < policy.tracking.seed_drift:
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
    # no candidate from the shift-invert road: a dense QZ at every rung
    for nn in policy.ladder():
        mode = direct_mode(flow, k, n=nn, policy=policy, cache=cache)
        if mode is None:
            continue
        if mode.physical:
            return mode
        if _better(mode, best, policy):
            best = mode
    if best is None:
        raise ConvergenceError(
            f"least-stable mode at theta = {flow.theta:g}, nu0 = {flow.nu0:g}, k = {k:g}: "
            f"no finite eigenvalue up to N = {policy.n_max}"
        )
    return best


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
