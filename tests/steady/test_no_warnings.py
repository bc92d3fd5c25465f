"""The steady solver raises no floating-point warnings (paper §3): its trial states — a
continuation predictor, a chord or a line-search step — may leave the closures' domain
(ν0 > ν_m, overflow of e^s), which the line search handles by a shorter step; numpy's
warnings about them are silenced where the trial residual is evaluated
(:meth:`chuteflow.steady.newton.SteadyNewton.trial_residual`), so that callers need not
silence anything. Every warning is an error in these tests."""

from __future__ import annotations

import contextlib
import math
import warnings

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.errors import ChuteflowError
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.steady import solve_steady, steady_existence, steady_family, steady_tangent
from chuteflow.steady.newton import SteadyNewton

#: Points without a steady flow or at the existence boundaries (cold starts that fail,
#: shooting verdicts of every kind, thin layers).
_HARD = ((12.0, 0.05), (25.0, 0.2), (14.3, 0.017), (13.26, 0.0984), (18.0, 0.02), (22.0, 0.3))


def _count_bad_trials(monkeypatch) -> list[int]:
    """Count the trial residuals that are not finite (the case the silencing is for)."""
    bad = [0]
    trial = SteadyNewton.trial_residual

    def counted(self, st):
        R = trial(self, st)
        bad[0] += not np.isfinite(R).all()
        return R

    monkeypatch.setattr(SteadyNewton, "trial_residual", counted)
    return bad


def _solve_everything():
    for p in POINTS.values():
        flow = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
        assert flow.converged
        steady_tangent(flow)
    for theta, nu0 in _HARD:
        steady_existence(theta, nu0)
        with contextlib.suppress(ChuteflowError):
            solve_steady(theta, nu0, strict=False)
    # a family across the upper existence boundary (its last points have no flow)
    ds = steady_family(16.0, np.geomspace(0.005, 0.5, 16))
    assert {"ok", "no_steady_flow"} <= set(ds.status.values)


def test_no_warnings_from_steady_solves():
    """The paper's points, points without a flow, an existence scan and a family."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _solve_everything()


def test_no_warnings_on_the_numpy_road(monkeypatch):
    """Without the compiled rows (no C compiler) the residual runs through numpy, which
    warns on NaN and overflow; trial states outside the closures' domain do occur there
    (counted), and no warning leaves the solver."""
    monkeypatch.setattr("chuteflow.steady.system._road_parts", lambda *a: None)
    bad = _count_bad_trials(monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _solve_everything()
    assert bad[0] > 0, "no trial left the closures' domain: the test does not test the silencing"


def test_trial_residual_silences_only_its_own_evaluation(monkeypatch):
    """Outside :meth:`SteadyNewton.trial_residual` numpy's floating-point state is the
    caller's: the solver does not switch warnings off around the whole solve."""
    monkeypatch.setattr("chuteflow.steady.system._road_parts", lambda *a: None)
    seen = []
    trial = SteadyNewton.trial_residual

    def spy(self, st):
        seen.append(np.geterr()["invalid"])
        return trial(self, st)

    monkeypatch.setattr(SteadyNewton, "trial_residual", spy)
    with np.errstate(invalid="raise"):
        solve_steady(16.0, 0.05)
        assert np.geterr()["invalid"] == "raise"
    assert seen
    assert set(seen) == {"raise"}
    assert math.isfinite(solve_steady(16.0, 0.05).Q)


@pytest.mark.parametrize("name", ["P1", "P4"])
def test_no_warnings_with_numpy_errors_raised(name):
    """With numpy set to raise on every floating-point error, the paper's points solve."""
    p = POINTS[name]
    with np.errstate(all="raise"):
        flow = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
    assert flow.converged
