"""The simulation driver: :class:`DnsSimulation` steps a :class:`DnsState` under trackers.

``DnsSimulation(flow, length, ...)`` fixes the grid, the frame, the time step and the initial
state from a :class:`~chuteflow.steady.SteadyFlow` (as every stability function takes one);
``run(trackers)`` steps BDF2 (:class:`~chuteflow.dns.stepper.Stepper`) with the trackers of
:mod:`chuteflow.trackers` (the same as the 1D model's :class:`~chuteflow.reduced.WaveSimulation`)
watching every step, recording ρ̄(ξ, t), Q(ξ, t), the resolution of the highest modes and
full-field snapshots in the state; ``dataset(state)`` is the xarray result. The state saves
and loads itself (:meth:`DnsState.save`, :meth:`DnsState.load`, atomic writes): a run killed
at any moment (SIGKILL included) continues from its last checkpoint exactly as if never
interrupted, trackers included (:meth:`chuteflow.trackers.Tracker.checkpoint`).
"""

from __future__ import annotations

import hashlib
import math
import os
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import scipy.fft
import xarray as xr

from .._files import atomic_write
from ..errors import ConvergenceError, ParameterError
from ..spectral import fourier_evaluate, fourier_resample
from ..stability import OperatorCache, least_stable
from ..steady import SteadyFlow, steady_tangent
from ..trackers import WavePolicy, run_tail
from .diagnostics import bdf2_eigenvalue, measure_mode, resolution_tails, wave_measures
from .discretisation import Discretisation
from .remap import best_grid, remap_coefficients
from .setup import INITS, DnsSetup, _check_valid, check_setup, history_coefficients, initial_coefficients
from .stepper import NewtonSettings, Stepper
from .xmap import TanMap

__all__ = ["DnsSimulation", "DnsState", "DnsStep"]

#: The largest x grid a run may be refined to (nx = 2M + 1 = 1025).
MAX_MODES = 512
#: The most Chebyshev intervals a run may be refined to (the largest ``n``).
MAX_N = 400
#: A y refinement multiplies N by this (rounded up to a multiple of 8): the coupled blocks'
#: factorisation grows as N³, so the y grid grows by half, not double, at each refinement.
Y_REFINE = 1.5
#: ``follow_wave``: the frame follows the wave once ρ̄ varies by this fraction of its mean
#: (max − min; the nonlinear phase: the linear one, measured against the eigenvalue, is left
#: in the frame it started in) …
FOLLOW_AMPLITUDE = 0.05
#: … measured over this many records since the last change of frame …
FOLLOW_WINDOW = 20
#: … where the wave's speed differs from the frame's by more than this fraction of it (each
#: change rebuilds the preconditioner; docs/dns.md, *A frame that follows the wave*).
FOLLOW_TOL = 5e-3


def ceiling(value, start: int, limit: int, name: str, start_name: str, what: str) -> int:
    """The most ``what`` a run may be refined to: ``value`` (None: ``start``, the grid is
    kept), a whole number in [``start``, ``limit``]."""
    v = start if value is None else value
    if int(v) != v or not start <= v <= limit:
        raise ParameterError(
            f"{name} = {v!r} must be a whole number in [{start_name} = {start}, {limit}]: "
            f"the most {what} the grid may be refined to"
        )
    return int(v)


def _refined_n(n: int, max_n: int) -> int:
    """Chebyshev intervals after one y refinement of ``n`` (at most ``max_n``)."""
    return min(8 * math.ceil(Y_REFINE * n / 8), max_n)


def _refine_n(records: dict, n0: int) -> list:
    """The N after each refinement; a checkpoint written before y refinement existed has no
    ``refine_n``: its refinements were all in x, at the starting N ``n0``."""
    return _backfilled(records, "refine_n", n0)


def _backfilled(records: dict, name: str, start) -> list:
    """The record ``name`` of each refinement, ``start`` for the refinements of a checkpoint
    written before it was recorded (the y grid and the uniform x grid: what they had)."""
    got = list(records[name])
    return [start] * (len(records["refine_t"]) - len(got)) + got


def _grids(records: dict, setup: DnsSetup):
    """(t, modes, N, β, x0) after each refinement (β = 1, x0 = 0: the uniform x grid)."""
    return zip(
        records["refine_t"],
        records["refine_modes"],
        _refine_n(records, setup.n),
        _backfilled(records, "refine_beta", 1.0),
        _backfilled(records, "refine_centre", 0.0),
    )


def _refined_at(records: dict, setup: DnsSetup) -> str:
    """ "t = 40 (nx 9), t = 80 (ny 40)": when the grid grew, and to what."""
    out, m0, n0, map0 = [], setup.modes, setup.n, (1.0, 0.0)
    for t, m, n, beta, x0 in _grids(records, setup):
        m, n, mp = int(m), int(n), (float(beta), float(x0))
        grew = [f"nx {2 * m + 1}"] * (m != m0) + [f"ny {n}"] * (n != n0)
        if mp != map0:
            grew.append("uniform x" if mp[0] == 1.0 else f"x mapped, β {mp[0]:g} at ξ = {mp[1]:.5g}")
        out.append(f"t = {t:.6g} ({', '.join(grew)})")
        m0, n0, map0 = m, n, mp
    return ", ".join(out)


def _on_last_grid(records: dict, setup: DnsSetup, direction: str) -> int:
    """Index of the first record on the grid the run ends on in ``direction`` (``"x"``: the
    Fourier modes, ``"y"``: the Chebyshev intervals): the first after the last refinement
    that way, 0 if there was none. The tails recorded before it are the coarser grid's, to
    which the refinement answered (:meth:`ResolutionMonitor.refined` starts that direction's
    series anew there)."""
    last, m0, n0, map0 = None, setup.modes, setup.n, (1.0, 0.0)
    for t, m, n, beta, x0 in _grids(records, setup):
        mp = (float(beta), float(x0))
        if (m != m0 or mp != map0) if direction == "x" else (n != n0):
            last = t
        m0, n0, map0 = int(m), int(n), mp
    if last is None:
        return 0
    after = np.nonzero(np.asarray(records["t"], dtype=float) > last)[0]
    return int(after[0]) if after.size else len(records["t"]) - 1


def _to_nodes(f: np.ndarray, old, new, axis: int) -> np.ndarray:
    """Values at the nodes of ChebyshevGrid ``old`` along ``axis`` → the same polynomial at
    the nodes of ``new`` (the same interval, more nodes: exact)."""
    g = old.interpolate(np.moveaxis(np.asarray(f), axis, -1), new.y)
    return np.moveaxis(g, -1, axis)


def _pad_modes(C: np.ndarray, modes: int) -> np.ndarray:
    """Coefficients (…, M + 1) with zeros up to ``modes``: the same function on more modes."""
    out = np.zeros((*C.shape[:-1], modes + 1), dtype=C.dtype)
    out[..., : C.shape[-1]] = C
    return out


