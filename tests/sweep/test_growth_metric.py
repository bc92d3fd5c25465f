"""The growth metric keeps a flagged estimate where the paper's 1e-7 is missed (issue 9)."""

from __future__ import annotations

import pytest

from chuteflow.steady import solve_steady
from chuteflow.sweep.metrics import GrowthMetric
from chuteflow.sweep.points import Point


def test_unconverged_k_keeps_values_with_flag_and_drift():
    """θ = 14.3077°, ν0(0) = 0.102308 (a point of the quick φ = 0.05 diagram): at k = 0.0063
    the branch misses the drift test at N = 160 (measured drift 3.5e-7, tail 9.1e-10).
    Version 2 left growth_max missing; now the estimate is kept, flagged, with its drift."""
    theta, nu0 = 14.307692307692, 0.102307692308
    flow = solve_steady(theta, nu0)
    point = Point(-1, -1, theta, nu0)
    out = GrowthMetric().compute(flow, point)
    assert out["dispersion_sampled"] and out["growth_converged"] is False
    assert 1e-7 < out["growth_drift"] < 1e-6  # the convergence estimate (measured 3.5e-7)
    # stable at every sampled k (the long-wave verdict there: stable)
    assert out["growth_max"] < 0 and out["k_growth_max"] == pytest.approx(1e-4)
    assert "k_c" not in out
    assert any("not converged to the paper's thresholds" in n for n in point.notes)


class _LosingTracker:
    """Stands in for BranchTracker: tracks up to k < k_lost, then loses the branch."""

    k_lost = 3e-3

    def __init__(self, flow, n, policy=None, cache=None):
        self.n = 160

    def mode(self, k):
        from chuteflow.errors import ConvergenceError

        if k >= self.k_lost:
            raise ConvergenceError(f"lost the branch near k = {self.k_lost:.4g} (theta = 0)")
        return _mode(k)


def _mode(k):
    from types import SimpleNamespace

    # Re α = k (1 − k/0.02): unstable below k_c = 0.02, with a maximum in the grid
    return SimpleNamespace(
        k=k, alpha=complex(k * (1 - k / 0.02), -3 * k), n=160, drift=1e-9, tail=1e-9, physical=True
    )


def _fake_after_lost(calls, reached_up_to):
    def after_lost_branch(flow, k, *, n, policy=None, cache=None, lost=""):
        calls.append(k)
        return _mode(k) if k <= reached_up_to else None

    return after_lost_branch


@pytest.fixture
def losing(monkeypatch):
    import chuteflow.sweep.metrics as metrics

    monkeypatch.setattr(metrics, "BranchTracker", _LosingTracker)
    calls: list[float] = []

    def install(reached_up_to):
        monkeypatch.setattr(metrics, "after_lost_branch", _fake_after_lost(calls, reached_up_to))
        monkeypatch.setattr(GrowthMetric, "_refine", staticmethod(lambda flow, ma, mb, cache=None: 0.02))
        return calls

    return install


def test_lost_branch_tries_the_largest_k_first_and_stops_there(losing):
    """After the branch is lost, every remaining k is followed afresh from k = 0; when the
    largest is not reached the values stay missing, so the nearer ones are not computed
    (this saved 27 % of the growth metric at 13 lost points of the 60 × 60 diagram)."""
    calls = losing(reached_up_to=0.02)
    point = Point(-1, -1, 16.0, 0.05)
    out = GrowthMetric().compute(object(), point)
    assert calls == [pytest.approx(0.05)]
    assert out == {"dispersion_sampled": True}
    assert any("not reached with the relaxed tail threshold either (k = 0.05" in n for n in point.notes)


def test_lost_branch_values_come_back_in_the_order_of_the_k_grid(losing):
    calls = losing(reached_up_to=1.0)
    point = Point(-1, -1, 16.0, 0.05)
    metric = GrowthMetric()
    out = metric.compute(object(), point)
    ks = metric.k_grid()
    rest = [float(k) for k in ks if k >= _LosingTracker.k_lost]
    assert calls == rest[-1:] + rest[:-1]  # the largest first, then in order
    re = [k * (1 - k / 0.02) for k in ks]
    assert out["growth_max"] == max(re) and out["k_growth_max"] == ks[re.index(max(re))]
    assert out["k_c"] == 0.02 and out["growth_converged"]
    assert any("followed with the relaxed tail threshold from there" in n for n in point.notes)
