"""``chuteflow steady``: one steady flow (paper §3) as a table or one JSON object."""

from __future__ import annotations

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, with_model_options
from ._fast import JSON_KEYS, steady_command

__all__ = ["JSON_KEYS", "steady"]


@app.command("steady")
@with_model_options
def steady(
    theta: float = typer.Option(..., "--theta", help="Inclination θ in degrees."),
    nu0: float = typer.Option(..., "--nu0", help="Floor packing fraction ν0(0)."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help="Density where the domain ends (paper: 1e-9)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    strict: bool = typer.Option(
        False,
        "--strict/--no-strict",
        help="Fail (exit 2) where the flow misses the tolerance 1e-8 between two resolutions, "
        "or print it, flagged converged = false, with a warning (default).",
    ),
) -> None:
    """Solve for the steady flow at (θ, ν0(0)) and print its quantities."""
    steady_command(theta, nu0, model, nu_top, as_json, strict=strict)
