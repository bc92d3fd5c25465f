"""The rejection policy object and the operator cache of the stability solvers."""

from __future__ import annotations

import dataclasses
import gc

import numpy as np
import pytest

from chuteflow.errors import ParameterError
from chuteflow.stability import (
    DEFAULT_POLICY,
    OperatorCache,
    RejectionPolicy,
    least_stable,
    stability_operator,
)
from chuteflow.stability.modes import resolve_policy

K = 0.01


def test_default_policy_is_the_papers():
    # §4.1: drift and tail below 1e-7, ten highest Chebyshev coefficients
    p = DEFAULT_POLICY
    assert (p.drift_tol, p.tail_tol, p.tail_terms) == (1e-7, 1e-7, 10)
    assert p.ladder() == [80, 100, 125, 156, 195, 244, 256]
    assert RejectionPolicy(n_max=100).ladder() == [80, 100]
    assert RejectionPolicy(n_max=64).ladder() == [64]
    assert RejectionPolicy(n_start=48).ladder() == [48, 60, 75, 94, 118, 148, 185, 231, 256]
    assert p.accepts(9e-8, 9e-8)
    assert not p.accepts(1e-7, 0.0)


def test_policy_is_frozen_and_checked():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_POLICY.drift_tol = 1.0
    with pytest.raises(ParameterError, match="tail_tol"):
        RejectionPolicy(tail_tol=2.0)
    with pytest.raises(ParameterError, match="n_max"):
        RejectionPolicy(n_max=4)
    with pytest.raises(ParameterError, match="policy"):
        resolve_policy("strict")
    assert resolve_policy(None, drift_tol=1e-6).drift_tol == 1e-6
    assert resolve_policy(RejectionPolicy(n_max=100), n_max=None).n_max == 100
    assert hash(RejectionPolicy()) == hash(DEFAULT_POLICY)


def test_policy_ranks_a_direct_mode_over_the_relaxed_branch():
    """The rule of least_stable's fallback (RejectionPolicy.direct_outranks_relaxed): beyond
    relaxed_k_max (0.1) a resolved direct mode that drifts less than a flagged relaxed branch
    value and is at least as unstable replaces it; below, only a direct mode that passes both
    of the paper's tests and is less damped does.
    Numbers (N = 200, benchmarks/probes/relaxed_branch.py): P5, k = 0.5: direct −0.3667
    (drift 4.6e-9, tail 1.2e-11), relaxed −0.8279 (drift 7.5e-4); P4, k = 0.5: direct −2.5106
    (drift 1.4e-8) against the branch −0.0300 (drift 6.4e-4); (16.5°, 0.13, 0.08, 0.30),
    k = 0.005, N = 80: QZ −0.498 (drift 3.1e-7) against the branch −0.0028 (drift 2.3e-4)."""
    p = DEFAULT_POLICY
    assert p.relaxed_k_max == 0.1
    assert p.direct_outranks_relaxed(0.5, -0.3667, 4.6e-9, 1.2e-11, -0.8279, 7.5e-4)  # P5
    assert not p.direct_outranks_relaxed(0.5, -2.5106, 1.4e-8, 2.8e-12, -0.0300, 6.4e-4)  # P4
    assert not p.direct_outranks_relaxed(0.005, -0.0027, 3.1e-7, 6.0e-10, -0.0028, 2.3e-4)  # below
    # below relaxed_k_max a mode that passes both tests and is less damped outranks the
    # rejected relaxed value ((17.5°, 0.11, 0.075, 0.35), k = 0.005, N = 125: −0.00522663
    # with drift 2.8e-8, tail 1.0e-10 against −0.0054775 with drift 1.8e-4) …
    assert p.direct_outranks_relaxed(0.005, -0.00522663, 2.8e-8, 1.0e-10, -0.0054775, 1.8e-4)
    # … but not a more damped one, nor one that fails a test
    assert not p.direct_outranks_relaxed(0.005, -0.0060, 2.8e-8, 1.0e-10, -0.0054775, 1.8e-4)
    assert not p.direct_outranks_relaxed(0.005, -0.00522663, 2.4e-7, 1.9e-9, -0.0054775, 1.8e-4)
    assert not p.direct_outranks_relaxed(0.5, -0.3667, 4e-3, 1.2e-11, -0.8279, 3.0e-3)  # drifts more
    assert not p.direct_outranks_relaxed(0.5, -0.3667, 1e-8, 1e-4, -0.8279, 3.0e-3)  # not resolved
    # relaxed_k_max moves the boundary: at k = 0.5 < 1.0 the rule below the continuum applies
    # (a direct mode that fails the drift test does not outrank, however resolved its tail)
    wide = RejectionPolicy(relaxed_k_max=1.0)
    assert not wide.direct_outranks_relaxed(0.5, 0.0, 2e-7, 0.0, -1.0, 1e-3)
    assert p.direct_outranks_relaxed(0.5, 0.0, 2e-7, 0.0, -1.0, 1e-3)
    assert wide.direct_outranks_relaxed(0.5, 0.0, 1e-8, 0.0, -1.0, 1e-3)
    with pytest.raises(ParameterError, match="relaxed_k_max"):
        RejectionPolicy(relaxed_k_max=-1.0)


def test_policy_and_keywords_agree(p1_flow):
    a = least_stable(p1_flow, K, n=80, policy=RejectionPolicy(drift_tol=1e-6))
    b = least_stable(p1_flow, K, n=80, drift_tol=1e-6)
    assert a.alpha == b.alpha
    assert a.drift_tol == b.drift_tol == 1e-6
    assert a.physical


def test_two_flows_never_share_an_operator(p1_flow):
    cache = OperatorCache(4)
    twin = dataclasses.replace(p1_flow)  # equal content, another object
    op1 = stability_operator(p1_flow, 24, cache=cache)
    op2 = stability_operator(twin, 24, cache=cache)
    assert op1 is not op2
    assert op1.flow is p1_flow
    assert op2.flow is twin
    assert stability_operator(p1_flow, 24, cache=cache) is op1  # a hit
    assert stability_operator(p1_flow, 24, True, cache=cache) is not op1  # 3D: another one


def test_cache_survives_address_reuse_and_in_place_changes(p1_flow):
    cache = OperatorCache(2)
    for _ in range(5):
        # short-lived flows: a new one may get the address of a freed one
        f = dataclasses.replace(p1_flow, log_nu=np.array(p1_flow.log_nu))
        assert stability_operator(f, 24, cache=cache).flow is f
        del f
        gc.collect()
    assert len(cache) <= 2
    f = dataclasses.replace(p1_flow, log_nu=np.array(p1_flow.log_nu))
    op = stability_operator(f, 24, cache=cache)
    f.log_nu[0] += 1e-3  # the arrays are writable: a changed flow gets a new operator
    assert stability_operator(f, 24, cache=cache) is not op
