"""The simulation in one call: :func:`simulate` (a :class:`DnsSimulation` with its trackers)
and :func:`summary` (the JSON scalars of ``chuteflow dns --json``)."""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from ..steady import SteadyFlow
from ..trackers import (
    ProgressTracker,
    ResolutionMonitor,
    ResolutionWarning,
    SaturationStop,
    Tracker,
    WallTimeStop,
    WavePolicy,
)
from .diagnostics import bdf2_eigenvalue, measure_mode
from .setup import INITS, DnsSetup, relax_steady
from .simulation import DnsSimulation
from .stepper import NewtonSettings

__all__ = ["DnsSetup", "simulate", "summary", "relax_steady", "measure_mode", "bdf2_eigenvalue", "INITS"]


def _checkpoint_path(out: str | os.PathLike | None, checkpoint: str | os.PathLike | None) -> Path | None:
    if checkpoint is not None:
        return Path(checkpoint)
    if out is not None:
        return Path(str(out) + ".checkpoint.npz")
    return None


def simulate(
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
    out: str | os.PathLike | None = None,
    checkpoint: str | os.PathLike | None = None,
    checkpoint_every: float = 30.0,
    progress: Callable[[float, float], None] | None = None,
    saturation_tol: float | None = None,
    resolution_tol: float = 1e-4,
    trackers: Sequence[Tracker] = (),
    settings: NewtonSettings | None = None,
    min_dt_fraction: float = 1e-3,
    initial: Callable[[np.ndarray], np.ndarray] | None = None,
    wall_limit: float | None = None,
    max_modes: int | None = None,
    max_n: int | None = None,
    x_map: bool = False,
    follow_wave: bool | None = None,
) -> xr.Dataset:
    """Simulate the time-dependent equations on a slope periodic in x (docs/dns.md).

    A :class:`DnsSimulation` of ``flow`` run with a
    :class:`~chuteflow.trackers.ProgressTracker` for ``progress``, a
    :class:`~chuteflow.trackers.SaturationStop` for ``saturation_tol``, a
    :class:`~chuteflow.trackers.ResolutionMonitor` (warns when the highest modes carry more
    than ``resolution_tol``) and the caller's ``trackers``: the same names as the 1D model's
    :func:`chuteflow.reduced.simulate` (``time``, ``snapshots``, ``frame_speed``, ``progress``,
    ``trackers``).

    Parameters
    ----------
    flow : SteadyFlow
        The steady flow (:func:`chuteflow.steady.solve_steady`): θ, ν0(0) and the closures.
    length : float
        Period L along the slope; the fundamental wavenumber is k = 2π/L.
    time, n, modes, dt, init, amplitude, seed, frame_speed, top, relax
        See :class:`DnsSimulation`.
    snapshots, record_every, settings, min_dt_fraction, initial
        See :class:`DnsSimulation` (``initial``: a callable δ ln ν(x), e.g. a localised pulse).
    out : path, optional
        NetCDF file written at the end (also for a run that stopped early: the partial
        result); its checkpoint is ``out + ".checkpoint.npz"``.
    checkpoint : path, optional
        Checkpoint file (overrides the one derived from ``out``). A run with the same
        parameters continues from it; it is removed once the run has finished.
    checkpoint_every : float
        Seconds of wall time between checkpoints.
    progress : callable, optional
        Called as ``progress(t, time)`` after each step.
    saturation_tol : float, optional
        Stop once the wave's amplitude (max − min of ρ̄ over its mean) has grown tenfold and
        changed by less than this, relative, over the last tenth of the run (sampled every
        ``time``/200); ``time`` is then the longest run. Also the tolerance of the verdict
        (:class:`~chuteflow.trackers.WavePolicy`; default 0.02).
    resolution_tol : float
        Tolerance of the spectra's tails (``x_tail``, ``y_tail``; a
        :class:`~chuteflow.trackers.ResolutionWarning` above it).
    trackers : sequence of Tracker
        More trackers (:mod:`chuteflow.trackers`).
    max_modes : int, optional
        Let the x grid follow the wave (:meth:`DnsSimulation.refine`): the modes double,
        up to this many, wherever the x tail rises past ``resolution_tol`` / 4, so that a
        steepening front (P5's bore) stays resolved; default: the grid is kept and a
        rising tail only warns. ``nx``, ``refinements`` and ``refined_at`` in the result.
    max_n : int, optional
        The same in y: the Chebyshev intervals grow by half (to a multiple of 8), up to this
        many, wherever the y tail rises past ``resolution_tol`` / 4; ``ny``, ``ny_initial``
        in the result.
    x_map : bool
        Let the x grid follow the front with a tan map (:class:`DnsSimulation`): where the x
        tail rises the run goes to a map centred at the steepest point of ln ν, at the
        run's modes where that suffices, and re-centres it as the front moves; ``x_map_beta``,
        ``x_map_centre`` and ``refined_at`` in the result (the records stay on a uniform x).
    follow_wave : bool, optional
        Let the frame follow the nonlinear wave's measured speed (:class:`DnsSimulation`;
        default on from noise, off from a mode); ``frame_speed_end`` and ``reframes`` in the
        result (the records stay in the frame of ``frame_speed``).
    wall_limit : float, optional
        Seconds of wall time after which the run pauses
        (:class:`~chuteflow.trackers.WallTimeStop`): status ``"paused at t = …"``, the wave
        so far judged (e.g. ``verdict`` ``growing``), the checkpoint kept so that the same
        call continues.

    Returns
    -------
    xarray.Dataset
        ``rho_bar(time, x)``, ``Q(time, x)``, ``mass(time)``, ``amplitude_re/_im(time)`` (mode-1
        coefficient of ρ̄), ``x_tail(time)``, ``y_tail(time)``, fields ``nu, u, v, T(snapshot,
        y, x)``, and as attributes the measured ``growth_rate``, ``phase_velocity``, the
        eigenvalue compared with (``alpha_re``, ``alpha_im``), the BDF2-inverted discrete
        eigenvalue (``alpha_dns_re``, ``alpha_dns_im``), ``mode_phase_velocity`` = −Im α/k,
        ``kinematic_wave_speed`` = dQ0/dρ̄0 (eq. (B 6)), the wave at the end
        (:func:`~chuteflow.dns.diagnostics.wave_measures`: ``verdict``, ``rho_min_rel``,
        ``rho_max_rel``, ``wave_speed``, ``wavelength``, ``t_saturation``,
        ``amplitude_growth``), the largest tails
        ``x_tail``, ``y_tail``, ``mass_drift``, ``status``, timings and the model.
    """
    sim = DnsSimulation(
        flow,
        length,
        time=time,
        n=n,
        modes=modes,
        dt=dt,
        init=init,
        amplitude=amplitude,
        seed=seed,
        frame_speed=frame_speed,
        top=top,
        relax=relax,
        snapshots=snapshots,
        record_every=record_every,
        settings=settings,
        min_dt_fraction=min_dt_fraction,
        initial=initial,
        max_modes=max_modes,
        max_n=max_n,
        x_map=x_map,
        follow_wave=follow_wave,
        wave_policy=WavePolicy(tol=saturation_tol) if saturation_tol is not None else None,
    )
    tracking: list[Tracker] = []
    if progress is not None:
        tracking.append(ProgressTracker(progress))
    if saturation_tol is not None:
        tracking.append(SaturationStop(saturation_tol, interval=sim.setup.time / 200, min_samples=20))
    monitor = ResolutionMonitor(
        resolution_tol,
        every=max(1, 10 // sim.setup.record_every),
        # (with a map the run may re-centre it at the most modes)
        action="refine" if sim.x_map or sim.can_refine("x") or sim.can_refine("y") else "warn",
        settle=sim.setup.init == "noise",  # (a custom start too)
    )
    tracking.append(monitor)
    if wall_limit is not None:
        tracking.append(WallTimeStop(wall_limit))
    tracking.extend(trackers)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ResolutionWarning)
        state = sim.run(
            tracking, checkpoint=_checkpoint_path(out, checkpoint), checkpoint_every=checkpoint_every
        )
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    ds = sim.dataset(state)
    ds.attrs["resolution_tol"] = float(resolution_tol)
    ds.attrs["resolution_warnings"] = "; ".join(
        str(w.message) for w in caught if w.category is ResolutionWarning
    )
    if out is not None:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(out, engine="h5netcdf")
    return ds


