"""``chuteflow steady``: one steady flow (paper §3) as a table or one JSON object."""

from __future__ import annotations

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, with_model_options

#: Keys of the JSON output, in order (the summary of :class:`~chuteflow.steady.SteadyFlow`).
JSON_KEYS = (
    "theta",
    "nu0",
    "roughness",
    "wall_loss",
    "restitution",
    "nu_max",
    "radial",
    "wall",
    "transport",
    "u_floor",
    "T_floor",
    "h",
    "nu_mean",
    "rho_bar",
    "Q",
    "T_mean",
    "monotonic",
    "y_peak",
    "nu_peak",
    "y_max",
    "nu_top",
    "n",
    "convergence",
    "residual",
    "iterations",
    "spectral_tail",
)

_ROWS = (
    ("u_floor", "slip velocity u0(0)", ".8g"),
    ("T_floor", "floor temperature T0(0)", ".8g"),
    ("h", "thickness h (σ)", ".8g"),
    ("nu_mean", "mean density ν̄", ".8g"),
    ("rho_bar", "one-dimensional density ρ̄0 (σ)", ".8g"),
    ("Q", "flux Q0", ".8g"),
    ("T_mean", "mean temperature T̄0", ".8g"),
    ("monotonic", "ν0 monotonic", ""),
    ("y_peak", "height of the density maximum (σ)", ".6g"),
    ("nu_peak", "maximum density", ".6g"),
    ("y_max", "top of the domain y_max (σ)", ".8g"),
    ("n", "Chebyshev intervals", "d"),
    ("convergence", "relative change n → 3n/2", ".1e"),
    ("residual", "final scaled residual", ".1e"),
)


@app.command("steady")
@with_model_options
def steady(
    theta: float = typer.Option(..., "--theta", help="Inclination θ in degrees."),
    nu0: float = typer.Option(..., "--nu0", help="Floor packing fraction ν0(0)."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help="Density where the domain ends (paper: 1e-9)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Solve for the steady flow at (θ, ν0(0)) and print its quantities."""
    import json
    import warnings

    from chuteflow.steady import solve_steady

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        flow = solve_steady(theta, nu0, model, nu_top=nu_top)
    summary = flow.summary()
    if as_json:
        typer.echo(json.dumps({k: summary[k] for k in JSON_KEYS}))
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(
        title=f"Steady flow at θ = {theta:g}°, ν0(0) = {nu0:g}",
        caption=f"{model.describe()}, ν0(y_max) = {nu_top:g}",
    )
    table.add_column("quantity")
    table.add_column("value", justify="right")
    for key, label, fmt in _ROWS:
        v = summary[key]
        table.add_row(label, ("yes" if v else "no") if fmt == "" else format(v, fmt))
    Console().print(table)
