"""What watches a time-dependent run, shared by both models' steppers.

The simulation of the full equations (:class:`chuteflow.dns.DnsSimulation`) and that of the
1D model (:class:`chuteflow.reduced.WaveSimulation`) step in time the same way (in the style
of py-pde's ``solve(..., tracker=[...])``): before the first step every tracker's
:meth:`Tracker.initialize` is called, after every accepted step its :meth:`Tracker.handle`
(a returned string stops the run with that status, after every tracker has seen the step),
:meth:`Tracker.left_validity` when the state leaves the range where the model is defined
(return True to stop there with the data kept instead of raising), and :meth:`Tracker.finalize`
at the end. A resumable run (the DNS) stores :meth:`Tracker.checkpoint` with its state and
gives it back through :meth:`Tracker.restore`, so a tracker resumed after SIGKILL continues
as if never interrupted.

This module is layer-neutral: it imports nothing of the pipeline. What a tracker asks of a
simulation ``sim`` is duck-typed:

* ``sim.wave_amplitude(y)`` → float, the size of the wave in the state ``y``
  (:class:`SaturationStop`);
* ``sim.max_growth_rate`` → float, the largest linear growth rate of the run's modes
  (:class:`SaturationStop`);
* ``sim.resolution(y)`` → dict with ``x_tail`` and ``y_tail``, the amplitude of the highest
  modes relative to the largest (:class:`ResolutionMonitor`);
* ``sim.can_refine(direction)`` → bool, whether its grid may still grow in ``"x"`` or ``"y"``
  (:class:`ResolutionMonitor` with ``action="refine"`` returns ``"refine x"`` or ``"refine y"``;
  the simulation then refines and calls :meth:`Tracker.refined`).

and of a step ``step``: ``step.t_prev``, ``step.t``, ``step.number``, ``step.y`` (the state at
its end) and ``step.state(t)`` (the state at ``t`` in [t_prev, t]).

:func:`wave_measures` judges a run's end from its records of ρ̄(t, ξ) the same way for both
models: the saturated amplitude, wave speed, wavelength, time to saturate and the verdict.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ParameterError
from .spectral import fourier_resample

__all__ = [
    "Tracker",
    "Sampler",
    "SnapshotTracker",
    "SaturationStop",
    "ProgressTracker",
    "ValidityStop",
    "WallTimeStop",
    "ResolutionMonitor",
    "ResolutionWarning",
    "run_tail",
    "saturated",
    "VERDICTS",
    "WavePolicy",
    "wave_measures",
]

#: What became of a wave (``verdict`` of :func:`wave_measures`).
VERDICTS = ("saturated", "coarsening", "growing", "decaying", "left_validity", "stopped")


class ResolutionWarning(UserWarning):
    """The highest resolved modes of a run carry more than the tolerance."""


class Tracker:
    """Base class of what watches a run (see the module's notes)."""

    def initialize(self, sim: Any, initial: Any, t_end: float) -> None:
        """Called once before the first step (``initial.y`` the state, ``initial.t`` its time)."""

    def handle(self, sim: Any, step: Any) -> str | None:
        """Called after each accepted step; return a status to stop the run."""
        return None

    def left_validity(self, sim: Any, message: str) -> bool:
        """Called when the state left the model's validity; True stops the run instead of raising."""
        return False

    def finalize(self, sim: Any, info: Any) -> None:
        """Called once at the end of the run."""

    def refined(self, sim: Any, state: Any, direction: str = "x") -> None:
        """Called after the simulation refined its grid in ``direction`` (``"x"`` or ``"y"``;
        the state ``state.y`` has more modes or nodes)."""

    def checkpoint(self) -> dict[str, np.ndarray]:
        """What the tracker has gathered, as arrays (saved with a resumable run's state)."""
        return {}

    def restore(self, saved: dict[str, np.ndarray]) -> None:
        """Take back what :meth:`checkpoint` returned (after :meth:`initialize`)."""


class Sampler(Tracker):
    """A tracker acting at fixed times: ``count`` uniform times on [0, t_end] (both ends
    included) or every ``interval`` (and at t_end)."""

    def __init__(self, count: int | None = None, interval: float | None = None):
        if (count is None) == (interval is None):
            raise ParameterError("give exactly one of count and interval")
        if count is not None and (int(count) != count or count < 2):
            raise ParameterError(f"snapshots = {count!r} must be at least 2 (both ends of the run)")
        if interval is not None and not (math.isfinite(interval) and interval > 0):
            raise ParameterError(f"interval = {interval!r} must be a positive time")
        self.count, self.interval = count, interval

    def initialize(self, sim, initial, t_end):
        if self.count is not None:
            self.sample_times = np.linspace(0.0, t_end, int(self.count))
        else:
            self.sample_times = np.unique(np.r_[np.arange(0.0, t_end, self.interval), t_end])
        self._next = 1
        self.sample(sim, 0.0, initial.y)

    def handle(self, sim, step):
        ts, took = self.sample_times, False
        while self._next < len(ts) and ts[self._next] <= step.t * (1 + 1e-14):
            t = float(ts[self._next])
            self.sample(sim, t, step.state(t))
            self._next += 1
            took = True
        return self.check(sim) if took else None

    def sample(self, sim, t: float, y: np.ndarray) -> None:
        """Record the state ``y`` at time ``t``."""

    def check(self, sim) -> str | None:
        """After the samples of a step: a status to stop the run, or None."""
        return None

    def checkpoint(self):
        return {"next": np.array(self._next)}

    def restore(self, saved):
        self._next = int(saved["next"])


class SnapshotTracker(Sampler):
    """Store the state at ``count`` uniform times (or every ``interval``).

    A run stopped by :class:`ValidityStop` also stores its last accepted state, at its own
    time. ``times`` and ``states`` hold the snapshots.
    """

    def initialize(self, sim, initial, t_end):
        self.times, self.states = [], []
        super().initialize(sim, initial, t_end)

    def sample(self, sim, t, y):
        self.times.append(t)
        self.states.append(np.array(y, copy=True))

    def finalize(self, sim, info):
        if info.status in ("left_validity", "left_family"):
            self.sample(sim, info.t, info.y)

    def checkpoint(self):
        return {**super().checkpoint(), "times": np.array(self.times), "states": np.array(self.states)}

    def restore(self, saved):
        super().restore(saved)
        self.times, self.states = list(saved["times"]), list(saved["states"])


def saturated(amps: np.ndarray, a0: float, tol: float, sigma: float) -> bool:
    """Amplitude settled: grew (or decayed) well past its start and changed by less than
    ``tol`` relative over the last tenth of the samples (at least 3)."""
    n = len(amps)
    w = max(n // 10, 3)
    recent = amps[-w:]
    if sigma > 0 and amps[-1] < 10 * a0:
        return False
    if sigma <= 0:
        return bool(amps[-1] < a0 * math.exp(-10.0))
    return float(np.ptp(recent)) < tol * float(recent.max())


class SaturationStop(Sampler):
    """Stop when the wave amplitude ``sim.wave_amplitude(y)`` has settled.

    The amplitude is sampled like the snapshots (``count`` or ``interval``). From the
    ``min_samples``-th sample on, an unstable state (``sim.max_growth_rate`` > 0) stops with
    status "saturated" once the amplitude exceeds 10× its start (``initial.amplitude``) and
    changed by less than ``tol`` relative over the last tenth of the samples; a stable one
    stops with "decayed" once it fell below e⁻¹⁰ of its start.
    """

    def __init__(
        self,
        tol: float = 0.02,
        count: int | None = None,
        interval: float | None = None,
        min_samples: int = 10,
    ):
        super().__init__(count, interval)
        if not 0.0 < tol < 1.0:
            raise ParameterError(f"saturation_tol = {tol!r} must be in (0, 1)")
        self.tol, self.min_samples = float(tol), int(min_samples)

    def initialize(self, sim, initial, t_end):
        self.amplitudes: list[float] = []
        self._a0 = float(initial.amplitude)
        super().initialize(sim, initial, t_end)

    def sample(self, sim, t, y):
        self.amplitudes.append(float(sim.wave_amplitude(y)))

    def check(self, sim):
        if len(self.amplitudes) >= self.min_samples and saturated(
            np.array(self.amplitudes), self._a0, self.tol, sim.max_growth_rate
        ):
            return "saturated" if sim.max_growth_rate > 0 else "decayed"
        return None

    def checkpoint(self):
        return {**super().checkpoint(), "amplitudes": np.array(self.amplitudes)}

    def restore(self, saved):
        super().restore(saved)
        self.amplitudes = [float(a) for a in saved["amplitudes"]]


class ProgressTracker(Tracker):
    """Call ``callback(t, t_end)`` after every step (e.g. a progress bar's update)."""

    def __init__(self, callback: Callable[[float, float], None]):
        self.callback = callback

    def initialize(self, sim, initial, t_end):
        self._t_end = float(t_end)

    def handle(self, sim, step):
        self.callback(step.t, self._t_end)


class ValidityStop(Tracker):
    """Stop (status "left_validity", data kept) instead of raising when the state leaves the
    range where the model is defined (the 1D model: the steady family's densities)."""

    def left_validity(self, sim, message):
        return True


class WallTimeStop(Tracker):
    """Pause the run after ``seconds`` of wall time in this call (status ``"paused at t = …"``).

    A run with a checkpoint keeps it (as for a stopped one), so the same call again continues
    for another ``seconds``; the records so far are judged as usual
    (:func:`wave_measures`: e.g. ``growing`` when the wave had not settled when the time ran
    out). Meant for runs of unknown length: a map of flows with a budget per flow, or a wave
    that may never saturate.
    """

    def __init__(self, seconds: float):
        if not (math.isfinite(seconds) and seconds > 0):
            raise ParameterError(f"wall_limit = {seconds!r}: a positive number of seconds of wall time")
        self.seconds = float(seconds)

    def initialize(self, sim, initial, t_end):
        self._start, self._t_end = time.perf_counter(), float(t_end)

    def handle(self, sim, step):
        last = step.t >= self._t_end * (1 - 1e-12)  # the run ends here anyway
        if not last and time.perf_counter() - self._start >= self.seconds:
            return (
                f"paused at t = {step.t:.6g}: wall-time limit of {self.seconds:g} s reached "
                "(the same call with the same checkpoint continues)"
            )
        return None


#: A start's transient has died when its tail has fallen this far below its first peak (P5:
#: 4.4e-3 to 2e-8; a wiggle of its decay above 1e-3 of the peak is still the start's)
#: (:func:`run_tail`).
TRANSIENT_FALL = 1e-3


def _transient_end(v: np.ndarray) -> int | None:
    """Where a start's transient ends in a series of tails: the first local minimum once the
    tail has fallen :data:`TRANSIENT_FALL` below its first peak; None while it has not."""
    d = np.diff(v)
    falls = np.nonzero(d < 0)[0]
    if not falls.size:
        return None
    p = int(falls[0])  # the first peak
    low = np.nonzero(v[p:] <= TRANSIENT_FALL * v[p])[0]
    if not low.size:
        return None
    q = p + int(low[0])
    rise = np.nonzero(d[q:] >= 0)[0]
    return q + int(rise[0]) if rise.size else v.size - 1


def run_tail(series) -> float:
    """The tail of a run from its tails over time (``x_tail`` or ``y_tail`` at each record):
    the largest from the end of the start's transient on; 0 for an empty series.

    The one definition of a run's resolution, used by :class:`ResolutionMonitor` and the
    simulations' ``x_tail``/``y_tail``. The initial condition's own high modes (noise) and
    what they make at once (their products: from noise of 1e-2 in modes ≤ M/2 the top
    eighth of the modes carries ≈ 4e-3 of the largest within one step, P5) are data, not
    truncation: they decay. What the run itself puts into its highest modes shows once they
    have: from the first minimum on, where the tail falls from the start, or from the first
    minimum after it has fallen a thousandfold (:data:`TRANSIENT_FALL`) below its first peak,
    where it rises first; every later value counts. A tail that falls to the end gives the
    last value; one that rises from the start and never falls a thousandfold, the largest.
    (P1, L = 2000, noise 1e-4: 3.1e-4 at t = 24 from the noise, then lower; 2.1e-4 at the
    end, from the wave.)"""
    v = np.asarray(series, dtype=float)
    if v.size == 0:
        return 0.0
    end = _transient_end(v)
    if end is None:
        rise = np.nonzero(np.diff(v) >= 0)[0]
        end = int(rise[0]) if rise.size else v.size - 1
    return float(v[end:].max())


class ResolutionMonitor(Tracker):
    """Watch the amplitude of the highest resolved modes, ``sim.resolution(y)``.

    Every ``every`` steps (and at the start, after the first step and at the end) the
    ``x_tail`` and ``y_tail``
    (amplitude of the highest modes relative to the largest, see the simulation's
    ``resolution``) are measured; :attr:`x_tail` and :attr:`y_tail` are the run's tails by
    :func:`run_tail` (the largest from the first minimum on: the initial condition's own
    high modes do not count while they decay). When one of them rises above ``tol`` (or
    ends above it): with ``action="warn"`` a :class:`ResolutionWarning` (once per
    direction), with ``"stop"`` the run stops with status ``"under-resolved"`` (its data
    kept: rerun finer).

    With ``action="refine"`` the grid follows the wave: once the x (or y) tail, rising,
    passes ``tol / REFINE_MARGIN`` the monitor returns ``"refine x"`` (``"refine y"``) where
    ``sim.can_refine(direction)`` says the grid may still grow that way, and the simulation
    refines (exactly: the state is the same function, :meth:`chuteflow.dns.DnsSimulation.refine`)
    and calls :meth:`Tracker.refined`, which starts that direction's series anew. Where the
    grid may not grow (``max_modes`` or ``max_n`` reached) it warns as with ``"warn"``. The
    margin keeps the tail below ``tol`` between two measurements while it rises (tenfold in
    ≈ 20 steps at P5's bore, docs/dns.md). With ``settle=True`` (a broadband start: noise) the monitor neither
    refines nor warns before the start's own transient has died (:func:`run_tail`; at the end
    it warns all the same): noise of 1e-2 puts 4e-3 into the top modes at once, which
    decays a thousandfold within t ≈ 1000 at P5 and is no reason to run the whole linear
    phase on a finer grid.
    """

    #: Refine when a tail passes tol / REFINE_MARGIN (``action="refine"``).
    REFINE_MARGIN = 4.0

    def __init__(self, tol: float = 1e-4, *, every: int = 10, action: str = "warn", settle: bool = False):
        if not (math.isfinite(tol) and 0 < tol < 1):
            raise ParameterError(f"resolution_tol = {tol!r} must be in (0, 1): a relative amplitude")
        if int(every) != every or every < 1:
            raise ParameterError(f"every = {every!r} must be a positive number of steps")
        if action not in ("warn", "stop", "refine"):
            raise ParameterError(f"action = {action!r}: choose 'warn', 'stop' or 'refine'")
        self.tol, self.every, self.action = float(tol), int(every), action
        self.settle = bool(settle)
        self._series: dict[str, list[float]] = {"x": [], "y": []}  # the tails measured
        self._warned: set[str] = set()

    @property
    def x_tail(self) -> float:
        return run_tail(self._series["x"])

    @property
    def y_tail(self) -> float:
        return run_tail(self._series["y"])

    def initialize(self, sim, initial, t_end):
        self._measure(sim, initial.y)

    def handle(self, sim, step):
        # (and after the first step: a tail the first step raises — a mode started at a
        # finite amplitude — is refined then, not ``every`` steps later)
        if step.number % self.every and step.number != 1:
            return None
        return self._measure(sim, step.y)

    def finalize(self, sim, info):
        self._measure(sim, info.y, end=True)

    def refined(self, sim, state, direction="x"):
        # the spectrum of the finer grid: a new series (the coarse grid's tails are its own);
        # a start's transient is behind a run that refined (it refines only after it)
        self._series[direction] = []
        self._warned.discard(direction)
        self.settle = False
        self._measure(sim, state.y)

    def _measure(self, sim, y, end: bool = False) -> str | None:
        r = sim.resolution(y)
        refine = None  # (both directions are measured; one refinement at a time)
        for d in ("x", "y"):
            series = self._series[d]
            series.append(float(r[f"{d}_tail"]))
            v = run_tail(series)
            # while the tail still falls it is the initial condition's (run_tail); from a
            # broadband start (settle) it is the start's own until that has died away
            rising = len(series) > 1 and bool(np.any(np.diff(series) >= 0))
            transient = self.settle and _transient_end(np.asarray(series)) is None
            if (
                self.action == "refine"
                and not end
                and len(series) > 1
                and series[-1] >= series[-2]
                and v > self.tol / self.REFINE_MARGIN
                and not transient
                and sim.can_refine(d)
            ):
                refine = refine or f"refine {d}"
                continue
            if v > self.tol and (rising or end) and (end or not transient) and d not in self._warned:
                self._warned.add(d)
                if self.action == "stop":
                    return "under-resolved"
                warnings.warn(
                    f"the highest {d} modes carry {v:.1e} of the largest (tolerance {self.tol:g}): "
                    f"the run is not resolved in {d}; rerun with a finer {'nx' if d == 'x' else 'ny'}",
                    ResolutionWarning,
                    stacklevel=2,
                )
        return refine

    def checkpoint(self):
        out = {f"tails_{d}": np.array(v) for d, v in self._series.items()}
        return {**out, "settle": np.array(self.settle)}

    def restore(self, saved):
        if "settle" in saved:
            self.settle = bool(saved["settle"])
        if "tails_x" in saved:
            self._series = {d: [float(v) for v in saved[f"tails_{d}"]] for d in ("x", "y")}
        else:  # a checkpoint written before run_tail kept only the maxima: counted as reached
            self._series = {d: [float(v)] * 2 for d, v in zip(("x", "y"), saved["tails"])}


@dataclass(frozen=True)
class WavePolicy:
    """How a run's end is judged (:func:`wave_measures`).

    Attributes
    ----------
    window : float
        Fraction of the run at its end over which the amplitude's change is judged (a tenth:
        the window of :class:`SaturationStop`, so that a run it stopped is judged settled).
    tol : float
        Relative change of the amplitude (max − min of ρ̄ over its mean) over the window
        below which the wave counts as settled; also the band that defines the time to
        saturate.
    linear : float
        Amplitudes below this are the linear phase ("growing" or "decaying").
    """

    window: float = 0.1
    tol: float = 0.02
    linear: float = 1e-3


#: Points on which :func:`wave_measures` takes the extrema of ρ̄ (the trigonometric
#: interpolant of its samples where they are fewer).
EXTREMA_POINTS = 256


def wave_measures(
    t: np.ndarray,
    rho: np.ndarray,
    length: float,
    frame: float,
    *,
    status: str = "ok",
    policy: WavePolicy | None = None,
) -> dict:
    """The wave at the end of a run from its records ρ̄(t, ξ) (frame speed ``frame``).

    Returns ``rho_min_rel``, ``rho_max_rel`` (min and max of ρ̄ over its mean, minus 1, at the
    end; of the trigonometric interpolant of the samples on :data:`EXTREMA_POINTS` points
    where they are fewer), ``amplitude_rel`` (their difference), ``wavelength`` (L over the
    number of the dominant Fourier mode of ρ̄ at the end), ``wave_speed`` (lab speed of that mode's phase
    over the last window of the run), ``amplitude_growth`` (d ln A/dt of the amplitude
    A = ``amplitude_rel`` over that window, least squares: the linear growth rate Re α of the
    dominant mode in the linear phase, → 0 as the wave saturates; how fast a run that ended
    ``growing`` still grew), ``t_saturation`` (the first time after which the
    amplitude stays within ``tol`` of its end value; NaN unless settled) and ``verdict``:
    ``saturated`` (amplitude settled — changed by less than ``tol`` over the window, or the
    run was ended by :class:`SaturationStop`, ``status="saturated"`` — and the dominant mode
    unchanged over the window),
    ``coarsening`` (the dominant mode changed over the window: waves merging),
    ``growing`` / ``decaying`` (amplitude still changing, or in the linear phase),
    ``left_validity`` (the run stopped where the state left the model's range: the 1D
    model's ``left_family``, non-finite fields of the DNS) or ``stopped`` (the solver failed;
    ``status`` says where). ``rho`` is the depth-integrated density of either model.
    """
    p = policy or WavePolicy()
    t = np.asarray(t, dtype=float)
    rho = np.asarray(rho, dtype=float)
    nan = math.nan
    out = {
        "verdict": "stopped",
        "rho_min_rel": nan,
        "rho_max_rel": nan,
        "amplitude_rel": nan,
        "wave_speed": nan,
        "wavelength": nan,
        "amplitude_growth": nan,
        "t_saturation": nan,
    }
    if rho.ndim != 2 or len(t) == 0 or rho.shape[1] < 3:
        return out
    spec = np.fft.rfft(rho, axis=1)
    if rho.shape[1] < EXTREMA_POINTS:
        # the extrema of the trigonometric interpolant, not of the samples: on a coarse
        # grid (8 points at nx = 5) the samples miss the crest by up to 1 − cos(π/8) = 8 %
        rho = fourier_resample(rho, EXTREMA_POINTS)
    mean = rho.mean(axis=1)
    amp = (rho.max(axis=1) - rho.min(axis=1)) / mean
    out["rho_min_rel"] = float(rho[-1].min() / mean[-1] - 1.0)
    out["rho_max_rel"] = float(rho[-1].max() / mean[-1] - 1.0)
    out["amplitude_rel"] = float(amp[-1])
    dominant = 1 + np.argmax(np.abs(spec[:, 1:]), axis=1)
    m = int(dominant[-1])
    out["wavelength"] = float(length / m)
    win = t >= t[-1] - p.window * (t[-1] - t[0])
    if win.sum() >= 3:
        k = 2.0 * math.pi * m / length
        phase = np.unwrap(np.angle(spec[win, m]))
        omega = np.polyfit(t[win], phase, 1)[0]
        out["wave_speed"] = float(frame - omega / k)
        if np.all(amp[win] > 0):
            out["amplitude_growth"] = float(np.polyfit(t[win], np.log(amp[win]), 1)[0])
    if status in ("left_family", "left_validity") or "non-finite" in status:
        out["verdict"] = "left_validity"
        return out
    if status.startswith("stopped"):
        return out
    a_end = amp[-1]
    a_win = amp[win]
    change = float((a_win.max() - a_win.min()) / a_end) if a_end > 0 else 0.0
    trend = float(a_win[-1] - a_win[0])
    if a_end < p.linear or win.sum() < 3:
        out["verdict"] = "growing" if trend > 0 else "decaying"
        return out
    coarsening = bool(np.any(dominant[win] != m))
    # a run that SaturationStop ended is settled by its criterion (sampled at its own times)
    if change < p.tol or status == "saturated":
        out["verdict"] = "coarsening" if coarsening else "saturated"
        far = np.nonzero(np.abs(amp - a_end) > p.tol * a_end)[0]
        out["t_saturation"] = float(t[far[-1] + 1]) if far.size else float(t[0])
    elif coarsening:
        out["verdict"] = "coarsening"
    else:
        out["verdict"] = "growing" if trend > 0 else "decaying"
    return out