def summary(ds: xr.Dataset) -> dict:
    """JSON-ready scalars of a run (what ``chuteflow dns --json`` prints)."""
    keys = (
        "theta",
        "nu0",
        "length",
        "k",
        "nx",
        "ny",
        "nx_initial",
        "ny_initial",
        "refinements",
        "x_map_beta",
        "x_map_centre",
        "dt",
        "time_end",
        "init",
        "amplitude",
        "frame_speed",
        "frame_speed_end",
        "reframes",
        "growth_rate",
        "phase_velocity",
        "alpha_re",
        "alpha_im",
        "alpha_dns_re",
        "alpha_dns_im",
        "kinematic_wave_speed",
        "mode_phase_velocity",
        "mass_drift",
        "mean_flow_change",
        "steady_relaxation",
        "verdict",
        "rho_min_rel",
        "rho_max_rel",
        "wave_speed",
        "wavelength",
        "t_saturation",
        "amplitude_growth",
        "x_tail",
        "y_tail",
        "resolved",
        "steps",
        "newton_mean",
        "krylov_mean",
        "newton_rtol",
        "time_per_step",
        "wall_time",
        "status",
    )
    out: dict = {}
    for k_ in keys:
        v = ds.attrs.get(k_)
        if k_ == "resolved":
            v = bool(max(ds.attrs["x_tail"], ds.attrs["y_tail"]) <= ds.attrs.get("resolution_tol", 1e-4))
        if isinstance(v, np.generic):
            v = v.item()
        out[k_] = v
    ar, ai = float(out["alpha_re"]), float(out["alpha_im"])
    c_mode = -ai / float(out["k"])
    out["growth_rate_error"] = abs(out["growth_rate"] - ar) / abs(ar) if ar else math.nan
    out["phase_velocity_error"] = abs(out["phase_velocity"] - c_mode) / abs(c_mode) if c_mode else math.nan
    return out
