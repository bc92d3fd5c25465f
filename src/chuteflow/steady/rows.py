"""The scheduler of a row of steady flows at fixed θ (paper §3.2): continuation walks along
ν0(0), seeds from the neighbouring θ row, cold starts and shooting scans, in that order.
"""

from __future__ import annotations

import dataclasses
import functools

from ..closures import ChuteModel
from .continuation_step import _UNREACHED, _cold, _continue, _Point
from .options import Options
from .proofs import _HIGH_KINDS, _LOW_KINDS, Proof, _decide, _implied

#: A flow whose dense layer ends within this fraction of its thickness h below the top of
#: the domain (y_max − h < _TOP_GAP h: a cold top, the upper existence boundary near) is not
#: continued to a larger ν0(0): towards the boundary the layer's edge sharpens and meets the
#: top, and the Euler predictor misses (residuals 0.2–2.5, Newton stalls). Measured, steps up
#: in ν0(0) from such flows: on the 60 × 60 paper maps 51 of 51 failed
#: (φ = 0.05) and 56 of 56 (φ = 0.10); on the rows of the 60 × 60 φ = 0.05 diagram, whose ν0
#: steps are shorter, 91 of 111 (4.7 s of CPU, against 2.8 s for the 20 that converged).
#: Skipping them leaves the maps bit for bit the same and the diagram with every status and
#: stability label (13 flows reached by another road moved by ≤ 4.4e-10, within their
#: estimates; their dQ0/dρ̄0 by ≤ 1.2e-7), with 7–11 % less Newton work in its rows. The
#: point is still tried from its other neighbours and decided by the shooting scan: the
#: rule changes the road, never the answer. (At 0.3 the maps still lose no step, but the
#: diagram's rows lose 53 more that converge.)
_TOP_GAP = 0.1


def _top_bound(point: _Point) -> bool:
    """Whether ``point``'s dense layer ends within :data:`_TOP_GAP` h of the top of its
    domain (no continuation from it to a larger ν0(0))."""
    f = point.flow
    return f is not None and f.y_max - f.h < _TOP_GAP * f.h


_TOP_BOUND_MESSAGE = (
    "not continued from the smaller floor density: its dense layer ends at the top of the "
    "domain (the upper existence boundary is near)"
)


def _undecided_target(pts, settled, usable) -> int | None:
    """Next point to decide by the shooting scan: in a run of undecided points, the end
    next to a point where ``usable`` holds (a converged flow: the existence boundary is
    there; or a point the scan has decided), else the middle."""
    N = len(pts)
    runs, i = [], 0
    while i < N:
        if settled(i):
            i += 1
            continue
        j = i
        while j + 1 < N and not settled(j + 1):
            j += 1
        runs.append((i, j))
        i = j + 1
    for a, b in runs:
        if b + 1 < N and usable(b + 1):
            return b
        if a > 0 and usable(a - 1):
            return a
    if runs:
        a, b = runs[0]
        return (a + b) // 2
    return None


