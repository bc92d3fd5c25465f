"""``chuteflow reduced`` (the 1D model of §5.1.2) and ``chuteflow simulate`` (its density waves)."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, time_progress, with_model_options

#: Per-point keys of ``chuteflow reduced --json`` (``points``: the family's knots, exact).
POINT_KEYS = (
    "nu0",
    "rho0",
    "F",
    "Tbar",
    "a",
    "U",
    "dU",
    "dP",
    "mu_bar",
    "q0",
    "dq0",
    "criterion_margin",
    "unstable",
    "short_wave_unstable",
    "alpha2",
    "phase_velocity",
    "k_c",
    "L_c",
)


def _num(v):
    """JSON-safe float: inf and nan as strings (JSON has neither)."""
    v = float(v)
    return v if math.isfinite(v) else str(v)


def _point(c, nu0=None):
    d = c.to_dict()
    d["nu0"] = c.F if nu0 is None else nu0
    out = {}
    for k in POINT_KEYS:
        v = d[k]
        out[k] = v if isinstance(v, bool) else _num(v)
    return out


@app.command("reduced")
@with_model_options
def reduced(
    theta: float = typer.Option(..., "--theta", help="Inclination θ in degrees."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu0: float | None = typer.Option(
        None, "--nu0", help="Also give the linear theory at this floor density."
    ),
    tol: float = typer.Option(1e-4, "--tol", help="Interpolation tolerance of F, T̄, a."),
    nu0_min: float = typer.Option(5e-3, "--nu0-min", help="Lowest floor density of the family."),
    nu0_max: float | None = typer.Option(None, "--nu0-max", help="Highest floor density (default 0.75 ν_m)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    plot: Path | None = typer.Option(None, "--plot", help="Save a figure of the functions."),
) -> None:
    """The 1D model at θ: F, T̄, a, U along the steady family, the criterion
    (ρ̄U')² > (ρ̄T̄)' and the long-wave coefficients (§5.1.2)."""
    import json

    from chuteflow.reduced import reduced_model
    from chuteflow.reduced.model import SEEDS

    # the family is started at the user's density first: it has a flow wherever one exists
    seeds = SEEDS if nu0 is None else (nu0, *SEEDS)
    rm = reduced_model(theta, model, tol=tol, nu0_min=nu0_min, nu0_max=nu0_max, seeds=seeds)
    state = None
    if nu0 is not None:
        state = rm.coefficients(rm.rho_at_nu0(nu0))
    points = [_point(c) for c in rm.coefficients_at_knots]
    if plot is not None:
        from chuteflow.figures.reduced import plot_functions, save

        save(plot_functions(rm), plot)
    if as_json:
        out = {
            "theta": rm.theta,
            **model.to_dict(),
            "rho_range": list(rm.rho_range),
            "nu0_range": [float(rm.nu0[0]), float(rm.nu0[-1])],
            "accuracy": {k: float(v) for k, v in rm.accuracy.items()},
            "ends": list(rm.ends),
            "points": points,
        }
        if state is not None:
            out["state"] = _point(state, nu0)
            kmax, smax = state.most_unstable()
            out["state"].update(k_max=_num(kmax), growth_max=_num(smax))
        typer.echo(json.dumps(out))
        return
    from rich.console import Console
    from rich.table import Table

    con = Console()
    table = Table(
        title=f"1D model (§5.1.2) at θ = {theta:g}°, {model.describe()}",
        caption=f"{len(points)} steady flows (knots), ρ̄ ∈ [{rm.rho_range[0]:.4g}, "
        f"{rm.rho_range[1]:.4g}]; interpolation error ≤ "
        f"{max(rm.accuracy[k] for k in ('F', 'Tbar', 'a')):.1e} (F, T̄, a), "
        f"{max(rm.accuracy[k] for k in ('dF', 'dTbar', 'da')):.1e} "
        "(slopes). Unstable: (ρ̄U')² > (ρ̄T̄)'; 'all k': (ρ̄T̄)' < 0.",
    )
    for col in ("ν0(0)", "ρ̄", "T̄", "a", "U", "U'", "(ρ̄T̄)'", "criterion", "α2", "−dq0/dρ̄", "L_c", "stability"):
        table.add_column(col, justify="right")
    for p in points:
        lc = p["L_c"]
        lc = lc if isinstance(lc, str) else f"{lc:.4g}"
        stab = "all k" if p["short_wave_unstable"] else ("unstable" if p["unstable"] else "stable")
        table.add_row(
            f"{p['nu0']:.4g}",
            f"{p['rho0']:.4g}",
            f"{p['Tbar']:.4g}",
            f"{p['a']:.4g}",
            f"{p['U']:.4g}",
            f"{p['dU']:.4g}",
            f"{p['dP']:.4g}",
            f"{p['criterion_margin']:+.3g}",
            f"{p['alpha2']:.3g}",
            f"{p['phase_velocity']:.4g}",
            lc,
            stab,
        )
    con.print(table)
    con.print(f"family ends: low — {rm.ends[0]}; high — {rm.ends[1]}", highlight=False)
    if state is not None:
        kmax, smax = state.most_unstable()
        con.print(
            f"at ν0(0) = {nu0:g}: ρ0 = {state.rho0:.6g}, U = {state.U:.6g}, α(k) = "
            f"−i {state.dq0:.6g} k + {state.alpha2:.6g} k² + O(k³) (eq. 5.14); criterion "
            f"{state.criterion_margin:+.4g} → {'unstable' if state.unstable else 'stable'}; "
            f"k_c = {state.k_c:.4g}, L_c = 2π/k_c = {state.L_c:.4g}; fastest growth "
            f"{smax:.4g} at k = {kmax:.4g}",
            highlight=False,
        )
    if plot is not None:
        con.print(f"figure: {plot}", highlight=False)


@app.command("simulate")
@with_model_options
def simulate(
    theta: float = typer.Option(..., "--theta", help="Inclination θ in degrees."),
    nu0: float = typer.Option(..., "--nu0", help="Floor density ν0(0) of the uniform state."),
    length: float = typer.Option(..., "--length", help="Periodic domain length L (σ)."),
    time: float | None = typer.Option(
        None, "--time", help="Final time (default: until saturation, decay or leaving the steady family)."
    ),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    cells: int | None = typer.Option(None, "--cells", help="Grid cells (default: automatic)."),
    mode: int | None = typer.Option(
        None, "--mode", help="Start from this discrete eigenmode instead of noise."
    ),
    amplitude: float = typer.Option(1e-3, "--amplitude", help="Initial δρ̄/ρ0."),
    seed: int = typer.Option(0, "--seed", help="Seed of the initial noise."),
    rtol: float = typer.Option(1e-6, "--rtol", help="Time integrator tolerance."),
    snapshots: int = typer.Option(200, "--snapshots", help="Stored snapshots."),
    frame_speed: float | None = typer.Option(
        None,
        "--frame-speed",
        help="Speed of the frame ξ = x − ct of the run (default: the fastest-growing mode's phase velocity).",
    ),
    nu0_min: float = typer.Option(5e-3, "--nu0-min", help="Lowest floor density of the steady family."),
    nu0_max: float | None = typer.Option(None, "--nu0-max", help="Highest floor density (default 0.75 ν_m)."),
    out: Path | None = typer.Option(None, "--out", help="Write the run to this NetCDF file."),
    plot: Path | None = typer.Option(None, "--plot", help="Save the space–time figure."),
    as_json: bool = typer.Option(False, "--json", help="Print a JSON summary."),
) -> None:
    """Nonlinear density waves of the 1D model on a periodic slope (§5.2)."""
    import json

    from rich.console import Console

    from chuteflow.errors import ParameterError
    from chuteflow.reduced import reduced_model
    from chuteflow.reduced import simulate as run
    from chuteflow.reduced.model import SEEDS
    from chuteflow.trackers import wave_measures

    if not (math.isfinite(length) and length > 0):  # before the family is built
        raise ParameterError(f"length = {length!r} must be a positive number of diameters")
    con = Console(stderr=True)
    with con.status("building the 1D model from the steady family…"):
        rm = reduced_model(theta, model, tol=1e-4, nu0_min=nu0_min, nu0_max=nu0_max, seeds=(nu0, *SEEDS))
    coef = rm.coefficients(rm.rho_at_nu0(nu0))
    if coef.short_wave_unstable:
        con.print(
            "warning: (ρ0 T̄)' < 0 here: the 1D model is unstable at every "
            "wavelength, down to the grid; the waves depend on the grid",
            style="yellow",
            highlight=False,
        )
    with time_progress("simulating", con, disable=as_json and not con.is_terminal, digits=4) as progress:
        ds = run(
            rm,
            length,
            nu0=nu0,
            n_cells=cells,
            time=time,
            mode=mode,
            amplitude=amplitude,
            seed=seed,
            rtol=rtol,
            snapshots=snapshots,
            progress=progress,
            on_exit="stop",
            frame_speed="wave" if frame_speed is None else frame_speed,
        )
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(out, engine="h5netcdf")
    if plot is not None:
        from chuteflow.figures.reduced import plot_spacetime, save

        save(plot_spacetime(ds), plot)
    a = ds.attrs
    summary = {
        k: (_num(a[k]) if isinstance(a[k], float) else (a[k].item() if hasattr(a[k], "item") else a[k]))
        for k in (
            "theta",
            "roughness",
            "rho0",
            "nu0",
            "length",
            "n_cells",
            "t_end",
            "status",
            "mass_drift",
            "max_growth_rate",
            "k_c",
            "L_c",
            "steps",
            "wall_time_s",
        )
    }
    summary["amplitude_end"] = float(ds["amplitude"].values[-1])
    # the keys of ``chuteflow dns`` for the same things: the time reached, the wall time and
    # the wave at the end (chuteflow.trackers.wave_measures, the same measure for both models)
    summary["time_end"] = summary["t_end"]
    summary["wall_time"] = summary["wall_time_s"]
    summary["frame_speed"] = _num(a["frame_speed"])
    waves = wave_measures(
        ds["t"].values, ds["rho"].values, float(a["length"]), float(a["frame_speed"]), status=str(a["status"])
    )
    summary.update({k: (v if isinstance(v, str) else _num(v)) for k, v in waves.items()})
    summary.update({k: v for k, v in model.to_dict().items() if k not in summary})
    if a.get("left_family"):
        summary["left_family"] = a["left_family"]
    if as_json:
        typer.echo(json.dumps(summary))
    else:
        for k, v in summary.items():
            typer.echo(f"{k:16s} {v}")
    if a["status"] == "left_family":
        con.print(
            f"warning: {a['left_family']}; the run stops there (the data up to that time is kept)",
            style="yellow",
            highlight=False,
        )
    if out is not None:
        con.print(f"wrote {out}", highlight=False)
