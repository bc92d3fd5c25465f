"""The layer-neutral trackers (:mod:`chuteflow.trackers`) on scripted series: the one
definition of a run's tail (:func:`~chuteflow.trackers.run_tail`) and the monitor that uses it."""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
import pytest

from chuteflow.trackers import ResolutionMonitor, ResolutionWarning, run_tail


def test_run_tail_counts_from_the_first_minimum():
    assert run_tail([]) == 0.0
    assert run_tail([5.0, 3.0, 1.0, 2.0, 4.0, 0.5]) == 4.0  # the noise's 5 and 3 decay first
    assert run_tail([3.0, 2.0, 1.0]) == 1.0  # falls to the end: the last value
    assert run_tail([1.0, 2.0, 3.0, 2.5]) == 3.0  # never falls first: the largest
    assert run_tail([0.0, 1e-5, 2e-5, 1e-5]) == 2e-5  # a run from a smooth state (x_tail 0 at t = 0)
    # noise's products: 0 at t = 0, ≈ 4e-3 at once, a thousandfold lower later (P5 from noise
    # of 1e-2): from the minimum after that fall on, the wave's own tail
    assert run_tail(P5_LIKE) == 8e-5
    assert run_tail(P5_LIKE[:7]) == 4.4e-3  # not yet fallen a thousandfold: the largest


# x tails of a P5-like run from noise: the start's transient, its decay, the bore's rise
P5_LIKE = [0.0, 4e-3, 3e-3, 4.4e-3, 1e-3, 1e-4, 5e-5, 2e-5, 3e-5, 1e-8, 2e-8, 1e-7, 2e-6, 3e-5, 8e-5]


class _Scripted:
    """A duck-typed simulation whose ``resolution`` returns the next scripted tails."""

    def __init__(self, xs, ys):
        self.values = iter(zip(xs, ys))

    def resolution(self, y):
        x, yy = next(self.values)
        return {"x_tail": x, "y_tail": yy}


def _run(monitor, xs, ys):
    sim = _Scripted(xs, ys)
    monitor.initialize(sim, SimpleNamespace(y=None), 1.0)
    status = None
    for i in range(1, len(xs) - 1):
        status = monitor.handle(sim, SimpleNamespace(number=i, y=None)) or status
    monitor.finalize(sim, SimpleNamespace(y=None))
    return status


def test_the_monitor_streams_the_same_tail_and_ignores_decaying_noise():
    rng = np.random.default_rng(3)
    for _ in range(20):
        xs = list(rng.uniform(0, 1e-3, 12))
        ys = list(rng.uniform(0, 1e-3, 12))
        mon = ResolutionMonitor(0.5, every=1)
        _run(mon, xs, ys)
        assert mon.x_tail == run_tail(xs)
        assert mon.y_tail == run_tail(ys)
    # the initial noise's tail (3e-3) decays below the tolerance and the run stays below it:
    # no warning (the old monitor kept the maximum, 3e-3, and warned)
    xs = [3e-3, 5e-4, 2e-5, 3e-5, 4e-5, 3e-5]
    mon = ResolutionMonitor(1e-4, every=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ResolutionWarning)
        _run(mon, xs, [1e-6] * len(xs))
    assert mon.x_tail == 4e-5
    # the run itself pushes the tail above the tolerance: it warns, or stops
    xs = [3e-3, 5e-4, 2e-5, 3e-4, 4e-4, 5e-4]
    with pytest.warns(ResolutionWarning, match="highest x modes carry 3.0e-04"):
        _run(ResolutionMonitor(1e-4, every=1), xs, [1e-6] * len(xs))
    assert _run(ResolutionMonitor(1e-4, every=1, action="stop"), xs, [1e-6] * len(xs)) == "under-resolved"
    # a tail still above the tolerance at the end warns even while it falls
    xs = [3e-3, 2e-3, 1e-3]
    with pytest.warns(ResolutionWarning, match="1.0e-03"):
        _run(ResolutionMonitor(1e-4, every=1), xs, [1e-6] * len(xs))


def test_the_monitor_resumes_from_its_checkpoint():
    xs = [3e-3, 5e-4, 2e-5, 3e-5, 4e-5, 3e-5, 6e-5, 1e-5]
    ys = [1e-6] * len(xs)
    whole = ResolutionMonitor(1e-4, every=1)
    _run(whole, xs, ys)
    first = ResolutionMonitor(1e-4, every=1)
    sim = _Scripted(xs, ys)
    first.initialize(sim, SimpleNamespace(y=None), 1.0)
    for i in range(1, 4):
        first.handle(sim, SimpleNamespace(number=i, y=None))
    saved = {k: np.asarray(v) for k, v in first.checkpoint().items()}
    second = ResolutionMonitor(1e-4, every=1)
    second.restore(saved)
    for i in range(4, len(xs) - 1):
        second.handle(sim, SimpleNamespace(number=i, y=None))
    second.finalize(sim, SimpleNamespace(y=None))
    assert (second.x_tail, second.y_tail) == (whole.x_tail, whole.y_tail) == (6e-5, 1e-6)
    # a checkpoint of the old form (the maxima only) still loads
    old = ResolutionMonitor(1e-4)
    old.restore({"tails": np.array([2e-5, 1e-6])})
    assert (old.x_tail, old.y_tail) == (2e-5, 1e-6)