@dataclass
class DnsState:
    """Where a run stands: the fields, the BDF2 history and everything recorded so far.

    Attributes
    ----------
    C : ndarray
        Coefficients (4, N + 1, M + 1) of s = ln ν, u, v, T at time ``t``.
    prev : ndarray or None
        The previous time level (ν, u, v, T) on the padded grid (BDF2's history).
    t, step : float, int
        Time reached and steps taken.
    dt, h_prev : float
        Next step's Δt (halved where Newton failed) and the last step's.
    restart : bool
        The next step is a BDF1 step (no usable history).
    C_init : ndarray
        Coefficients at t = 0.
    amplitude : float
        Size of the initial wave (max − min of ρ̄ over its mean; :class:`~chuteflow.trackers.SaturationStop`).
    status : str
        ``"running"``, ``"ok"`` (reached the end), a tracker's stop (``"saturated"``, …) or
        ``"stopped at t = …: why"``.
    wall : float
        Wall-clock seconds spent so far (over every resumed part).
    records : dict of lists
        ``t``, ``rho``, ``Q``, ``x_tail``, ``y_tail`` every ``record_every`` steps;
        ``snap_t``, ``snaps`` the full fields; ``newton``, ``krylov`` per step;
        ``refine_t``, ``refine_modes``, ``refine_n`` when and to how many x modes and
        Chebyshev intervals the grid was refined (:meth:`DnsSimulation.refine`; the records
        and snapshots before are interpolated onto the finer grid); ``refine_beta``,
        ``refine_centre`` the x map after it (β = 1: uniform). The records and snapshots
        are on the uniform x grid of ``nxp`` points, mapped or not.
    x_map : tuple or None
        (x0, β) of the tan map of the x grid the state is on (None: uniform;
        :class:`~chuteflow.dns.xmap.TanMap`).
    solver : dict of arrays
        The stepper's :meth:`~chuteflow.dns.Stepper.snapshot` when the state was saved (a
        resumed run restores it and takes the same steps as the uninterrupted one).
    frame : float or None
        Speed of the frame the state is in (None: the run's ``frame_speed``); with
        ``follow_wave`` the frame follows the wave (:meth:`DnsSimulation.reframe`).
    frame_shift : float
        How far that frame has moved beyond the run's first one, ∫ (c(t) − c_0) dt: the
        records and snapshots are shifted back by it, so that they stay in the frame
        ξ = x − c_0 t. ``records["frame_t"]``, ``records["frame_speed"]``: when the frame
        changed, and to what.
    """

    C: np.ndarray = field(repr=False)
    prev: np.ndarray | None = field(repr=False)
    t: float
    step: int
    dt: float
    h_prev: float
    restart: bool
    C_init: np.ndarray = field(repr=False)
    status: str = "running"
    wall: float = 0.0
    amplitude: float = 0.0
    records: dict = field(default_factory=dict, repr=False)
    solver: dict = field(default_factory=dict, repr=False)
    x_map: tuple[float, float] | None = None
    frame: float | None = None
    frame_shift: float = 0.0

    RECORDS = (
        "t",
        "rho",
        "Q",
        "x_tail",
        "y_tail",
        "snap_t",
        "snaps",
        "newton",
        "krylov",
        "refine_t",
        "refine_modes",
        "refine_n",
        "refine_beta",
        "refine_centre",
        "rho_mean",
        "frame_t",
        "frame_speed",
    )

    def __post_init__(self):
        for k in self.RECORDS:
            self.records.setdefault(k, [])

    @property
    def y(self) -> np.ndarray:
        """The state trackers see (:mod:`chuteflow.trackers`): the coefficients."""
        return self.C

    def save(self, path: str | os.PathLike, key: str, trackers=()) -> None:
        """Write the state (and the trackers' :meth:`~chuteflow.trackers.Tracker.checkpoint`)
        atomically to ``path`` (.npz) under the run's ``key``."""
        payload: dict = {
            "key": np.array(key),
            "C": self.C,
            "C_init": self.C_init,
            "prev": self.prev if self.prev is not None else np.zeros(0),
            "scalars": np.array(
                [self.t, self.step, self.dt, self.h_prev, float(self.restart), self.wall, self.amplitude]
            ),
            "status": np.array(self.status),
            "x_map": np.array(self.x_map if self.x_map is not None else (), dtype=float),
            "frame": np.array((self.frame, self.frame_shift) if self.frame is not None else (), dtype=float),
            "trackers": np.array([type(tr).__name__ for tr in trackers]),
        }
        for k, v in self.records.items():
            payload[f"rec_{k}"] = np.array(v)
        for k, v in self.solver.items():
            payload[f"solver_{k}"] = np.asarray(v)
        for i, tr in enumerate(trackers):
            for k, v in tr.checkpoint().items():
                payload[f"tracker{i}_{k}"] = np.asarray(v)

        def write(fh):
            np.savez(fh, **payload)

        atomic_write(Path(path), write)

    @classmethod
    def load(cls, path: str | os.PathLike, key: str, trackers=()) -> DnsState | None:
        """The state saved at ``path`` under ``key`` (None if absent, unreadable or another
        run's); the trackers get their saved data back when they are the same classes."""
        try:
            with np.load(Path(path), allow_pickle=False) as ck:
                if str(ck["key"]) != key:
                    return None
                t, step, dt, h_prev, restart, wall, amp = (float(v) for v in ck["scalars"])
                st = cls(
                    C=ck["C"],
                    prev=ck["prev"] if ck["prev"].size else None,
                    t=t,
                    step=int(step),
                    dt=dt,
                    h_prev=h_prev,
                    restart=bool(restart),
                    C_init=ck["C_init"],
                    status=str(ck["status"]),
                    wall=wall,
                    amplitude=amp,
                    # (a checkpoint from before a record existed has none of it)
                    records={k: list(ck[f"rec_{k}"]) for k in cls.RECORDS if f"rec_{k}" in ck.files},
                    solver={k[7:]: ck[k] for k in ck.files if k.startswith("solver_")},
                    x_map=(
                        (float(ck["x_map"][0]), float(ck["x_map"][1]))
                        if "x_map" in ck.files and ck["x_map"].size
                        else None
                    ),
                    **(
                        {"frame": float(ck["frame"][0]), "frame_shift": float(ck["frame"][1])}
                        if "frame" in ck.files and ck["frame"].size
                        else {}
                    ),
                )
                names = [str(n) for n in ck["trackers"]]
                if names == [type(tr).__name__ for tr in trackers]:
                    for i, tr in enumerate(trackers):
                        pre = f"tracker{i}_"
                        saved = {k[len(pre) :]: ck[k] for k in ck.files if k.startswith(pre)}
                        if saved:
                            tr.restore(saved)
                return st
        except (OSError, KeyError, ValueError):
            return None


