"""The saturated density waves mapped over flows: one run from noise to saturation per flow.

:func:`map_waves` runs :func:`chuteflow.dns.simulate` from small noise at each (θ, ν0(0)) of a
list until the wave's amplitude settles (:class:`~chuteflow.trackers.SaturationStop`) or the
time runs out, in parallel over the flows (a process pool, or a Dask cluster: ``client=`` or
``scheduler=``), each run written to its own
NetCDF file in ``out_dir`` with its checkpoint beside it: a killed map continues where every
run stood, and a finished run is read back instead of re-run. The result has, per flow, the
wave at the end (:func:`~chuteflow.trackers.wave_measures`: verdict, min/max of ρ̄ relative to
its mean, wave speed, wavelength that won, time to saturate), its shape ρ̄(ξ)/⟨ρ̄⟩ − 1 in the
co-moving frame (crest at L/2), next to the linear growth rate and phase velocity of the
fundamental k = 2π/L, the mass drift and the resolution tails. Each flow may have its own
period L (``(θ, ν0, L)`` points): flows far apart are unstable at different lengths (at the
paper's points L_c ≈ 880 at P1, ≈ 2000 at P5, ≈ 6300 at P4).
"""

from __future__ import annotations

import math
import os
import uuid
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from ..closures import ChuteModel
from ..errors import ParameterError
from ..spectral import fourier_resample
from ..trackers import WallTimeStop
from .simulation import MAX_MODES, MAX_N, ceiling
from .stepper import NewtonSettings, step_settings

__all__ = ["WaveMapSettings", "map_waves", "WAVE_KEYS"]

#: Per-flow scalars of :func:`map_waves` (and of ``chuteflow waves --json``).
WAVE_KEYS = (
    "verdict",
    "rho_min_rel",
    "rho_max_rel",
    "wave_speed",
    "wavelength",
    "t_saturation",
    "amplitude_growth",
    "time_end",
    "growth_rate_linear",
    "phase_velocity_linear",
    "kinematic_wave_speed",
    "mass_drift",
    "x_tail",
    "y_tail",
    "nx",
    "ny",
    "status",
    "steps",
    "wall_time",
)