class _Refinable(_Scripted):
    def can_refine(self, direction="x"):
        return direction == "x"


def test_a_settling_monitor_leaves_the_starts_transient_alone():
    """From noise (settle=True) the start's transient neither warns nor refines; once it has
    fallen a thousandfold (its decay's wiggle at 3e-5 is still its own) the wave's own rise
    refines at tol/4 (3e-5 > 2.5e-5, rising); a monitor without settle refines at the
    transient's first rise. At the end a transient that never died warns all the same."""

    def first_refine(mon, xs):
        sim = _Refinable(xs, [1e-6] * len(xs))
        mon.initialize(sim, SimpleNamespace(y=None), 1.0)
        for i in range(1, len(xs)):
            if mon.handle(sim, SimpleNamespace(number=i, y=None)) == "refine x":
                return i
        return None

    with warnings.catch_warnings():
        warnings.simplefilter("error", ResolutionWarning)
        assert first_refine(ResolutionMonitor(1e-4, every=1, action="refine", settle=True), P5_LIKE) == 13
    assert first_refine(ResolutionMonitor(1e-4, every=1, action="refine"), P5_LIKE) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", ResolutionWarning)
        _run(ResolutionMonitor(1e-4, every=1, settle=True), P5_LIKE[:12], [1e-6] * 12)
    with pytest.warns(ResolutionWarning, match="4.4e-03"):
        _run(ResolutionMonitor(1e-4, every=1, settle=True), P5_LIKE[:6], [1e-6] * 6)


def test_a_refined_run_has_left_its_transient_behind_and_the_checkpoint_says_so():
    """After a refinement the x series starts anew on the finer grid; it rises from its first
    value (no thousandfold fall in it), yet the next rise past tol/4 refines again: the start's
    transient was behind the first refinement. A resumed monitor keeps that (checkpoint)."""
    xs = [*P5_LIKE[:14], 1e-8, 1e-7, 3e-5]  # refined at 13 (3e-5), then the finer grid's tails
    sim = _Refinable(xs, [1e-6] * len(xs))
    mon = ResolutionMonitor(1e-4, every=1, action="refine", settle=True)
    mon.initialize(sim, SimpleNamespace(y=None), 1.0)
    got = [mon.handle(sim, SimpleNamespace(number=i, y=None)) for i in range(1, 14)]
    assert got[-1] == "refine x"
    mon.refined(sim, SimpleNamespace(y=None))  # measures 1e-8
    saved = mon.checkpoint()
    again = ResolutionMonitor(1e-4, every=1, action="refine", settle=True)
    again.restore(saved)
    assert not again.settle
    assert again.handle(sim, SimpleNamespace(number=15, y=None)) is None  # 1e-7
    assert again.handle(sim, SimpleNamespace(number=16, y=None)) == "refine x"  # 3e-5


@pytest.mark.parametrize("n", [7, 8, 15, 64])
def test_the_wave_extrema_do_not_depend_on_the_samples_grid(n):
    """``wave_measures``' ρ̄ extrema are those of the trigonometric interpolant: for the
    band-limited ρ̄ = 1 + 1e-3 cos 2π(x − 0.37) + 3e-4 cos 4πx sampled on 7 … 64 points
    the crest and trough are the exact ones (by a 1e5-point evaluation: 1.1235814e-3,
    −1.1489673e-3) to 2e-7 (measured 4.6e-8 and 9.1e-8: the 256-point evaluation's error);
    the samples' own max on 8 points, 0.9995e-3, is 11 % low."""
    from chuteflow.trackers import wave_measures

    x, t = np.arange(n) / n, np.linspace(0.0, 10.0, 20)
    rho = (
        1
        + 1e-3 * np.cos(2 * np.pi * (x[None, :] - 0.37))
        + 3e-4 * np.cos(4 * np.pi * x[None, :])
        + 0 * t[:, None]
    )
    w = wave_measures(t, rho, 1000.0, 0.0)
    assert w["rho_max_rel"] == pytest.approx(1.1235814e-3, abs=2e-7)
    assert w["rho_min_rel"] == pytest.approx(-1.1489673e-3, abs=2e-7)
    assert w["wavelength"] == 1000.0