def _anchor_order(n: int) -> list[int]:
    """Cold-start candidates spread over the row: middle, quartiles, eighths, …"""
    order: list[int] = []
    seen: set[int] = set()
    k = 2
    while len(order) < n:
        for j in range(1, k, 2):
            i = min(n - 1, (j * n) // k)
            if i not in seen:
                seen.add(i)
                order.append(i)
        k *= 2
        if k > 4 * n:
            order += [i for i in range(n) if i not in seen]
            break
    return order


def continue_row(
    theta: float,
    nu0_values,
    model: ChuteModel,
    opts: Options,
    previous: list[_Point] | None = None,
    existing: list[_Point] | None = None,
    cold_starts: bool = True,
    proofs: list[Proof] | None = None,
) -> list[_Point]:
    """Solve at every ν0 of a row (sorted ascending) by continuation.

    A point is started from a converged neighbour: the one below or above in ν0 (predicted
    along the exact tangent), or the same ν0 in ``previous`` (the neighbouring θ row of a
    map; predicted along dX/dθ). Each source is tried once per point; a step up in ν0 from a
    flow whose layer reaches the top of its domain is not taken (:data:`_TOP_GAP`). Walks
    along ν0 go first; when they stall, one point is seeded from ``previous`` and the walks
    resume.
    When nothing more can be reached, a cold start is tried at a spread-out point not yet
    attempted (at most ``opts.max_cold`` per row, ``opts.max_cold_seeded`` if ``previous``
    is given: in a map the existence region is reached from the neighbouring rows).

    Continuation is only the fast road. Every point it does not reach is decided
    (``opts.decide``) by the shooting scan :func:`~chuteflow.steady.shooting.steady_existence`
    or by an earlier scan's verdict that covers it (:class:`~chuteflow.steady.proofs.Proof`;
    ``proofs`` collects them and may be shared by the rows of a map): no flow (with the scan's
    reason), or a flow, solved by Newton from the shot profile and then continued to its
    neighbours. A run of undecided points is scanned at its end next to a converged flow, where
    the existence boundary lies (or next to a point already scanned: outwards), so that one
    verdict usually settles the whole run; while such a run is undecided no cold start is tried,
    and none ever at a point a verdict covers. In a family (no ``previous``) a point where the
    scan finds a flow that Newton from the shot profile does not resolve gets the cold start as
    the last resort. With ``opts.decide = False`` the points continuation did not reach are
    'unreached'.
    """
    nus = [float(v) for v in nu0_values]
    N = len(nus)
    pts: list[_Point | None] = [None] * N
    tried: list[set] = [set() for _ in range(N)]
    if existing is not None:
        for i, p in enumerate(existing):
            if p is not None and p.status != _UNREACHED:
                pts[i], tried[i] = p, set(p.tried)
    prev = previous if previous is not None else [None] * N
    order = _anchor_order(N)
    # a θ source is identified by its angle, so that both neighbouring rows can be tried
    ttag = ("theta", next((p.flow.theta for p in prev if p is not None and p.flow is not None), None))
    proofs = proofs if proofs is not None else []
    memo: dict = {}  # continuation steps already tried in this row (see _continue)

    def usable(i):
        return pts[i] is not None and pts[i].usable

    def proven(i):
        # decided by the shooting scan (or a scan's covering verdict) to have no flow:
        # continuation does not try it again
        return not usable(i) and ("scan" in tried[i] or "proof" in tried[i])

    def settled(i):
        return usable(i) or "scan" in tried[i] or "proof" in tried[i]

    def anchor(i):
        # where a run of undecided points is decided from: next to a flow (the existence
        # boundary is there) or next to a scanned point (outwards from the boundary)
        return usable(i) or "scan" in tried[i]

    def open_(i):
        return not usable(i) and not proven(i)

    def attempt(i, tag, make):
        tried[i].add(tag)
        p = make()
        if pts[i] is None or p.usable:
            pts[i] = p

    cold = [0]

    def covering(i) -> Proof | None:
        # a scan's verdict that decides point i (no flow there), if any
        return next((q for q in proofs if q.covers(theta, nus[i])), None)

    def walk():
        while True:
            walked = False
            for i in range(1, N):
                below = pts[i - 1]
                if open_(i) and below is not None and below.usable and "below" not in tried[i]:
                    if _top_bound(below):
                        # recorded as a failed step, without its cost (_TOP_GAP)
                        attempt(i, "below", lambda: _Point("not_converged", None, _TOP_BOUND_MESSAGE))
                        continue
                    attempt(i, "below", functools.partial(_continue, below, theta, nus[i], model, opts, memo))
                    walked = True
            for i in range(N - 2, -1, -1):
                above = pts[i + 1]
                if open_(i) and above is not None and above.usable and "above" not in tried[i]:
                    attempt(i, "above", functools.partial(_continue, above, theta, nus[i], model, opts, memo))
                    walked = True
            if walked:
                continue
            seeded = [
                (i, src)
                for i in order
                if open_(i) and (src := prev[i]) is not None and src.usable and ttag not in tried[i]
            ]
            if seeded:
                i, seed = seeded[0]
                attempt(i, ttag, functools.partial(_continue, seed, theta, nus[i], model, opts, memo))
                continue
            if not cold_starts:
                return
            if opts.decide:
                # with the scan deciding, the ends of the pieces of the branch found so far
                # go first, outwards: the verdict there (a proof for a whole quadrant,
                # usually the rest of the run) says where a cold start is pointless (a
                # failed cold start costs ~0.15 s, a too_small verdict 0.04 s), and a scan
                # finds any other piece of the branch
                t = _undecided_target(pts, settled, anchor)
                if t is not None and any(0 <= j < N and anchor(j) for j in (t - 1, t + 1)):
                    return
            # walks stalled: a cold start where nothing has been attempted yet (a separate
            # piece of the branch, or no piece found so far), unless a scan's verdict
            # already proves that there is none
            cand = [i for i in order if not tried[i] and covering(i) is None]
            if previous is None and not cand and not opts.decide:
                # a family without the scan: points where continuation failed get a cold
                # start too (the isothermal start sometimes succeeds where a far
                # neighbour's predictor does not; with the scan, after it: see below)
                cand = [
                    i
                    for i in order
                    if open_(i)
                    and "cold" not in tried[i]
                    and ((i > 0 and usable(i - 1)) or (i < N - 1 and usable(i + 1)))
                ]
            if not cand or cold[0] >= (opts.max_cold if previous is None else opts.max_cold_seeded):
                return
            cold[0] += 1
            attempt(cand[0], "cold", functools.partial(_cold, theta, nus[cand[0]], model, opts))

    while True:
        walk()
        if not opts.decide:
            break
        target = _undecided_target(pts, settled, anchor)
        if target is None:
            break
        i = target
        cover = covering(i)
        if cover is not None:
            tried[i].add("proof")
            pts[i] = _implied(theta, nus[i], model, cover)
            continue
        tried[i].add("scan")
        p, v = _decide(theta, nus[i], model, opts)
        nb = [j for j in (i - 1, i + 1) if 0 <= j < N and usable(j)]
        if not p.usable and v is not None and v.exists and nb and "substeps" not in tried[i]:
            # the scan finds a flow that Newton from the shot profile does not resolve: next
            # to a converged flow, shorter continuation steps often reach it (a sharp layer
            # near the upper existence boundary). After the scan, not before: the scan's
            # verdict (5–30 ms) usually settles the point, shorter steps cost ~0.1 s
            tried[i].add("substeps")
            fine = dataclasses.replace(opts, substeps=max(opts.substeps, 2))
            seed = pts[nb[0]]
            assert seed is not None  # usable
            q = _continue(seed, theta, nus[i], model, fine, memo)
            p = q if q.usable else p
        if p.status == "not_converged" and previous is None and cold_starts and "cold" not in tried[i]:
            # a flow exists but Newton from the shot profile did not converge: the isothermal
            # cold start sometimes does (the family's rule for points where continuation
            # failed, above, applied after the scan)
            tried[i].add("cold")
            q = _cold(theta, nus[i], model, opts)
            p = q if q.usable else p
        pts[i] = p
        if v is not None and (v.kind in _LOW_KINDS or v.kind in _HIGH_KINDS) and p.status != "ok":
            proofs.append(Proof(theta, nus[i], v.kind, v.reason))
    out = []
    for pt, t in zip(pts, tried):
        point = (
            pt
            if pt is not None
            else _Point(
                _UNREACHED,
                None,
                "not reached: no converged neighbour to continue from and no cold start tried here",
            )
        )
        point.tried = frozenset(t)
        out.append(point)
    return out
