"""``chuteflow dns``: nonlinear time-dependent simulation of the chute flow."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, time_progress, with_model_options


def _num(v):
    """JSON-safe value: non-finite floats as strings."""
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    return v


@app.command("dns")
@with_model_options
def dns(
    theta: float = typer.Option(..., "--theta", help="Inclination θ in degrees."),
    nu0: float = typer.Option(..., "--nu0", help="Floor density ν0(0) of the steady flow."),
    length: float = typer.Option(..., "--length", help="Period L along the slope (diameters)."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    time: float | None = typer.Option(None, "--time", help="Simulated time (default: two wave periods)."),
    nx: int | None = typer.Option(
        None,
        "--nx",
        help="Fourier unknowns per node, nx = 2M + 1 (default 5 from a mode, 2·max(8, L/30)+1 from noise).",
    ),
    max_nx: int | None = typer.Option(
        None,
        "--max-nx",
        help="Let the x grid follow the wave: double nx, up to this, where the highest x modes "
        "rise towards --resolution-tol (default: keep --nx).",
    ),
    x_map: bool = typer.Option(
        False,
        "--x-map/--no-x-map",
        help="Let the x grid follow the front: where the highest x modes rise, a tan map "
        "centred at the steepest point of ln ν (at the same nx where that suffices, else "
        "nx doubled up to --max-nx), re-centred as the front moves (docs/dns.md).",
    ),
    follow_wave: bool | None = typer.Option(
        None,
        "--follow-wave/--no-follow-wave",
        help="Let the frame follow the nonlinear wave's measured speed (the wave stands in it; "
        "the records stay in the first frame; docs/dns.md). Default: on from noise, off from a mode.",
    ),
    ny: int | None = typer.Option(None, "--ny", help="Chebyshev intervals N (default: the eigenvalue's N)."),
    max_ny: int | None = typer.Option(
        None,
        "--max-ny",
        help="Let the y grid follow the wave: grow N by half, up to this, where the highest "
        "Chebyshev coefficients rise towards --resolution-tol (default: keep --ny).",
    ),
    dt: float | None = typer.Option(None, "--dt", help="Time step (default: wave period / 100)."),
    init: str = typer.Option("mode", "--init", help="mode (least-stable eigenmode at k = 2π/L) or noise."),
    amplitude: float = typer.Option(
        1e-6, "--amplitude", help="Largest component of the initial perturbation."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the initial noise."),
    frame_speed: float | None = typer.Option(
        None,
        "--frame-speed",
        help="Speed of the frame ξ = x − ct of the run (default 0 from a mode, the wave speed from noise).",
    ),
    top: str = typer.Option(
        "transport",
        "--top",
        help="Row of ln ν at the top: transport (eq. (2.1), atmosphere gradient at inflow) or isothermal.",
    ),
    snapshots: int = typer.Option(6, "--snapshots", help="Full-field snapshots stored (equally spaced)."),
    record_every: int = typer.Option(
        1, "--record-every", help="Store ρ̄(x, t), Q(x, t) every this many steps."
    ),
    saturation_tol: float | None = typer.Option(
        None,
        "--saturation-tol",
        help="Stop once the wave's amplitude has settled to this relative change (--time: the longest run).",
    ),
    dt_tol: float = typer.Option(
        0.0,
        "--dt-tol",
        help="Time-step control (docs/dns.md): 0 keeps --dt; e.g. 1e-3 lengthens the step "
        "where the wave changes slowly.",
    ),
    preconditioner: str = typer.Option(
        "auto",
        "--preconditioner",
        help="Newton–Krylov preconditioner (docs/dns.md): auto, mean, columns or coupled "
        "(neighbouring Fourier modes coupled: fewer GMRES iterations at large amplitude).",
    ),
    newton_rtol: float | None = typer.Option(
        None,
        "--newton-rtol",
        help="Newton stops at this fraction of its extrapolated guess's residual (docs/dns.md, "
        "Newton's tolerance relative to the step); default 1e-3, 0: every step to 1e-10.",
    ),
    wall_limit: float | None = typer.Option(
        None,
        "--wall-limit",
        help="Pause after this many seconds of wall time (status 'paused'; with --out the same "
        "command continues).",
    ),
    resolution_tol: float = typer.Option(
        1e-4,
        "--resolution-tol",
        help="Warn when the highest x or y modes carry more than this of the largest.",
    ),
    out: Path | None = typer.Option(
        None,
        "--out",
        help="NetCDF output; a killed run resumes from OUT.checkpoint.npz with the same command.",
    ),
    plot: Path | None = typer.Option(None, "--plot", help="Save the space–time figure and a snapshot."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Time-dependent simulation of eqs (2.1)–(2.3) with the Johnson–Jackson floor on a slope
    periodic in x (docs/dns.md): growth rate and phase velocity of the k = 2π/L wave against
    the linear eigenvalue, mass drift, and the nonlinear waves: their amplitude, speed,
    wavelength, time to saturate and verdict, and the resolution of the highest modes."""
    import json
    import warnings

    from rich.console import Console

    from chuteflow.dns import simulate, summary
    from chuteflow.dns.stepper import step_settings
    from chuteflow.errors import ParameterError
    from chuteflow.steady import solve_steady
    from chuteflow.trackers import ResolutionWarning

    if nx is not None and (nx < 1 or nx % 2 == 0):
        raise ParameterError(f"nx = {nx}: an odd number ≥ 1 (nx = 2M + 1 real Fourier unknowns)")
    if max_nx is not None and (max_nx < 1 or max_nx % 2 == 0 or (nx is not None and max_nx < nx)):
        raise ParameterError(
            f"max_nx = {max_nx}: an odd number ≥ nx (the largest x grid, nx = 2M + 1, the run may refine to)"
        )
    if init not in ("mode", "noise"):
        raise ParameterError(f"init = {init!r}: choose mode or noise")
    con = Console(stderr=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ResolutionWarning)  # reported below, in one line
        with con.status("solving the steady flow…"):
            flow = solve_steady(theta, nu0, model, strict=True)
        with time_progress("dns", con, disable=as_json and not con.is_terminal, digits=5) as progress:
            ds = simulate(
                flow,
                length,
                time=time,
                n=ny,
                modes=None if nx is None else (nx - 1) // 2,
                max_modes=None if max_nx is None else (max_nx - 1) // 2,
                max_n=max_ny,
                x_map=x_map,
                follow_wave=follow_wave,
                dt=dt,
                init=init,
                amplitude=amplitude,
                seed=seed,
                frame_speed=frame_speed,
                top=top,
                snapshots=snapshots,
                record_every=record_every,
                saturation_tol=saturation_tol,
                resolution_tol=resolution_tol,
                out=out,
                progress=progress,
                settings=step_settings(dt_tol, preconditioner, newton_rtol),
                wall_limit=wall_limit,
            )
    if plot is not None:
        from chuteflow.figures.dns import plot_dns, save

        save(plot_dns(ds), plot)
    s = {k: _num(v) for k, v in summary(ds).items()}
    s.update({k: v for k, v in model.to_dict().items() if k not in s})
    if as_json:
        typer.echo(json.dumps(s))
    else:
        for k, v in s.items():
            typer.echo(f"{k:22s} {v}")
    if float(ds.attrs["alpha_re"]) < 0:
        con.print(
            f"warning: length = {length:g} is below the critical length of this flow (Re α = "
            f"{float(ds.attrs['alpha_re']):.3g} < 0 at k = 2π/L): no wave grows",
            style="yellow",
            highlight=False,
        )
    if ds.attrs.get("resolution_warnings"):
        con.print(f"warning: {ds.attrs['resolution_warnings']}", style="yellow", highlight=False)
    if str(ds.attrs["status"]).startswith(("stopped", "paused")):
        kept = f"; the run so far is in {out} and its checkpoint" if out is not None else ""
        con.print(f"warning: {ds.attrs['status']}{kept}", style="yellow", highlight=False)
    growth, alpha_re = float(ds.attrs["amplitude_growth"]), float(ds.attrs["alpha_re"])
    if ds.attrs["verdict"] == "growing" and math.isfinite(growth) and alpha_re > 0:
        con.print(
            f"not saturated at t = {float(ds.attrs['time_end']):g}: the wave's amplitude still grows at "
            f"d ln A/dt = {growth:.3g}, {growth / alpha_re:.2f} of the linear rate Re α = {alpha_re:.3g}",
            style="yellow",
            highlight=False,
        )
    if out is not None:
        con.print(f"wrote {out}", highlight=False)
    if plot is not None:
        con.print(f"figure: {plot}", highlight=False)