class DnsStep:
    """One accepted step (t_prev, t] as trackers see it (:mod:`chuteflow.trackers`)."""

    def __init__(self, C_old: np.ndarray, C_new: np.ndarray, t_prev: float, t: float, number: int):
        self._old, self.y = C_old, C_new
        self.t_prev, self.t, self.number = float(t_prev), float(t), int(number)

    def state(self, t: float) -> np.ndarray:
        """Coefficients at ``t`` in [t_prev, t] (linear interpolation in time)."""
        if self.t <= self.t_prev:
            return self.y
        w = (float(t) - self.t_prev) / (self.t - self.t_prev)
        return (1.0 - w) * self._old + w * self.y


class DnsSimulation:
    """The time-dependent equations on a slope periodic in x, from a steady flow (docs/dns.md).

    Parameters
    ----------
    flow : SteadyFlow
        The steady flow (θ, ν0(0) and the closures are its).
    length : float
        Period L along the slope; the fundamental wavenumber is k = 2π/L.
    time : float, optional
        Simulated time; default two wave periods 2 × 2π/|Im α| of the least-stable mode.
    n : int, optional
        Chebyshev intervals N; default the resolution at which
        :func:`chuteflow.stability.least_stable` converged at k = 2π/L.
    modes : int, optional
        Highest Fourier mode M; default 2 for ``init="mode"``, max(8, L/30) for noise.
    dt : float, optional
        Time step; default a hundredth of the wave period.
    init : {"mode", "noise"}
        Least-stable eigenmode at k = 2π/L, or random noise in the density (ŝ = δ ln ν
        uniform in y) in modes 1 … M/2.
    amplitude : float
        Largest component of the initial perturbation.
    seed : int
        Random seed of the noise.
    frame_speed : float, optional
        Speed c of the frame ξ = x − ct of the run; default 0 from a mode, the eigenmode's
        phase velocity from noise.
    top : {"transport", "isothermal"}
        Row of s = ln ν at the top node (:class:`~chuteflow.dns.Discretisation`).
    relax : bool
        Start from this grid's discrete steady state (:func:`~chuteflow.dns.relax_steady`).
    snapshots : int
        Full-field snapshots (equally spaced in time, both ends included).
    record_every : int
        Record ρ̄(x, t), Q(x, t) and the resolution every this many steps.
    settings : NewtonSettings, optional
        Newton–Krylov tolerances and preconditioner.
    min_dt_fraction : float
        Stop (status ``"stopped: ..."``) when Newton fails at Δt below this fraction of ``dt``.
    wave_policy : WavePolicy, optional
        How the wave at the end is judged (:func:`~chuteflow.trackers.wave_measures`).
    max_modes : int, optional
        Let the x grid follow the wave: where the x tail rises towards the resolution
        tolerance (:class:`~chuteflow.trackers.ResolutionMonitor` with ``action="refine"``)
        the modes are doubled, up to this many (:meth:`refine`). Default ``modes``: the grid
        is kept.
    max_n : int, optional
        Let the y grid follow the wave likewise: where the y tail rises, the Chebyshev
        intervals grow by half (``Y_REFINE``, to a multiple of 8), up to this many. Default
        ``n``: the y grid is kept.
    x_map : bool
        Let the x grid follow the front (docs/dns.md, *A grid that follows the front*):
        where the x tail rises, the run goes first to a tan map centred at the steepest point
        of ln ν (:func:`~chuteflow.dns.remap.best_grid`: the β of
        :data:`~chuteflow.dns.remap.BETAS` that minimises the tail, taken at the run's modes
        where it lowers the tail :data:`~chuteflow.dns.remap.REMAP_GAIN` times, else with
        half as many modes again, up to ``max_modes``); later rises re-centre the map on the moved
        front the same way. The records, snapshots and the dataset stay on the uniform x
        grid (evaluated exactly from the mapped series). Default False: refinement doubles
        the uniform modes.
    follow_wave : bool, optional
        Let the frame follow the wave (docs/dns.md, *A frame that follows the wave*): once
        the wave is nonlinear (ρ̄ varies by :data:`FOLLOW_AMPLITUDE` of its mean), its speed
        is measured from the phase of ρ̄'s dominant mode over the last
        :data:`FOLLOW_WINDOW` records, and where it differs from the frame's by more than
        :data:`FOLLOW_TOL` of it the frame takes it (:meth:`reframe`: the BDF2 history
        shifted into the new frame, the preconditioner rebuilt). The nonlinear wave travels
        faster than the linear phase velocity the run starts at (P1: 7.86 against 7.68);
        in its own frame the wave stands, the preconditioner's coefficients stay valid and
        the step's error is smaller. The records, snapshots and dataset stay in the run's
        first frame ξ = x − ``frame_speed`` t; ``frame_speed_end`` and ``reframes`` in the
        result. Default: on from noise or ``initial`` (runs for the nonlinear wave; P1 at
        L = 2000 reached t = 8676 in 15 minutes against 8340), off from a mode (the
        verification of the linear phase, in the lab frame).
    initial : callable, optional
        A start of the caller's: ``initial(x)`` → δ ln ν ≈ δν/ν0 at the points ``x`` in
        [0, L) of the padded grid at t = 0 (uniform in y, as the noise; projected onto the
        modes |m| ≤ M), e.g. a localised pulse for the impulse response
        (``benchmarks/probes/packet_edges.py``). It replaces the random noise of
        ``init="noise"`` (the run is a broadband start: the defaults of ``modes`` and
        ``frame_speed``, the first BDF1 step and the measurement window are the noise's; the
        dataset's ``init`` reads ``"custom"``); ``amplitude`` and ``seed`` are not used
        (``amplitude`` records max |δ ln ν|).
    """

    def __init__(
        self,
        flow: SteadyFlow,
        length: float,
        *,
        time: float | None = None,
        n: int | None = None,
        modes: int | None = None,
        dt: float | None = None,
        init: str = "mode",
        amplitude: float = 1e-6,
        seed: int = 0,
        frame_speed: float | None = None,
        top: str = "transport",
        relax: bool = True,
        snapshots: int = 6,
        record_every: int = 1,
        settings: NewtonSettings | None = None,
        min_dt_fraction: float = 1e-3,
        wave_policy: WavePolicy | None = None,
        initial: Callable[[np.ndarray], np.ndarray] | None = None,
        max_modes: int | None = None,
        max_n: int | None = None,
        x_map: bool = False,
        follow_wave: bool | None = None,
    ):
        if initial is not None:
            if not callable(initial):
                raise ParameterError(
                    f"initial = {type(initial).__name__}: a callable x -> δ ln ν(x), the initial perturbation"
                )
            init = "noise"
        if not isinstance(flow, SteadyFlow):
            raise ParameterError(
                f"flow = {type(flow).__name__}: a SteadyFlow (chuteflow.steady.solve_steady(theta, nu0))"
            )
        try:
            length = float(length)
        except (TypeError, ValueError):
            raise ParameterError(f"length = {length!r}: a positive number of diameters") from None
        if not (math.isfinite(length) and length > 0):
            raise ParameterError(f"length = {length!r}: the period L must be a positive number of diameters")
        if init not in INITS:
            raise ParameterError(f"init = {init!r}: choose one of {INITS}")
        if n is not None and not 8 <= int(n) <= 400:
            raise ParameterError(f"ny = {n} is outside [8, 400]: Chebyshev intervals that resolve the layer")
        if not (math.isfinite(min_dt_fraction) and 0 < min_dt_fraction <= 1):
            raise ParameterError(f"min_dt_fraction = {min_dt_fraction!r} must be in (0, 1]")
        self.flow = flow
        k = 2.0 * math.pi / length
        # the plain Chebyshev grid of the stability operator: the DNS grid is the same, so the
        # linear phase compares discretisation with discretisation
        plain = OperatorCache(mapped=False)
        self.mode = (
            least_stable(flow, k, cache=plain) if n is None else least_stable(flow, k, n=int(n), cache=plain)
        )
        period = 2.0 * math.pi / max(abs(self.mode.alpha.imag), 1e-12)
        modes = (2 if init == "mode" else max(8, int(length / 30))) if modes is None else int(modes)
        self.setup = DnsSetup(
            theta=float(flow.theta),
            nu0=float(flow.nu0),
            length=length,
            time=float(time) if time is not None else 2.0 * period,
            n=int(n) if n is not None else int(self.mode.n),
            modes=modes,
            dt=float(dt) if dt is not None else period / 100.0,
            init=str(init),
            amplitude=float(amplitude),
            seed=int(seed),
            model=flow.model,
            relax=bool(relax),
            frame=float(frame_speed)
            if frame_speed is not None
            else (0.0 if init == "mode" else float(self.mode.wave_speed)),
            top=str(top),
            y_max=float(flow.y_max),
            snapshots=int(snapshots),
            record_every=int(record_every),
        )
        check_setup(self.setup)
        s = self.setup
        self.disc = Discretisation(
            s.theta, s.model, s.length, flow.y_max, s.n, s.modes, frame=s.frame, top=s.top
        )
        self.stepper = Stepper(self.disc, settings)
        #: The most x modes and Chebyshev intervals :meth:`refine` may reach.
        self.max_modes = ceiling(max_modes, s.modes, MAX_MODES, "max_modes", "modes", "x modes")
        self.max_n = ceiling(max_n, s.n, MAX_N, "max_ny", "ny", "Chebyshev intervals")
        #: Whether the x grid follows the front with a tan map (``x_map``).
        self.x_map = bool(x_map)
        #: Whether the frame follows the wave's measured speed (``follow_wave``).
        self.follow_wave = bool(follow_wave) if follow_wave is not None else self.setup.init != "mode"
        self._last_C: np.ndarray | None = None  # the state :meth:`resolution` saw last
        self.min_dt_fraction = float(min_dt_fraction)
        self.wave_policy = wave_policy or WavePolicy()
        #: Re α of the least-stable mode at k = 2π/L (the fundamental; the sign decides
        #: whether :class:`~chuteflow.trackers.SaturationStop` waits for growth or decay).
        self.max_growth_rate = float(self.mode.alpha.real)
        self.relax_change = 0.0
        #: δ ln ν of ``initial`` on the padded grid (None: the ``init`` start)
        self.initial: np.ndarray | None = None
        if initial is not None:
            ds = np.asarray(initial(self.disc.x.copy()), dtype=float)
            if ds.shape != self.disc.x.shape or not np.all(np.isfinite(ds)):
                raise ParameterError(
                    f"initial: returned shape {ds.shape} (or non-finite values) for x of shape "
                    f"{self.disc.x.shape}: it must give one finite δ ln ν per point"
                )
            self.initial = ds
            self.setup = replace(self.setup, amplitude=float(np.max(np.abs(ds))))

    # -- what trackers ask ----------------------------------------------------------------
    def wave_amplitude(self, C: np.ndarray) -> float:
        """(max − min of ρ̄) over its mean: the size of the wave."""
        rho = self.disc.depth_integrals(C)[0]
        return float((rho.max() - rho.min()) / self.disc.x_mean(rho))

    def resolution(self, C: np.ndarray) -> dict[str, float]:
        """Tails of the x and y spectra (:func:`~chuteflow.dns.diagnostics.resolution_tails`)."""
        self._last_C = C
        return resolution_tails(self.disc, C)

    def key(self) -> str:
        """The run's key: a checkpoint is continued only by the run that wrote it."""
        if self.initial is None:
            return self.setup.key()
        h = hashlib.sha256(self.setup.key().encode() + self.initial.tobytes())
        return h.hexdigest()[:16]

    # -- the grid that follows the wave ----------------------------------------------------------
    def can_refine(self, direction: str = "x") -> bool:
        """Whether :meth:`refine` may still add x modes (``max_modes`` not reached) or, with
        ``direction="y"``, Chebyshev intervals (``max_n`` not reached)."""
        if direction == "y":
            return self.disc.n < self.max_n
        if self.disc.modes < self.max_modes:
            return True
        # (the modes at their ceiling: a map re-centred on the moved front may still help)
        C = self._last_C
        if not self.x_map or C is None or C.shape != self.disc.shape:
            return False
        return self._grid_choice(C) is not None

    def _grid_choice(self, C: np.ndarray):
        return best_grid(self.disc, C, self.max_modes)

    def _set_grid(self, n: int, modes: int, x_map: TanMap | None, frame: float | None = None) -> None:
        """The discretisation and the stepper at ``n`` Chebyshev intervals, ``modes`` x
        modes, the x map ``x_map`` and the frame speed ``frame`` (default the current one;
        the preconditioner's kind and the step control's switch kept: the same wave on a
        finer grid, or in another frame)."""
        s, old = self.setup, self.stepper
        self.disc = Discretisation(
            s.theta,
            s.model,
            s.length,
            self.flow.y_max,
            int(n),
            int(modes),
            frame=self.disc.frame if frame is None else float(frame),
            top=s.top,
            x_map=x_map,
        )
        self.stepper = Stepper(self.disc, old.settings)
        if self.disc.modes >= 1:
            self.stepper.use(old.kind)  # the columns give way to the coupled blocks where too fine
        self.stepper.switch_dt = old.switch_dt

    def refine(self, state: DnsState, direction: str = "x") -> None:
        """Refine the run's grid in place: double the x modes (at most ``max_modes``) or, with
        ``direction="y"``, grow the Chebyshev intervals by half (at most ``max_n``). With
        ``x_map``, an x refinement goes to the grid :func:`~chuteflow.dns.remap.best_grid`
        chooses (a tan map centred at the front, at the run's modes or 3/2 as many; the
        state evaluated exactly at the new points, :func:`~chuteflow.dns.remap.remap_coefficients`).

        The state is the same function on the finer grid — its Fourier coefficients padded
        with zeros, or its Chebyshev interpolant evaluated at the finer nodes; the BDF2
        history level likewise — apart from a uniform shift of ln ν by the coarse
        quadrature's error, which keeps the total mass the run conserved. So the run goes on
        as it was, only with room for a steeper wave; the records so far (ρ̄, Q, the
        snapshots) are interpolated onto the finer grid, so that the result has one grid.
        ``refine_t``, ``refine_modes`` and ``refine_n`` record it.
        """
        if direction not in ("x", "y"):
            raise ParameterError(f"direction = {direction!r}: choose 'x' or 'y'")
        if not self.can_refine(direction):
            name, ceil = ("max_modes", self.max_modes) if direction == "x" else ("max_ny", self.max_n)
            raise ParameterError(f"{name} = {ceil}: the grid has as many {direction} points already")
        old, old_stepper = self.disc, self.stepper
        modes, n, x_map = old.modes, old.n, old.x_map
        remap = direction == "x" and self.x_map
        if remap:
            choice = self._grid_choice(state.C)
            if choice is None:
                raise ParameterError(
                    f"max_modes = {self.max_modes}: no map at these modes resolves the front better"
                )
            modes, x_map = choice.modes, choice.x_map
        elif direction == "x":
            modes = min(2 * max(old.modes, 1), self.max_modes)
        else:
            n = _refined_n(old.n, self.max_n)
        levels = [state.C] if state.prev is None else [state.C, history_coefficients(old, tuple(state.prev))]
        # the total mass of each level by the coarse grid's quadrature (what the run conserved)
        mass = [old.total_mass(*self._mass_fields(old_stepper, C)) for C in levels]
        self._set_grid(n, modes, x_map)
        new = self.disc
        if remap:
            fine = [remap_coefficients(C, old, new) for C in levels]
        elif direction == "x":
            fine = [_pad_modes(C, modes) for C in levels]
        else:
            fine = [_to_nodes(C, old.grid, new.grid, axis=1) for C in levels]
        for C, m in zip(fine, mass):
            # the finer quadrature of the same function differs by the coarse one's error (x:
            # aliasing, y: Clenshaw–Curtis of e^s): a uniform shift of ln ν of that size keeps
            # the mass the run conserved
            C[0, :, 0] += math.log(m / new.total_mass(*self._mass_fields(self.stepper, C)))
        state.C = fine[0]
        if len(fine) > 1:
            state.prev = np.array(self.stepper.physical(fine[1]))
        r = state.records
        if direction == "x":
            # (the records are on the uniform x grid of nxp points, mapped or not)
            C0 = state.C_init
            state.C_init = remap_coefficients(C0, old, new) if remap else _pad_modes(C0, modes)
            if new.nxp != old.nxp:
                for k in ("rho", "Q", "snaps"):
                    r[k] = [fourier_resample(v, new.nxp) for v in r[k]]
        else:
            state.C_init = _to_nodes(state.C_init, old.grid, new.grid, axis=1)
            r["snaps"] = [_to_nodes(v, old.grid, new.grid, axis=1) for v in r["snaps"]]
        r["refine_n"] = _refine_n(r, self.setup.n)
        r["refine_beta"] = _backfilled(r, "refine_beta", 1.0)
        r["refine_centre"] = _backfilled(r, "refine_centre", 0.0)
        r["refine_t"].append(state.t)
        r["refine_modes"].append(modes)
        r["refine_n"].append(n)
        r["refine_beta"].append(1.0 if x_map is None else x_map.beta)
        r["refine_centre"].append(0.0 if x_map is None else x_map.centre)
        state.x_map = None if x_map is None else (x_map.centre, x_map.beta)

    def reframe(self, state: DnsState, speed: float) -> None:
        """Move the run into the frame ξ' = x − ``speed`` t, coinciding with the current one
        now (``follow_wave``): the BDF2 history level, at t − h, is the same function shifted
        by (``speed`` − c) h (ln ν, u, v, T evaluated exactly from their series; ν times the
        factor that keeps its total mass, as :meth:`refine` does), the discretisation takes
        the new frame and the stepper starts afresh (its
        preconditioner had the old frame's transport). ``records["frame_t"]``,
        ``records["frame_speed"]`` note it."""
        d = self.disc
        speed = float(speed)
        if not math.isfinite(speed):
            raise ParameterError(f"speed = {speed!r}: a finite frame speed")
        if state.prev is not None:
            old = np.asarray(state.prev)
            new = self._shifted(old, (speed - d.frame) * state.h_prev)
            # the quadrature of e^s at the shifted points differs by its aliasing error (2.4e-9
            # of the mass at P1, L = 1000, nx 17): a uniform factor keeps the mass the run conserved
            new[0] *= d.total_mass(old[0], old[3][-1]) / d.total_mass(new[0], new[3][-1])
            state.prev = new
        self._set_grid(d.n, d.modes, d.x_map, speed)
        state.frame = speed
        state.records["frame_t"].append(state.t)
        state.records["frame_speed"].append(speed)

    def _shifted(self, fields: np.ndarray, delta: float) -> np.ndarray:
        """(ν, u, v, T) on the padded grid → the same functions at x − ``delta``."""
        f = np.array(fields, dtype=float)
        f[0] = np.log(f[0])
        out = self._at(f, self.disc.x - delta)
        out[0] = np.exp(out[0])
        return out

    def wave_speed_now(self, state: DnsState) -> float | None:
        """The wave's lab speed over the last :data:`FOLLOW_WINDOW` records, all after the
        last change of frame (the records themselves are in the run's first frame): the
        phase of ρ̄'s dominant mode, least squares in t; None where the wave is
        still linear (below :data:`FOLLOW_AMPLITUDE`), the records are fewer, or the two
        halves of the window give speeds more than :data:`FOLLOW_TOL` apart (a transient:
        the start from a mode at finite amplitude measured 14.2 against the mode's 7.8)."""
        r = state.records
        since = r["frame_t"][-1] if r["frame_t"] else -math.inf
        t = np.asarray(r["t"][-FOLLOW_WINDOW:], dtype=float)
        if len(t) < FOLLOW_WINDOW or t[0] <= since:
            return None
        rho = np.asarray(r["rho"][-FOLLOW_WINDOW:])
        last = rho[-1]
        if (last.max() - last.min()) < FOLLOW_AMPLITUDE * last.mean():
            return None
        R = np.fft.rfft(rho, axis=-1)
        m = 1 + int(np.argmax(np.abs(R[-1, 1:])))
        phase = np.unwrap(np.angle(R[:, m]))
        k = 2.0 * math.pi * m / self.setup.length

        def speed(sl: slice) -> float:
            # e^{ik(ξ − v t)} in the records' frame ξ = x − c_0 t: the phase falls at k v
            return self.setup.frame - float(np.polyfit(t[sl] - t[0], phase[sl], 1)[0]) / k

        c = speed(slice(None))
        half = FOLLOW_WINDOW // 2
        if abs(speed(slice(None, half)) - speed(slice(half, None))) > FOLLOW_TOL * abs(c):
            return None  # (not one speed over the window: a transient, or waves of several speeds)
        return c

    @staticmethod
    def _mass_fields(stepper: Stepper, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        nu, _, _, T = stepper.physical(C)
        return nu, T[-1]

    def _follow(self, state: DnsState) -> None:
        """Put the discretisation at the grid of ``state`` (a checkpoint of a refined run)."""
        n, modes = state.C.shape[1] - 1, state.C.shape[-1] - 1
        x_map = None if state.x_map is None else TanMap(state.x_map[0], state.x_map[1], self.setup.length)
        frame = self.setup.frame if state.frame is None else state.frame
        if (n, modes, x_map, frame) != (self.disc.n, self.disc.modes, self.disc.x_map, self.disc.frame):
            self._set_grid(n, modes, x_map, frame)
        r = state.records
        r["refine_n"] = _refine_n(r, self.setup.n)
        r["refine_beta"] = _backfilled(r, "refine_beta", 1.0)
        r["refine_centre"] = _backfilled(r, "refine_centre", 0.0)

    # -- the state ---------------------------------------------------------------------------
    def initial_state(self) -> DnsState:
        """The state at t = 0 (the relaxed steady flow plus the perturbation)."""
        s = self.setup
        if self.initial is None:
            C, Cm, self.relax_change = initial_coefficients(self.disc, self.flow, self.mode, s, s.dt, s.relax)
        else:
            # the caller's δ ln ν on the relaxed steady state, a BDF1 first step (as from noise)
            C, _, self.relax_change = initial_coefficients(
                self.disc, self.flow, self.mode, replace(s, amplitude=0.0), s.dt, s.relax
            )
            C[0, :, 1:] += self.disc.to_modes(self.initial)[None, 1:]
            _check_valid(self.disc, C, s)
            Cm = None
        prev = None if Cm is None else np.array(self.stepper.physical(Cm))
        st = DnsState(
            C=C,
            prev=prev,
            t=0.0,
            step=0,
            dt=s.dt,
            h_prev=s.dt,
            restart=prev is None,
            C_init=C.copy(),
            amplitude=self.wave_amplitude(C),
        )
        self._record(st)
        self._snapshot(st)
        return st

    def _uniform(self, f: np.ndarray, shift: float = 0.0) -> np.ndarray:
        """Values on the padded grid → the same function at the uniform x points
        ``disc.s`` (the records' grid) of the run's first frame, ``shift`` behind the
        current one (:attr:`DnsState.frame_shift`): itself without a map or shift; else its
        series in s (all the padded grid's modes below Nyquist) evaluated exactly at
        s = g⁻¹(x − shift)."""
        d = self.disc
        if d.x_map is None and shift == 0.0:
            return f
        return self._at(f, d.s - shift)

    def _at(self, f: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Values on the padded grid → the same function at the points ``x`` of the current
        frame: its series in s (all the padded grid's modes below Nyquist) evaluated exactly
        at s = g⁻¹(x)."""
        d = self.disc
        c = scipy.fft.rfft(f, axis=-1, norm="forward")[..., : (d.nxp - 1) // 2 + 1]
        return fourier_evaluate(c, self._s_at(x), d.length)

    def _s_at(self, x: np.ndarray) -> np.ndarray:
        """The computational coordinate s of the points ``x`` (modulo L) of the current frame."""
        d = self.disc
        pts = np.mod(x, d.length)
        return pts if d.x_map is None else d.x_map.s(pts)

    def _record(self, st: DnsState) -> None:
        rho, Q = self.disc.depth_integrals(st.C)
        tails = self.resolution(st.C)
        r = st.records
        # (the mean by the run's own quadrature, g'-weighted on a mapped grid: the mass it
        # conserves; the uniform samples of a mapped run's ρ̄ differ from it by their
        # interpolation error)
        r["rho_mean"].append(float(self.disc.x_mean(rho)))
        rho, Q = self._uniform(rho, st.frame_shift), self._uniform(Q, st.frame_shift)
        r["t"].append(st.t)
        r["rho"].append(rho)
        r["Q"].append(Q)
        r["x_tail"].append(tails["x_tail"])
        r["y_tail"].append(tails["y_tail"])

    def _snapshot(self, st: DnsState) -> None:
        d = self.disc
        if d.x_map is None and st.frame_shift == 0.0:
            s = np.stack([d.to_physical(st.C[i]) for i in range(4)])
        else:  # (on the records' uniform x grid: the series evaluated exactly there)
            s = fourier_evaluate(st.C, self._s_at(d.s - st.frame_shift), d.length)
        s[0] = np.exp(s[0])
        st.records["snap_t"].append(st.t)
        st.records["snaps"].append(s)

    # -- the time loop ---------------------------------------------------------------------------
    def run(
        self,
        trackers=(),
        *,
        state: DnsState | None = None,
        checkpoint: str | os.PathLike | None = None,
        checkpoint_every: float = 30.0,
    ) -> DnsState:
        """Step to ``time`` (or until a tracker stops the run); returns the final state.

        ``state``: continue from it (default: the checkpoint at ``checkpoint`` if it holds
        this run, else :meth:`initial_state`). With ``checkpoint`` the state is saved every
        ``checkpoint_every`` seconds of wall time and at the end (also when the run stops
        early, or is paused by :class:`~chuteflow.trackers.WallTimeStop`: the partial result
        is kept); it is removed once the run has finished.
        A Newton failure halves Δt (BDF1 restart) down to ``min_dt_fraction`` × ``dt``, then
        the run stops with status ``"stopped at t = …: why"`` and the data so far.
        """
        s, stepper = self.setup, self.stepper
        trackers = list(trackers)
        key = self.key()
        if state is None and checkpoint is not None and Path(checkpoint).exists():
            # the trackers are initialised first and then given their saved data back
            probe = self.initial_state()
            for tr in trackers:
                tr.initialize(self, probe, s.time)
            state = DnsState.load(checkpoint, key, trackers) or probe
            self._follow(state)
            if state.solver:
                self.stepper.restore(state.solver)
        elif state is None:
            state = self.initial_state()
            for tr in trackers:
                tr.initialize(self, state, s.time)
        else:
            self._follow(state)
            for tr in trackers:
                tr.initialize(self, state, s.time)
        state.status = "running"
        n_steps = int(math.ceil(s.time / s.dt - 1e-9))
        snap_steps = sorted(
            {int(round(i * n_steps / max(s.snapshots - 1, 1))) for i in range(max(s.snapshots, 1))}
        )
        start = _time.perf_counter()
        wall0 = state.wall
        last_ck = start
        ok_since_change = 0
        stop: str | None = None
        ctl = stepper.settings
        dt_lo, dt_hi = s.dt, max(ctl.dt_max or 64.0 * s.dt, s.dt)
        if ctl.dt_tol > 0:
            self.stepper.switch_dt = dt_lo
        if state.prev is not None and state.prev.shape[-1] != self.disc.nxp:
            # a checkpoint of an earlier padded grid (the default nxp changed on 2026-12-07)
            state.prev = fourier_resample(state.prev, self.disc.nxp)
        while state.t < s.time * (1 - 1e-12):
            disc, stepper = self.disc, self.stepper  # (refine replaces them)
            h = min(state.dt, s.time - state.t)
            C = state.C
            now_phys = stepper.physical(C)
            first = state.restart or state.prev is None
            prev = tuple(state.prev) if state.prev is not None else now_phys
            guess = None
            if not first and state.prev is not None:
                # (from the stored level, so that a resumed run takes the same steps)
                C_prev = history_coefficients(disc, tuple(state.prev))
                # linear extrapolation in time: Newton's starting point
                guess = C + (h / state.h_prev) * (C - C_prev)
            try:
                C_new, info = stepper.step(
                    C, (now_phys, prev), h, first=first, guess=guess, ratio=h / state.h_prev
                )
            except ConvergenceError as exc:
                state.dt *= 0.5
                state.restart = True
                stepper.reset()
                if state.dt < self.min_dt_fraction * s.dt:
                    stop = f"stopped at t = {state.t:.6g}: {exc}"
                    break
                continue
            if not np.all(np.isfinite(C_new)):
                stop = f"stopped at t = {state.t:.6g}: non-finite fields (the flow left the closures' range)"
                break
            grow = False
            if ctl.dt_tol > 0 and guess is not None:
                # Δt control (NewtonSettings.dt_tol): halve (repeat the step above 2 dt_tol),
                # double well below, unless GMRES struggles (its counts, unlike the error, can
                # differ after a resume, which rebuilds the preconditioner)
                err = stepper.step_error(C_new, guess)
                if err > ctl.dt_tol and state.dt > dt_lo:
                    state.dt = max(0.5 * state.dt, dt_lo)
                    if err > 2 * ctl.dt_tol:
                        continue
                grow = err < ctl.dt_tol / 8 and h >= state.dt * (1 - 1e-12) and info.krylov <= ctl.dt_krylov
                if info.krylov > 2 * ctl.dt_krylov and state.dt > dt_lo:
                    state.dt = max(0.5 * state.dt, dt_lo)  # the cost side: GMRES struggles
            t_prev = state.t
            state.prev, state.C = np.array(now_phys), C_new
            state.h_prev = h
            state.restart = False
            state.t += h
            state.step += 1
            state.frame_shift += (disc.frame - s.frame) * h
            state.records["newton"].append(info.newton)
            state.records["krylov"].append(info.krylov)
            ok_since_change += 1
            if grow:
                state.dt = min(2 * state.dt, dt_hi)
            elif ctl.dt_tol == 0 and state.dt < s.dt and ok_since_change >= 20:
                state.dt, ok_since_change = min(2 * state.dt, s.dt), 0
            if state.step % s.record_every == 0 or state.t >= s.time * (1 - 1e-12):
                self._record(state)
                speed = self.wave_speed_now(state) if self.follow_wave else None
                if speed is not None and abs(speed - disc.frame) > FOLLOW_TOL * abs(speed):
                    self.reframe(state, speed)
            snaps_t = state.records["snap_t"]
            if any(t_prev + 0.5 * s.dt <= k * s.dt < state.t + 0.5 * s.dt for k in snap_steps[1:]) and (
                not snaps_t or state.t - snaps_t[-1] > 0.5 * s.dt
            ):
                self._snapshot(state)
            step = DnsStep(C, C_new, t_prev, state.t, state.step)
            stops = [r for r in [tr.handle(self, step) for tr in trackers] if r]
            refine = [r for r in stops if r in ("refine x", "refine y")]
            if refine:
                # the grid follows the wave (ResolutionMonitor, action="refine")
                stops = [r for r in stops if r not in refine]
                direction = refine[0][-1]
                self.refine(state, direction)
                for tr in trackers:
                    tr.refined(self, state, direction)
            if checkpoint is not None and _time.perf_counter() - last_ck > checkpoint_every:
                last_ck = _time.perf_counter()
                state.wall = wall0 + last_ck - start
                state.solver = self.stepper.snapshot()
                state.save(checkpoint, key, trackers)
            if stops:
                stop = stops[0]
                break
        state.wall = wall0 + _time.perf_counter() - start
        state.status = stop or "ok"
        if state.records["t"][-1] < state.t:
            self._record(state)
        snaps_t = state.records["snap_t"]
        if snaps_t and snaps_t[-1] < state.t - 0.5 * s.dt:
            self._snapshot(state)
        for tr in trackers:
            tr.finalize(self, state)
        if checkpoint is not None:
            if state.status.startswith(("stopped", "paused")):
                state.solver = self.stepper.snapshot()
                state.save(checkpoint, key, trackers)  # the partial run is kept
            elif Path(checkpoint).exists():
                Path(checkpoint).unlink()
        return state

    # -- the result -----------------------------------------------------------------------------
    def dataset(self, state: DnsState) -> xr.Dataset:
        """The run as an :class:`xarray.Dataset` (see :func:`chuteflow.dns.simulate`)."""
        disc, setup, flow, mode = self.disc, self.setup, self.flow, self.mode
        r = state.records
        t = np.asarray(r["t"], dtype=float)
        rho = np.asarray(r["rho"])
        Q = np.asarray(r["Q"])
        newton = r["newton"]
        x = disc.s  # (the records' uniform grid, also where the run ends mapped)
        # mode-1 coefficient of ρ̄(x): amplitude of the wave e^{ikx}
        A = (
            np.fft.rfft(rho, axis=-1)[:, 1] / disc.nxp
            if disc.nxp > 2 and rho.size
            else np.zeros(len(t), complex)
        )
        if len(r["rho_mean"]) == len(t):
            mass = np.asarray(r["rho_mean"], dtype=float) * setup.length
        else:  # (a checkpoint from before the record: the uniform grid's mean)
            mass = rho.mean(axis=-1) * setup.length if rho.size else np.zeros(0)
        k = 2.0 * math.pi / setup.length
        # linear phase: the records while the wave is below 1e-3 of the mean ρ̄ (all, from a mode)
        if setup.init == "mode":
            lin = np.arange(len(t)) >= 1
        else:
            rel = np.abs(A) / (rho.mean(axis=-1) + 1e-300)
            lin = (t >= 0.2 * t[-1] if len(t) else np.zeros(0, bool)) & (rel < 1e-3)
        meas = measure_mode(t[lin], A[lin], k)
        # back to the lab frame: a phase e^{ik(ξ − c' t)} with ξ = x − c t travels at c + c'
        meas["phase_velocity"] += setup.frame
        alpha_dns = complex(math.nan, math.nan)
        if setup.init == "mode" and lin.sum() > 2 and np.all(np.abs(A[lin]) > 0):
            dts = np.diff(t[lin])
            G = A[lin][1:] / A[lin][:-1]
            same = np.abs(dts - setup.dt) < 1e-9 * setup.dt
            if same.any():
                gm = np.exp(np.mean(np.log(G[same])))
                alpha_dns = bdf2_eigenvalue(gm, setup.dt) - 1j * k * setup.frame
        mass_drift = float(np.max(np.abs(mass - mass[0])) / mass[0]) if mass.size else math.nan
        change = float(np.max(np.abs(state.C[:, :, 0] - state.C_init[:, :, 0])))
        sn = np.asarray(r["snaps"]) if r["snaps"] else np.zeros((0, 4, disc.n + 1, disc.nxp))
        waves = wave_measures(t, rho, setup.length, setup.frame, status=state.status, policy=self.wave_policy)
        x_tail = np.asarray(r["x_tail"], dtype=float)
        y_tail = np.asarray(r["y_tail"], dtype=float)
        attrs = {
            "theta": setup.theta,
            "nu0": setup.nu0,
            "length": setup.length,
            "k": k,
            "ny": disc.n,
            "nx": 2 * disc.modes + 1,
            "modes": disc.modes,
            "nx_padded": disc.nxp,
            # the grid that followed the wave (max_modes, max_n): where it started, when it grew
            "nx_initial": 2 * setup.modes + 1,
            "nx_max": 2 * self.max_modes + 1,
            "ny_initial": setup.n,
            "ny_max": self.max_n,
            "refinements": len(r["refine_t"]),
            "refined_at": _refined_at(r, setup),
            # the tan map of the x grid the run ends on (β 1: uniform; x_map)
            "x_map": int(self.x_map),
            "follow_wave": int(self.follow_wave),
            "x_map_beta": 1.0 if disc.x_map is None else disc.x_map.beta,
            "x_map_centre": 0.0 if disc.x_map is None else disc.x_map.centre,
            "dt": setup.dt,
            "time_end": float(t[-1]) if len(t) else 0.0,
            "init": "custom" if self.initial is not None else setup.init,
            "amplitude": setup.amplitude,
            "seed": setup.seed,
            "frame_speed": setup.frame,
            # the frame the run ended in (follow_wave; the records stay in frame_speed's)
            "frame_speed_end": float(disc.frame),
            "reframes": len(r["frame_t"]),
            "top": setup.top,
            "y_max": flow.y_max,
            "growth_rate": meas["growth_rate"],
            "phase_velocity": meas["phase_velocity"],
            "alpha_re": float(mode.alpha.real),
            "alpha_im": float(mode.alpha.imag),
            "alpha_n": int(mode.n),
            "alpha_dns_re": float(alpha_dns.real),
            "alpha_dns_im": float(alpha_dns.imag),
            "mass_drift": mass_drift,
            "mean_flow_change": change,
            "status": state.status,
            "steps": len(newton),
            "newton_mean": float(np.mean(newton)) if newton else 0.0,
            "krylov_mean": float(np.mean(r["krylov"])) if r["krylov"] else 0.0,
            # what Newton solved each step to (NewtonSettings.newton_rtol; 0: atol alone)
            "newton_rtol": float(self.stepper.settings.newton_rtol),
            "wall_time": float(state.wall),
            "time_per_step": float(state.wall / max(len(newton), 1)),
            # dQ0/dρ̄0 of the steady family at fixed θ (eq. (B 6), the k → 0 limit of the phase
            # velocity) — not the eigenmode's phase velocity at k = 2π/L, which is stored apart
            "kinematic_wave_speed": float(steady_tangent(flow)["dQ_drho"]),
            "mode_phase_velocity": float(mode.wave_speed),
            "rho_bar0": flow.rho_bar,
            "Q0": flow.Q,
            # the run's tails on the grid it ends on (the monitor's series, run_tail)
            "x_tail": run_tail(x_tail[_on_last_grid(r, setup, "x") :]),
            "y_tail": run_tail(y_tail[_on_last_grid(r, setup, "y") :]),
            "x_tail_end": float(x_tail[-1]) if x_tail.size else 0.0,
            "y_tail_end": float(y_tail[-1]) if y_tail.size else 0.0,
            "steady_relaxation": self.relax_change,
            **waves,
            **{f"model_{k_}": v for k_, v in setup.model.attrs().items()},
        }
        empty = np.zeros((0, disc.n + 1, disc.nxp))
        return xr.Dataset(
            {
                "rho_bar": (("time", "x"), rho, {"long_name": "ρ̄ = ∫ν dy (with the isothermal tail)"}),
                "Q": (("time", "x"), Q, {"long_name": "Q = ∫νu dy"}),
                "mass": (("time",), mass, {"long_name": "∫∫ν dy dx (by the run's quadrature)"}),
                "amplitude_re": (("time",), A.real, {"long_name": "Re of the k = 2π/L coefficient of ρ̄"}),
                "amplitude_im": (("time",), A.imag, {"long_name": "Im of the k = 2π/L coefficient of ρ̄"}),
                "x_tail": (
                    ("time",),
                    x_tail,
                    {"long_name": "highest x modes / largest (amplitude)", "units": "1"},
                ),
                "y_tail": (
                    ("time",),
                    y_tail,
                    {"long_name": "highest Chebyshev coefficients / largest", "units": "1"},
                ),
                "nu": (("snapshot_time", "y", "x"), sn[:, 0] if len(sn) else empty),
                "u": (("snapshot_time", "y", "x"), sn[:, 1] if len(sn) else empty),
                "v": (("snapshot_time", "y", "x"), sn[:, 2] if len(sn) else empty),
                "T": (("snapshot_time", "y", "x"), sn[:, 3] if len(sn) else empty),
            },
            coords={
                "time": t,
                "x": ("x", x, {"long_name": f"ξ = x − {setup.frame:g} t (the frame of the run)"}),
                "y": disc.grid.y,
                "snapshot_time": np.asarray(r["snap_t"], dtype=float),
            },
            attrs=attrs,
        )
