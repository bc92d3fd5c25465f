"""The one continuation stepper (chuteflow.continuation): its retry rules on toy problems."""

from __future__ import annotations

import math

import pytest

from chuteflow.continuation import StepRules, Trial, continue_to, march


def _recorder(fail=lambda s: False):
    tried = []

    def solve(state, s):
        tried.append(s)
        return Trial(not fail(s), s)

    return solve, tried


def test_reaches_target_exactly_with_growing_steps():
    solve, tried = _recorder()
    res = continue_to(solve, 0.0, 0.0, 1.0, StepRules(grow=2.0), h=0.125)
    assert res.reached
    assert res.s == 1.0
    assert res.reason == "reached"
    assert tried == [0.125, 0.375, 0.875, 1.0]  # 1/8, +1/4, +1/2, then clipped onto 1
    assert all(st.accepted for st in res.steps)


def test_halving_after_failure_and_min_step():
    solve, tried = _recorder(fail=lambda s: s > 0.5)
    res = continue_to(solve, 0.0, 0.0, 1.0, StepRules(grow=1.0, min_step=0.1), h=0.5)
    assert not res.reached
    assert res.reason == "min_step"
    assert res.s == 0.5
    # 0.5 accepted, then 1.0, 0.75, 0.625 fail; the next step (0.0625) is below min_step
    assert tried == [0.5, 1.0, 0.75, 0.625]
    assert [st.accepted for st in res.steps] == [True, False, False, False]


def test_max_halvings_and_continuing_step():
    solve, _ = _recorder(fail=lambda s: s > 0.3)
    res = continue_to(solve, 0.0, 0.0, 1.0, StepRules(grow=1.0, max_halvings=2), h=0.25)
    assert res.reason == "max_halvings"
    assert res.s == 0.25
    assert res.last.s == 0.25 + 0.0625  # the step tried last, halved twice


def test_growth_from_quality_and_ratio_cap():
    def solve(state, s):
        return Trial(True, s, quality=0.0)

    rules = StepRules(grow=lambda q: 3.0 if q < 0.02 else 1.0, max_step_ratio=2.0)
    res = continue_to(solve, 0.0, 0.0, 1.0, rules, h=1e-3, origin=0.0)
    s = [st.s for st in res.steps]
    # each step at most twice the distance from the origin: s triples
    assert s[:3] == pytest.approx([1e-3, 3e-3, 9e-3])
    assert res.reached
    assert math.isclose(res.h, 3 * res.steps[-1].h)


def test_clip_false_retries_the_target():
    solve, tried = _recorder(fail=lambda s: s == 1.0)
    res = continue_to(solve, 0.0, 0.9, 1.0, StepRules(clip=False, min_step=0.01), h=0.5)
    # the nominal step shrinks 0.5 → 0.25 → 0.125 with every retry at the target, then 0.0625
    assert tried[:4] == [1.0, 1.0, 1.0, 0.9 + 0.0625]
    assert not res.reached


def test_max_attempts():
    solve, tried = _recorder()
    res = continue_to(solve, 0.0, 0.0, 1.0, StepRules(grow=1.0, max_attempts=3), h=0.1)
    assert len(tried) == 3
    assert res.reason == "max_attempts"
    assert not res.reached


def test_descending_parameter():
    solve, tried = _recorder()
    res = continue_to(solve, 1.0, 1.0, 0.0, StepRules(grow=1.0), h=0.5)
    assert tried == [0.5, 0.0]
    assert res.reached


def test_subdivide_restarts_from_the_start():
    solve, tried = _recorder(fail=lambda s: s in (1.0, 0.5))
    res = continue_to(solve, "start", 0.0, 1.0, StepRules(retry="subdivide", max_depth=2))
    # depth 0: 1; depth 1: 0.5 fails (abandoned); depth 2: 0.25, 0.5 fails
    assert tried == [1.0, 0.5, 0.25, 0.5]
    assert not res.reached
    assert res.state == "start"
    assert res.reason == "max_depth"
    assert res.last_at(1.0).s == 1.0
    assert not res.last_at(1.0).accepted


def test_subdivide_succeeds_through_substeps():
    calls = []

    def solve(state, s):
        calls.append((state, s))
        return Trial(not (state == 0.0 and s == 1.0), s)

    res = continue_to(solve, 0.0, 0.0, 1.0, StepRules(retry="subdivide", max_depth=1))
    assert calls == [(0.0, 1.0), (0.0, 0.5), (0.5, 1.0)]
    assert res.reached
    assert res.state == 1.0


def test_final_failure_stops_at_once():
    """A failure marked final (the solver knows no shorter step passes it) ends the
    continuation there, in both retry modes, where a plain failure would be retried."""
    tried = []

    def solve(state, s):
        tried.append(s)
        return Trial(s <= 0.5, s, final=s > 0.5)

    res = continue_to(solve, 0.0, 0.0, 1.0, StepRules(grow=1.0, max_halvings=8), h=0.5)
    assert tried == [0.5, 1.0]  # not halved to 0.75, 0.625, …
    assert res.reason == "final"
    assert not res.reached
    assert res.s == 0.5
    assert res.state == 0.5
    tried.clear()
    res = continue_to(solve, 0.0, 0.0, 1.0, StepRules(retry="subdivide", max_depth=3))
    assert tried == [1.0]  # no finer subdivision is tried
    assert res.reason == "final"
    assert res.state == 0.0


def test_march_stops_at_first_failure():
    out = march(lambda st, i: Trial(i < 3, st + i), 0, range(1, 6))
    assert out == [(1, 1), (2, 3)]


def test_rules_are_checked():
    with pytest.raises(ValueError, match="retry"):
        StepRules(retry="bisect")
    with pytest.raises(ValueError, match="shrink"):
        StepRules(shrink=1.0)
