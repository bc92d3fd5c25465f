"""Candidate modes followed past the transverse branch (k_x = 0; paper §5.3).

Where the tracked α(0) = 0 branch enters the continuum of the dilute top
(:class:`~chuteflow.stability.transverse_tracking.TransverseTracker`), the least-stable
physical mode at larger k_z is another one: :func:`_beyond_branch` follows a few candidates
taken from one coarse dense eigensolve (re-seeded whenever k_z has grown by
``TransverseTrackingPolicy.reseed_ratio`` or every candidate is lost), each by shift-invert
on the real form of the pencil, and judges them (drift and tail, N raised along the ladder)
by :func:`_judge_complex`. Used by :func:`chuteflow.stability.transverse_dispersion` with
``beyond=True``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import ConvergenceError
from .modes import Mode, check_n, interp_vector, make_mode, stability_operator, tail, tails
from .realform import _nearest_kx0, _seed_spectrum
from .transverse_tracking import TransverseTrackingPolicy


def _seed_candidates(flow, kz, policy, cache, knobs: TransverseTrackingPolicy):
    """Candidate eigenpairs at (0, k_z) from one coarse dense eigensolve (N = ``knobs.seed_n``,
    real form, :func:`_seed_spectrum`), best first, one of each conjugate pair: those whose
    eigenvectors are nearly resolved there (tail < 1e-4; the continuum of the dilute top is
    dropped by |α| > 1e-5 and by the tail test at N). Returns [(α, eigenvector of the
    equilibrated pencil at N = ``knobs.seed_n``)]: the vector starts the shift-invert at N
    (without it the inverse iteration starts from a random vector and often falls back on
    Arnoldi)."""
    op = stability_operator(flow, knobs.seed_n, True, cache=cache)
    w, V = _seed_spectrum(op, kz, knobs.seed_shift)
    t = tails(op.pencil(0.0, kz), V, policy.tail_terms)
    keep = np.nonzero((t < 1e-4) & (w.imag >= 0) & (np.abs(w) > 1e-5))[0][: 2 * knobs.candidates]
    return [(complex(w[i]), V[:, i]) for i in keep]


def _beyond_branch(flow, ks, n, policy, cache, knobs: TransverseTrackingPolicy):
    """Least-stable physical mode at each k_z of ``ks`` (increasing, past the tracked
    branch): candidates seeded by a coarse dense scan (again whenever k_z has grown by
    ``knobs.reseed_ratio`` or every candidate is lost), followed by shift-invert from their
    last eigenvectors at the N where the last winner passed (``n`` again at each seeding),
    N raised along the ladder while not physical. Seeds that cannot reach the best
    ``knobs.candidates`` found, and candidates just lost on the same pencil, are not solved
    (again)."""
    nf = 5
    out: list[Mode | None] = []
    # candidates: (α, start vector, the N of that vector)
    cands: list[tuple[complex, np.ndarray, int]] = []
    k_seed = None
    n_cur = n
    for k in ks:
        k = float(k)
        found: list = []
        for attempt in range(2):
            if not cands or attempt == 1 or (k_seed is not None and k >= knobs.reseed_ratio * k_seed):
                if attempt == 1 and n_cur == n:
                    if k_seed == k:
                        break  # seeded here already: the same seeds would be lost again
                    # every candidate was just lost on this very pencil: solving them again
                    # from the same shifts and vectors would give the same answers
                    cands = []
                n_cur = n  # new candidates: from the first rung again
                seeds = [(a, v, knobs.seed_n) for a, v in _seed_candidates(flow, k, policy, cache, knobs)]
                cands = cands + seeds  # the followed ones first: their vectors are at N
                k_seed = k
            op = stability_operator(flow, n_cur, True, cache=cache)
            pencil = op.pencil(0.0, k)
            found = []
            for a, v, nv in cands:
                match = knobs.seed_match * max(abs(a), 1e-3)
                if nv == knobs.seed_n and any(
                    abs(a.real - f.real) + abs(abs(a.imag) - abs(f.imag)) <= match for f, *_ in found
                ):
                    continue  # a seed of an eigenvalue already followed
                if nv == knobs.seed_n and len(found) >= knobs.candidates:
                    # an accepted solve lies within 0.2 max(|a|, 1e-3) of the seed: one that
                    # cannot reach the best knobs.candidates found so far is not solved
                    kth = sorted((f.real for f, *_ in found), reverse=True)[knobs.candidates - 1]
                    if a.real + 0.2 * max(abs(a), 1e-3) < kth:
                        continue
                try:
                    alpha, w, _ = _nearest_kx0(op, k, a, v0=interp_vector(v, nf, nv, n_cur))
                except ConvergenceError:
                    continue
                if abs(alpha - a) > 0.2 * max(abs(a), 1e-3):
                    continue  # jumped to another eigenvalue
                alpha = complex(alpha)
                tol = 1e-8 * max(1.0, abs(alpha))
                near = [abs(alpha.real - f.real) + abs(abs(alpha.imag) - abs(f.imag)) for f, *_ in found]
                if near and min(near) <= tol:
                    continue  # the same eigenvalue or its conjugate
                t = tail(pencil.unscale(w), len(pencil.fields), policy.tail_terms)
                if t < policy.track_tail_tol:
                    found.append((alpha, w, t))
            found = sorted(found, key=lambda f: -f[0].real)[: knobs.candidates]
            if found:
                break
        cands = [(a, w, n_cur) for a, w, _ in found]
        mode = None
        for a, w, *_ in found:
            mode = _judge_complex(flow, k, a, w, n_cur, policy, cache)
            if mode.physical:
                break
        if mode is not None and mode.physical:
            n_cur = mode.n  # the next k_z starts where this one passed (until the next seeding)
        out.append(mode)
    return out


def _judge_complex(flow, kz, alpha, w, n, policy, cache) -> Mode:
    """Drift and tail of a shift-invert eigenpair at (0, k_z), N raised while not physical
    (at most three rungs), ``method = "shift"``:
    :func:`~chuteflow.stability.transverse.judge_resolved` on the real form
    (:func:`~chuteflow.stability.realform._nearest_kx0`). A rung's check resolution
    N' = round(0.8 N) is the rung before
    (80 → 100 → 125 → 156 …), where this eigenvalue was just solved: that α(N') is reused
    instead of solving again from the interpolated vector (the same eigenvalue at the same
    N, to the inverse iteration's tolerance 1e-7 |α − σ|)."""
    nf = 5
    mode = None
    before = None  # (N, α) of the rung before
    for nn in policy.ladder(n)[:3]:
        op = stability_operator(flow, nn, True, cache=cache)
        if nn != n:
            try:
                a_new, w, _ = _nearest_kx0(op, kz, alpha, v0=interp_vector(w, nf, n, nn))
            except ConvergenceError:
                break
            before = (n, alpha)
            alpha, n = a_new, nn
        n2 = check_n(nn)
        if before is not None and before[0] == n2:
            drift = abs(alpha - before[1])
        else:
            try:
                op2 = stability_operator(flow, n2, True, cache=cache)
                a2, _, _ = _nearest_kx0(op2, kz, alpha, v0=interp_vector(w, nf, nn, n2))
                drift = abs(a2 - alpha)
            except ConvergenceError:
                drift = math.inf
        mode = make_mode(op.pencil(0.0, kz), alpha, w, drift, n2, policy)
        if mode.physical:
            break
    assert mode is not None  # the ladder from n has at least one rung
    return dataclasses.replace(mode, method="shift")
