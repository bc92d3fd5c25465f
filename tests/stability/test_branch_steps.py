"""The branch tracker's work: steps memoised on the operator, and the tail-crossing rule.

Both are about cost, and both are checked against the behaviour they replace: a replayed
continuation gives the same numbers bit for bit with no new eigen-solve, and a continuation
stopped by the crossing rule stops where the old creeping continuation stopped.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.errors import ConvergenceError
from chuteflow.stability import BranchTracker, OperatorCache, RejectionPolicy, TrackingPolicy
from chuteflow.steady import solve_steady

tracking = importlib.import_module("chuteflow.stability.tracking")


@pytest.fixture(scope="module")
def crossing_flow():
    """A dense thin flow of the 60 × 60 φ = 0.05 diagram (h = 5.1) whose branch's
    eigenvector tail rises through the tracking threshold 1e-5 at k ≈ 9.97e-5 on N = 48 (its
    growth metric crept up to it: 53 solves)."""
    return solve_steady(14.745762711864, 0.217457627119, ChuteModel(roughness=0.05), min_thickness=0.0)


@pytest.fixture
def solves(monkeypatch):
    """Count the tracker's eigen-solves."""
    count = [0]
    solve = tracking.nearest_eigenpair

    def counted(*args, **kw):
        count[0] += 1
        return solve(*args, **kw)

    monkeypatch.setattr(tracking, "nearest_eigenpair", counted)
    return count


def test_a_replayed_continuation_is_the_same_without_solving(p1_flow, solves):
    cache = OperatorCache(2)
    a1, w1 = BranchTracker(p1_flow, 48, cache=cache).advance(0.01)
    first = solves[0]
    assert first > 3
    tr = BranchTracker(p1_flow, 48, cache=cache)
    a2, w2 = tr.advance(0.01)
    assert solves[0] == first  # every step served from the operator's memo
    assert a2 == a1
    assert np.array_equal(w2, w1)
    # a farther target shares the steps up to the last one before 0.01
    BranchTracker(p1_flow, 48, cache=cache).advance(0.02)
    shared = solves[0] - first
    solves[0] = 0
    BranchTracker(p1_flow, 48, cache=OperatorCache(2)).advance(0.02)
    fresh = solves[0]
    assert shared < fresh - 2
    # and a fresh operator gives the same value as the memo
    a3, _ = BranchTracker(p1_flow, 48, cache=OperatorCache(2)).advance(0.01)
    assert a3 == a1


def test_relaxed_tracker_reuses_the_strict_trackers_solves(crossing_flow, solves):
    """The solves do not depend on the tail threshold: where the strict tracker rejected a
    step by its tail, the relaxed one accepts the same solve without redoing it."""
    cache = OperatorCache(2)
    with pytest.raises(ConvergenceError, match="rises through the tracking threshold"):
        BranchTracker(crossing_flow, 48, n_max=48, cache=cache).advance(1e-4)
    strict = solves[0]
    relaxed = RejectionPolicy().replace(track_tail_tol=1e-3, n_start=48, n_max=48)
    a, _ = BranchTracker(crossing_flow, 48, policy=relaxed, cache=cache).advance(1e-4)
    assert solves[0] == strict  # reached 1e-4 on the strict tracker's solves
    solves[0] = 0
    b, _ = BranchTracker(crossing_flow, 48, policy=relaxed, cache=OperatorCache(2)).advance(1e-4)
    assert a == b
    assert solves[0] == strict


def test_tail_crossing_stops_where_creeping_stopped(crossing_flow, solves):
    """The crossing rule (TrackingPolicy.crossing_near): the continuation stops at the first step
    rejected by the branch's own tail, at the log-linear estimate of the crossing, where
    the old rule crept up to the same crossing in ever shorter steps."""
    with pytest.raises(ConvergenceError, match="rises through") as new:
        BranchTracker(crossing_flow, 48, n_max=48, cache=OperatorCache(2)).advance(1e-4)
    n_new = solves[0]
    k_new = float(str(new.value).split("near k = ")[1].split()[0])
    off = _rules_off()  # the old rules: creep
    solves[0] = 0
    tr = BranchTracker(crossing_flow, 48, n_max=48, policy=off, cache=OperatorCache(2))
    with pytest.raises(ConvergenceError, match="step shrank"):
        tr.advance(1e-4)
    k_creep = tr.history[-1][0]  # the crept limit: 9.97235e-5
    assert n_new <= 5
    assert solves[0] > 40
    assert abs(k_new - k_creep) < 1e-3 * k_creep  # measured 9.974e-5 against 9.97235e-5


@pytest.fixture(scope="module")
def spurious_flow():
    """A flow of the same diagram (θ = 17.19°, ν0(0) = 0.144) whose k = 0 null vector is not
    resolved at N = 48 and 60 (tails 1.3e-4 and 1.1e-5 against 1e-5)."""
    return solve_steady(17.186440677966, 0.144237288136, ChuteModel(roughness=0.05), min_thickness=0.0)


def _rules_off(tail=True, stall=True) -> RejectionPolicy:
    """The policy without the tail crossing rule and/or the predictor's stall rule."""
    changes = {}
    if tail:
        changes["crossing_jump"] = 0.0
    if stall:
        changes["stall_rejections"] = 10**6
    return RejectionPolicy(tracking=TrackingPolicy(**changes))


def test_unresolved_null_vector_stops_at_once(spurious_flow, solves):
    """N = 48: every step from k = 0 has the null vector's tail 1.3e-4; the tracker gives up
    at the first (1 solve), where it halved 16 times before (17 solves), same history."""
    with pytest.raises(ConvergenceError, match="not resolved at k = 0"):
        BranchTracker(spurious_flow, 48, n_max=48, cache=OperatorCache(2)).advance(1e-5)
    assert solves[0] == 1
    off = _rules_off()
    solves[0] = 0
    tr = BranchTracker(spurious_flow, 48, n_max=48, policy=off, cache=OperatorCache(2))
    with pytest.raises(ConvergenceError, match="step shrank"):
        tr.advance(1e-5)
    assert solves[0] == 17
    assert len(tr.history) == 1


def test_stalled_predictor_stops_at_once(spurious_flow, solves):
    """N = 60 without the tail rules: after a point accepted at k = 1.22e-9 (off the branch:
    N = 75 reaches k = 1e-5 in one step from k = 0) every shorter step misses the prediction
    by 0.36 of the step; the stall rule stops after 3 such misses instead of halving 14
    times, with the same history."""
    tr = BranchTracker(spurious_flow, 60, n_max=60, policy=_rules_off(stall=False), cache=OperatorCache(2))
    with pytest.raises(ConvergenceError, match="misses the prediction"):
        tr.advance(1e-5)
    n_stall, hist = solves[0], [(s, a) for s, a, _ in tr.history]
    solves[0] = 0
    tr = BranchTracker(spurious_flow, 60, n_max=60, policy=_rules_off(), cache=OperatorCache(2))
    with pytest.raises(ConvergenceError, match="step shrank"):
        tr.advance(1e-5)
    assert [(s, a) for s, a, _ in tr.history] == hist
    assert len(hist) == 2
    assert n_stall <= solves[0] - 10  # measured: 20 against 31