@dataclass(frozen=True)
class WaveMapSettings:
    """One run per flow: the grid, the time and the stop (all runs alike).

    Attributes
    ----------
    length : float
        Period L.
    time : float
        Longest simulated time (the run stops earlier once saturated).
    dt : float
        Time step.
    modes, n : int
        Highest Fourier mode M and Chebyshev intervals N.
    amplitude, seed : float, int
        The initial noise.
    saturation_tol : float
        :class:`~chuteflow.trackers.SaturationStop`'s tolerance.
    resolution_tol : float
        Tolerance of the resolution tails.
    dt_tol : float
        The time-step control (:attr:`~chuteflow.dns.stepper.NewtonSettings.dt_tol`,
        docs/dns.md *Time-step control*): 0 keeps Δt = ``dt``; e.g. 1e-3 lengthens the step
        up to 64 ``dt`` where the wave changes slowly (P1 from noise: ~10× fewer steps in
        the linear phase, 2–4× in the nonlinear one).
    preconditioner : str
        Newton–Krylov preconditioner of the runs
        (:attr:`~chuteflow.dns.stepper.NewtonSettings.preconditioner`, docs/dns.md).
    newton_rtol : float, optional
        Newton's tolerance relative to the step
        (:attr:`~chuteflow.dns.stepper.NewtonSettings.newton_rtol`); None: its default, 1e-3.
    max_modes : int, optional
        Let each run's x grid follow its wave, doubling up to this many modes
        (:meth:`~chuteflow.dns.DnsSimulation.refine`); default: ``modes`` throughout.
    max_n : int, optional
        The same in y: the Chebyshev intervals grow by half, up to this many; default ``n``.
    x_map : bool
        Let each run's x grid follow its front with a tan map
        (:class:`~chuteflow.dns.DnsSimulation`, docs/dns.md *In the runs*). Not in the
        settings' repr (a run is read back where its ``x_map`` attribute agrees), so that the
        runs of a map made before it existed are read back.
    follow_wave : bool
        Let each run's frame follow its wave's measured speed (default True, as for every
        run from noise: :class:`~chuteflow.dns.DnsSimulation`, docs/dns.md *A frame that
        follows the wave*); like ``x_map`` not in the repr (read back where the run's
        ``follow_wave`` attribute agrees; runs from before it existed, without the
        attribute, did not follow).
    """

    length: float = 1000.0
    time: float = 30000.0
    dt: float = 4.0
    modes: int = 32
    n: int = 80
    amplitude: float = 1e-3
    seed: int = 0
    saturation_tol: float = 0.02
    resolution_tol: float = 1e-4
    dt_tol: float = 0.0
    preconditioner: str = "auto"
    newton_rtol: float | None = None
    max_modes: int | None = None
    max_n: int | None = None
    x_map: bool = field(default=False, repr=False)
    follow_wave: bool = field(default=True, repr=False)

    def __post_init__(self):
        for name in ("length", "time", "dt"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ParameterError(f"{name} = {v!r} must be a positive number")
        if not 0 < self.saturation_tol < 1:
            raise ParameterError(f"saturation_tol = {self.saturation_tol!r} must be in (0, 1)")
        # (the same rule as the simulation's: None keeps the grid)
        ceiling(self.max_modes, self.modes, MAX_MODES, "max_modes", "modes", "x modes")
        ceiling(self.max_n, self.n, MAX_N, "max_ny", "ny", "Chebyshev intervals")
        self.newton()  # checks dt_tol, the preconditioner and newton_rtol

    def newton(self) -> NewtonSettings | None:
        """The runs' Newton settings (:func:`~chuteflow.dns.stepper.step_settings`; None:
        the solver's defaults)."""
        return step_settings(self.dt_tol, self.preconditioner, self.newton_rtol)


def _name(theta: float, nu0: float, length: float, s: WaveMapSettings) -> str:
    """The file of one flow's run (its period named where it is not the settings')."""
    return f"theta{theta:g}_nu0{nu0:g}" + ("" if length == s.length else f"_L{length:g}")


def _one(
    theta: float,
    nu0: float,
    length: float,
    model_dict: dict,
    s: WaveMapSettings,
    out_dir: str | None,
    wall_limit: float | None = None,
) -> dict:
    """Run (or read back) the wave at one flow and period; returns its scalars and shape."""
    from ..steady import solve_steady
    from .api import simulate, summary

    model = ChuteModel(**model_dict)
    out = None if out_dir is None else Path(out_dir) / f"{_name(theta, nu0, length, s)}.nc"
    ck = None if out is None else Path(str(out) + ".checkpoint.npz")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        flow = solve_steady(theta, nu0, model, strict=True)
        if out is not None and out.exists() and not (ck is not None and ck.exists()):
            ds: xr.Dataset | None = xr.load_dataset(out, engine="h5netcdf")
            assert ds is not None
            done = (
                ds.attrs.get("map_settings") == repr(s)
                and int(ds.attrs.get("x_map", 0)) == int(s.x_map)
                and int(ds.attrs.get("follow_wave", 0)) == int(s.follow_wave)
                and float(ds.attrs["length"]) == length
                and not str(ds.attrs["status"]).startswith(("stopped", "paused"))
            )
            if not done:
                ds = None
        else:
            ds = None
        if ds is None:
            if out is not None:
                out.parent.mkdir(parents=True, exist_ok=True)  # the checkpoint goes there too
            ds = simulate(
                flow,
                length,
                time=s.time,
                dt=s.dt,
                modes=s.modes,
                n=s.n,
                init="noise",
                amplitude=s.amplitude,
                seed=s.seed,
                snapshots=11,
                record_every=max(1, int(round(s.time / s.dt / 2000))),
                saturation_tol=s.saturation_tol,
                resolution_tol=s.resolution_tol,
                settings=s.newton(),
                wall_limit=wall_limit,
                checkpoint=ck,
                max_modes=s.max_modes,
                max_n=s.max_n,
                x_map=s.x_map,
                follow_wave=s.follow_wave,
            )
            ds.attrs["map_settings"] = repr(s)
            if out is not None:
                ds.to_netcdf(out, engine="h5netcdf")
    sm = summary(ds)
    rho = ds["rho_bar"].values[-1]
    shape = rho / rho.mean() - 1.0
    shape = np.roll(shape, len(shape) // 2 - int(np.argmax(shape)))  # crest at L/2
    row = {k: sm.get(k) for k in WAVE_KEYS}
    row["growth_rate_linear"] = sm["alpha_re"]
    row["phase_velocity_linear"] = sm["mode_phase_velocity"]
    return {
        "theta": theta,
        "nu0": nu0,
        "length": length,
        **row,
        "shape": shape,
        "phase": ds["x"].values / length,
    }


def _point(p, default_length: float) -> tuple[float, float, float]:
    """(θ, ν0, L) of one entry of ``points``."""
    try:
        vals = [float(v) for v in p]
    except (TypeError, ValueError):
        raise ParameterError(f"points: {p!r} is not (theta, nu0) or (theta, nu0, length)") from None
    if len(vals) not in (2, 3):
        raise ParameterError(f"points: {p!r} is not (theta, nu0) or (theta, nu0, length)")
    length = vals[2] if len(vals) == 3 else default_length
    if not (math.isfinite(length) and length > 0):
        raise ParameterError(f"points: length = {length!r} at {p!r} must be a positive number (the period L)")
    return vals[0], vals[1], length


def map_waves(
    points: Sequence[Sequence[float]],
    settings: WaveMapSettings | None = None,
    *,
    model: ChuteModel | None = None,
    out_dir: str | os.PathLike | None = None,
    workers: int = 1,
    progress: Callable[[int, int, dict], None] | None = None,
    client=None,
    scheduler: str | None = None,
    wall_limit: float | None = None,
) -> xr.Dataset:
    """The saturated waves at the flows ``points`` = [(θ, ν0(0)), …] (see the module notes).

    Parameters
    ----------
    points : sequence of (float, float) or (float, float, float)
        Inclination (degrees) and floor density of each steady flow, and optionally its
        period L (default ``settings.length``): flows unstable at different lengths each get
        theirs (e.g. the paper's P4 is stable at L = 1000, its k_c ≈ 1e-3).
    settings : WaveMapSettings
        The runs' grid, time and stop.
    model : ChuteModel, optional
        Closures (the paper's defaults).
    out_dir : path, optional
        One NetCDF file per flow (and its checkpoint while it runs): a map run again continues.
    workers : int
        Processes running flows at once (1: in this process).
    progress : callable, optional
        ``progress(done, total, row)`` after each flow.
    client : dask.distributed.Client, optional
        Run the flows on this Dask cluster instead of local processes (one task per flow;
        ``workers`` is then ignored). With ``out_dir`` the workers write and read the runs'
        files there, so it must be a directory they all see.
    scheduler : str, optional
        Address of a Dask scheduler (``tcp://host:8786``): a client is opened for the map and
        closed after. Needs the ``chuteflow[dask]`` extra.
    wall_limit : float, optional
        Seconds of wall time per flow and call (:class:`~chuteflow.trackers.WallTimeStop`): a
        run still going then pauses (status ``"paused at t = …"``, judged on the wave so far,
        e.g. ``growing``); with ``out_dir`` the same call continues the paused runs.

    Returns
    -------
    xarray.Dataset
        Dimension ``point`` (and ``phase`` for the shapes): ``theta``, ``nu0``, ``length``
        and the scalars of :data:`WAVE_KEYS` per flow, ``shape(point, phase)`` = ρ̄/⟨ρ̄⟩ − 1
        at the end against ξ/L (crest at 1/2); the settings and the model as attributes.
    """
    s = settings or WaveMapSettings()
    model = model or ChuteModel()
    pts = [_point(p, s.length) for p in points]
    if not pts:
        raise ParameterError("points: give at least one (theta, nu0)")
    if int(workers) != workers or workers < 1:
        raise ParameterError(f"workers = {workers!r} must be a positive integer")
    if wall_limit is not None:
        WallTimeStop(wall_limit)  # checks it here, not in every worker
    md = model.to_dict()
    od = None if out_dir is None else str(out_dir)
    rows: dict[int, dict] = {}
    if client is not None or scheduler is not None:
        from ..sweep.engine import dask_client

        run = uuid.uuid4().hex[:8]
        with dask_client(client, scheduler) as c:
            from dask.distributed import as_completed as dask_completed  # there: dask_client checked

            futures = {
                c.submit(
                    _one, th, nu, L, md, s, od, wall_limit, pure=False, key=f"chuteflow-wave-{run}-{i}"
                ): i
                for i, (th, nu, L) in enumerate(pts)
            }
            try:
                for fut in dask_completed(list(futures)):
                    rows[futures[fut]] = fut.result()
                    if progress is not None:
                        progress(len(rows), len(pts), rows[futures[fut]])
            except BaseException:
                c.cancel(list(futures))
                raise
    elif workers == 1 or len(pts) == 1:
        for i, (th, nu, L) in enumerate(pts):
            rows[i] = _one(th, nu, L, md, s, od, wall_limit)
            if progress is not None:
                progress(len(rows), len(pts), rows[i])
    else:
        with ProcessPoolExecutor(max_workers=int(workers)) as ex:
            futs = {ex.submit(_one, th, nu, L, md, s, od, wall_limit): i for i, (th, nu, L) in enumerate(pts)}
            for f in as_completed(futs):
                rows[futs[f]] = f.result()
                if progress is not None:
                    progress(len(rows), len(pts), rows[futs[f]])
    ordered = [rows[i] for i in range(len(pts))]
    data: dict[str, tuple] = {
        k: (
            ("point",),
            np.array([r[k] for r in ordered], dtype=object if k in ("verdict", "status") else float),
        )
        for k in WAVE_KEYS
    }
    for k in ("verdict", "status"):
        data[k] = (("point",), np.array([str(r[k]) for r in ordered]))
    # runs whose grids refined differently: the shapes on the finest grid among them
    n_phase = max(len(r["shape"]) for r in ordered)
    shapes = np.array(
        [r["shape"] if len(r["shape"]) == n_phase else fourier_resample(r["shape"], n_phase) for r in ordered]
    )
    data["shape"] = (("point", "phase"), shapes, {"long_name": "ρ̄/⟨ρ̄⟩ − 1"})
    return xr.Dataset(
        data,
        coords={
            "theta": ("point", [p[0] for p in pts], {"units": "degree"}),
            "nu0": ("point", [p[1] for p in pts]),
            "length": ("point", [p[2] for p in pts], {"long_name": "period L", "units": "sigma"}),
            "phase": (
                "phase",
                np.arange(n_phase) / n_phase,
                {"long_name": "ξ/L, crest at 1/2", "units": "1"},
            ),
        },
        attrs={
            "title": "saturated density waves of the full equations (chuteflow.dns.map_waves)",
            # (a setting left at None, e.g. max_modes: the grid kept, is not an attribute:
            # NetCDF has no None)
            # (and a bool as 0/1: NetCDF has no bool)
            **{
                f"setting_{k}": int(v) if isinstance(v, bool) else v
                for k, v in s.__dict__.items()
                if v is not None
            },
            **{f"model_{k}": v for k, v in model.attrs().items()},
        },
    )
