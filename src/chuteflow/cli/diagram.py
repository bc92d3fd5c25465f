"""``chuteflow diagram`` (run or resume a stability sweep) and ``chuteflow plot`` (redraw it)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, with_model_options


def _default_out(roughness: float) -> Path:
    return Path(f"diagram_phi{roughness:g}.nc")


@app.command("diagram")
@with_model_options
def diagram(
    model: ChuteModel = MODEL_OPTIONS_HERE,
    grid: str = typer.Option("60x60", "--grid", help="Grid size N_THETAxN_NU0."),
    theta_range: tuple[float, float] | None = typer.Option(
        None,
        "--theta-range",
        metavar="LOW HIGH",
        help="Inclination range in degrees (default: where the paper's flows exist).",
    ),
    nu0_range: tuple[float, float] | None = typer.Option(
        None, "--nu0-range", metavar="LOW HIGH", help="Floor density ν0(0) range."
    ),
    metrics: str | None = typer.Option(
        None, "--metrics", help="Comma-separated point functions (default: steady,kinematic,longwave,growth)."
    ),
    out: Path | None = typer.Option(None, "--out", "-o", help="NetCDF file (default diagram_phi<φ>.nc)."),
    png: Path | None = typer.Option(
        None, "--png", help="Diagram image (default: the output file with .png)."
    ),
    scheduler: str | None = typer.Option(
        None,
        "--scheduler",
        metavar="ADDRESS",
        help="Run on this Dask scheduler (needs the dask extra of chuteflow).",
    ),
    workers: int | None = typer.Option(
        None, "--workers", "-j", help="Local worker processes (default: all cores)."
    ),
    chunk: int | None = typer.Option(
        None, "--chunk", help="Points per task along ν0 (continuation; default: whole θ rows)."
    ),
    with_markers: bool = typer.Option(
        True, "--markers/--no-markers", help="Also compute the paper's points P1–P5 / Q1–Q3."
    ),
    fresh: bool = typer.Option(
        False,
        "--fresh",
        help="Discard saved results of a different configuration at --out instead of refusing.",
    ),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar."),
) -> None:
    """Compute the stability diagram over a (θ, ν0(0)) grid; resumes automatically."""
    from rich.console import Console

    from chuteflow.papers.mitarai2004 import markers as paper_markers
    from chuteflow.sweep import Sweep, SweepConfig, parse_grid, parts_dir

    shape = parse_grid(grid)
    kw: dict[str, Any] = {
        "shape": shape,
        "theta_range": theta_range,
        "nu0_range": nu0_range,
        "model": model,
        "chunk": chunk,
    }
    kw["markers"] = paper_markers(model.roughness) if with_markers else ()
    if metrics:
        kw["metrics"] = tuple(m.strip() for m in metrics.split(",") if m.strip())
    cfg = SweepConfig.grid(**kw)
    out = out or _default_out(model.roughness)
    sweep = Sweep(cfg, out, fresh=fresh)
    console = Console(stderr=True)
    try:
        ds = sweep.run(workers=workers, scheduler=scheduler, progress=progress)
    except KeyboardInterrupt:
        typer.echo(
            f"interrupted: finished tasks are saved in {parts_dir(out)}; run the "
            "same command again to continue",
            err=True,
        )
        raise typer.Exit(130) from None
    st = sweep.stats
    png = png or out.with_suffix(".png")
    from chuteflow.figures.diagram import save_diagram

    save_diagram(ds, png)
    _summary(console, ds, st, out, png)


def _summary(console, ds, st, out, png):
    from rich.table import Table

    from chuteflow.sweep import STATUS
    from chuteflow.sweep.regimes import regime_summary

    t = Table(title=f"stability diagram φ = {ds.attrs.get('roughness'):g}", show_header=True)
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for name, code in STATUS.items():
        t.add_row(f"points {name}", str(int((ds["status"].values == code).sum())))
    for name, s in regime_summary(ds).items():
        if s.get("points"):
            t.add_row(
                f"regime {name}",
                f"{s['points']} points, median h {s['h_median']:.3g}, ν̄ {s['nu_mean_median']:.3g}",
            )
        else:
            t.add_row(f"regime {name}", "none")
    if "finite_k_disagrees" in ds:
        t.add_row(
            "dispersion samples disagreeing",
            f"{int((ds['finite_k_disagrees'].values == 1).sum())} of "
            f"{int((ds['finite_k_disagrees'].values >= 0).sum())}",
        )
    if "marker" in ds.dims and "marker_unstable" in ds:
        t.add_row(
            "marked points",
            ", ".join(
                f"{n}: {'unstable' if u == 1 else 'stable' if u == 0 else 'n/a'}"
                for n, u in zip(ds["marker"].values, ds["marker_unstable"].values)
            ),
        )
    t.add_row("tasks computed / reused", f"{st.computed} / {st.reused}")
    t.add_row("wall time", f"{st.seconds:.1f} s ({st.backend}, {st.workers} workers)")
    t.add_row("results", f"{out}, {png}")
    console.print(t)


@app.command("plot")
def plot(
    file: Path = typer.Argument(..., help="NetCDF file written by chuteflow diagram."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Image file (default: FILE with .png)."),
    h_max: float | None = typer.Option(None, "--h-max", help="Largest h shown."),
    nu_max: float | None = typer.Option(None, "--nu-max", help="Largest ν̄ shown."),
    grid_panel: bool = typer.Option(
        True, "--grid-panel/--no-grid-panel", help="Add the (θ, ν0) classification panel."
    ),
) -> None:
    """Redraw a stability diagram from a saved sweep file."""
    from chuteflow.figures.diagram import save_diagram
    from chuteflow.sweep import load_sweep

    ds = _load_for_plot(file, load_sweep)
    path = save_diagram(
        ds, out or file.with_suffix(".png"), h_max=h_max, nu_max=nu_max, grid_panel=grid_panel
    )
    typer.echo(str(path))


def _load_for_plot(file: Path, load_sweep):
    """``load_sweep(file)``, with a one-line :class:`ParameterError` naming the file if it
    is not a NetCDF-4 file that can be read (instead of the HDF5 library's traceback)."""
    from chuteflow.errors import ParameterError

    if file.is_dir():
        raise ParameterError(f"file: {file} is a directory, not a NetCDF file written by chuteflow diagram")
    try:
        return load_sweep(file)
    except ParameterError:
        raise
    except (OSError, ValueError) as exc:
        why = " ".join(str(exc).split()) or type(exc).__name__
        why = why.removeprefix("Unable to synchronously open file ").strip("() ")
        if isinstance(exc, PermissionError):
            raise ParameterError(f"file: {file} cannot be read ({why})") from None
        raise ParameterError(
            f"file: {file} is not a NetCDF-4 file written by chuteflow diagram ({why})"
        ) from None