def _floats(text: str, name: str) -> list[float]:
    from chuteflow.errors import ParameterError

    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ParameterError(f"{name} = {text!r}: numbers separated by commas") from None


@app.command("waves")
@with_model_options
def waves(
    theta: str | None = typer.Option(None, "--theta", help="Inclinations θ (degrees), comma-separated."),
    nu0: str | None = typer.Option(
        None, "--nu0", help="Floor densities ν0(0), comma-separated (a row per θ)."
    ),
    points: str | None = typer.Option(
        None, "--points", help="The paper's points instead, e.g. P1,P4,P5 (their roughness is used)."
    ),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    length: str = typer.Option(
        "1000",
        "--length",
        help="Period L along the slope (diameters): one for every flow, or one per flow, comma-separated.",
    ),
    time: float = typer.Option(30000.0, "--time", help="Longest simulated time (stops once saturated)."),
    dt: float = typer.Option(4.0, "--dt", help="Time step."),
    nx: int = typer.Option(65, "--nx", help="Fourier unknowns per node, nx = 2M + 1."),
    max_nx: int | None = typer.Option(
        None,
        "--max-nx",
        help="Let each run's x grid follow its wave: double nx, up to this, where the highest x "
        "modes rise towards the resolution tolerance (default: keep --nx).",
    ),
    x_map: bool = typer.Option(
        False,
        "--x-map/--no-x-map",
        help="Let each run's x grid follow its front with a tan map (as chuteflow dns --x-map).",
    ),
    follow_wave: bool = typer.Option(
        True,
        "--follow-wave/--no-follow-wave",
        help="Let each run's frame follow its wave's measured speed (as chuteflow dns --follow-wave).",
    ),
    ny: int = typer.Option(80, "--ny", help="Chebyshev intervals N."),
    max_ny: int | None = typer.Option(
        None,
        "--max-ny",
        help="Let each run's y grid follow its wave: grow N by half, up to this, where the "
        "highest Chebyshev coefficients rise towards the resolution tolerance (default: keep --ny).",
    ),
    amplitude: float = typer.Option(1e-3, "--amplitude", help="Size of the initial noise in ln ν."),
    seed: int = typer.Option(0, "--seed", help="Seed of the initial noise."),
    saturation_tol: float = typer.Option(
        0.02, "--saturation-tol", help="Relative change that counts as settled."
    ),
    dt_tol: float = typer.Option(
        0.0,
        "--dt-tol",
        help="Time-step control (docs/dns.md): 0 keeps --dt; e.g. 1e-3 lengthens the step "
        "where the wave changes slowly.",
    ),
    preconditioner: str = typer.Option(
        "auto",
        "--preconditioner",
        help="Newton–Krylov preconditioner (docs/dns.md): auto, mean, columns or coupled.",
    ),
    newton_rtol: float | None = typer.Option(
        None,
        "--newton-rtol",
        help="Newton stops at this fraction of its extrapolated guess's residual (docs/dns.md, "
        "Newton's tolerance relative to the step); default 1e-3, 0: every step to 1e-10.",
    ),
    wall_limit: float | None = typer.Option(
        None,
        "--wall-limit",
        help="Seconds of wall time per flow: a run still going pauses (verdict on the wave so "
        "far); with --out-dir the same command continues.",
    ),
    workers: int = typer.Option(1, "--workers", help="Flows run at once (processes)."),
    scheduler: str | None = typer.Option(
        None,
        "--scheduler",
        help="Run the flows on this Dask scheduler (tcp://host:8786; needs the dask extra); "
        "--out-dir must then be a directory the workers see.",
    ),
    reduced: bool = typer.Option(
        False,
        "--reduced",
        help="Also run the 1D model (§5.1.2) at each flow, with the same L, noise, --time and "
        "--saturation-tol, and print its wave beside.",
    ),
    out_dir: Path | None = typer.Option(
        None, "--out-dir", help="One NetCDF file per flow (a killed map continues from there)."
    ),
    out: Path | None = typer.Option(None, "--out", help="The map as one NetCDF file."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """The saturated density waves from noise at a list of flows (docs/dns.md): per flow the
    verdict, min/max of ρ̄ relative to its mean, wave speed, wavelength, time to saturate,
    next to the linear growth rate and phase velocity at k = 2π/L."""
    import json

    from rich.console import Console

    from chuteflow.dns import WaveMapSettings, map_waves
    from chuteflow.dns.waves import WAVE_KEYS
    from chuteflow.errors import ParameterError

    if nx < 1 or nx % 2 == 0:
        raise ParameterError(f"nx = {nx}: an odd number ≥ 1 (nx = 2M + 1 real Fourier unknowns)")
    if max_nx is not None and (max_nx % 2 == 0 or max_nx < nx):
        raise ParameterError(
            f"max_nx = {max_nx}: an odd number ≥ nx = {nx} (the largest x grid a run may refine to)"
        )
    if points is not None:
        if theta is not None or nu0 is not None:
            raise ParameterError("points: give either --points or --theta with --nu0, not both")
        from chuteflow.papers.mitarai2004.points import point

        named = [point(p.strip()) for p in points.split(",") if p.strip()]
        rough = {p.roughness for p in named}
        if len(rough) > 1:
            raise ParameterError(f"points = {points!r}: the points have different roughness {sorted(rough)}")
        model = ChuteModel(**{**model.to_dict(), "roughness": rough.pop()})
        pts = [(p.theta, p.nu0) for p in named]
    else:
        if theta is None or nu0 is None:
            raise ParameterError("theta, nu0: give --theta and --nu0 (comma-separated), or --points")
        pts = [(t, n) for t in _floats(theta, "theta") for n in _floats(nu0, "nu0")]
    lengths = _floats(length, "length")
    if not lengths or len(lengths) not in (1, len(pts)):
        raise ParameterError(
            f"length = {length!r}: give one period for every flow or one per flow ({len(pts)} flows)"
        )
    settings = WaveMapSettings(
        length=lengths[0],
        time=time,
        dt=dt,
        modes=(nx - 1) // 2,
        n=ny,
        amplitude=amplitude,
        seed=seed,
        saturation_tol=saturation_tol,
        dt_tol=dt_tol,
        preconditioner=preconditioner,
        newton_rtol=newton_rtol,
        max_modes=None if max_nx is None else (max_nx - 1) // 2,
        max_n=max_ny,
        x_map=x_map,
        follow_wave=follow_wave,
    )
    con = Console(stderr=True)

    def progress(done, total, row):
        con.print(
            f"[{done}/{total}] θ = {row['theta']:g}, ν0 = {row['nu0']:g}: {row['verdict']}, ρ̄ "
            f"{row['rho_min_rel']:+.3f} … {row['rho_max_rel']:+.3f}",
            highlight=False,
        )

    ds = map_waves(
        [(t, n, lengths[i] if len(lengths) > 1 else lengths[0]) for i, (t, n) in enumerate(pts)],
        settings,
        model=model,
        out_dir=out_dir,
        workers=workers,
        progress=progress,
        scheduler=scheduler,
        wall_limit=wall_limit,
    )
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(out, engine="h5netcdf")
    rows = []
    for i in range(ds.sizes["point"]):
        r: dict[str, object] = {
            "theta": float(ds["theta"][i]),
            "nu0": float(ds["nu0"][i]),
            "length": float(ds["length"][i]),
        }
        for k in WAVE_KEYS:
            v = ds[k].values[i]
            r[k] = str(v) if k in ("verdict", "status") else int(v) if k == "nx" else _num(float(v))
        rows.append(r)
    if reduced:
        _reduced_waves(rows, model, settings, con)
    if as_json:
        typer.echo(
            json.dumps(
                {"length": lengths[0] if len(lengths) == 1 else lengths, **model.to_dict(), "points": rows}
            )
        )
        return
    for r in rows:
        typer.echo(
            f"θ = {r['theta']:g}, ν0 = {r['nu0']:g}, L = {r['length']:g}: {r['verdict']}; "
            f"ρ̄ {r['rho_min_rel']} … {r['rho_max_rel']}; "
            f"c = {r['wave_speed']}, λ = {r['wavelength']}, t_sat = {r['t_saturation']}; linear Re α = "
            f"{r['growth_rate_linear']}, c = {r['phase_velocity_linear']}"
        )


#: The 1D model's keys of ``chuteflow waves --reduced`` (prefixed ``reduced_``).
REDUCED_KEYS = (
    "verdict",
    "rho_min_rel",
    "rho_max_rel",
    "wave_speed",
    "wavelength",
    "t_saturation",
    "short_wave_unstable",
)


def _reduced_waves(rows: list, model: ChuteModel, settings, con) -> None:
    """The 1D model's wave from noise at each row's flow (one model per θ), into the rows.

    The same period, noise, longest time and saturation test as the full equations' runs
    (``settings``, a :class:`~chuteflow.dns.WaveMapSettings`): the 1D run stops once its
    amplitude settles, or at ``settings.time`` (then ``growing``, as the full run would say).
    """

    from chuteflow.errors import ChuteflowError
    from chuteflow.reduced import reduced_model
    from chuteflow.reduced import simulate as run
    from chuteflow.reduced.model import SEEDS
    from chuteflow.trackers import SaturationStop, wave_measures

    models: dict = {}
    for r in rows:
        th, nu = float(r["theta"]), float(r["nu0"])
        try:
            if th not in models:
                nus = tuple(float(q["nu0"]) for q in rows if float(q["theta"]) == th)
                models[th] = reduced_model(th, model, tol=1e-4, seeds=(*nus, *SEEDS))
            s = settings
            L = float(r["length"])
            ds = run(
                models[th],
                L,
                nu0=nu,
                amplitude=s.amplitude,
                seed=s.seed,
                time=s.time,
                on_exit="stop",
                trackers=(SaturationStop(s.saturation_tol, count=200),),
            )
            a = ds.attrs
            w = wave_measures(
                ds["t"].values, ds["rho"].values, L, float(a["frame_speed"]), status=str(a["status"])
            )
            # the 1D model unstable at every k (k_c = ∞): its wave is the grid's, not the flow's
            w["short_wave_unstable"] = str(a["short_wave_unstable"]) == "True"  # stored as text
        except ChuteflowError as exc:
            con.print(f"1D model at θ = {th:g}, ν0 = {nu:g}: {exc}", style="yellow", highlight=False)
            w = dict.fromkeys(REDUCED_KEYS, "nan")
            w["verdict"] = "failed"
        for k in REDUCED_KEYS:
            v = w[k]
            r[f"reduced_{k}"] = v if isinstance(v, (str, bool)) else _num(float(v))
