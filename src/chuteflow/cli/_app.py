"""The typer application shared by the command modules, and its error handling."""
from __future__ import annotations

import os
from typing import Any

import typer
from typer.core import TyperGroup

from chuteflow.errors import ChuteflowError

#: Exit code of a user error (bad parameter, no steady flow, no convergence).
EXIT_USER_ERROR = 2
#: Errors shown as one ``error: ...`` line instead of a traceback.
USER_ERRORS: tuple[type[BaseException], ...] = (ChuteflowError, ValueError)


def report_user_error(exc: BaseException) -> None:
    """Print ``error: <message>`` (one line) to standard error."""
    message = " ".join(str(exc).split()) or type(exc).__name__
    typer.echo(f"error: {message}", err=True)


class ChuteflowGroup(TyperGroup):
    """Command group turning :data:`USER_ERRORS` into a one-line message and exit 2.

    Set ``CHUTEFLOW_DEBUG=1`` to get the traceback instead.
    """

    def invoke(self, ctx: typer.Context) -> Any:
        try:
            return super().invoke(ctx)
        except USER_ERRORS as exc:
            if os.environ.get("CHUTEFLOW_DEBUG"):
                raise
            report_user_error(exc)
            raise typer.Exit(EXIT_USER_ERROR) from None


def _version_callback(value: bool) -> None:
    if value:
        from chuteflow import __version__

        typer.echo(f"chuteflow {__version__}")
        raise typer.Exit()


app = typer.Typer(
    name="chuteflow",
    cls=ChuteflowGroup,
    help="Hydrodynamic stability of rapid granular chute flows (Mitarai & Nakanishi).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version_callback,
                                 is_eager=True, help="Show the version and exit."),
) -> None:
    """chuteflow: steady chute flows, linear stability, stability diagrams."""


#: CLI defaults and help of the model parameters (the same as ChuteModel's defaults, which
#: tests/cli/test_cli.py checks; kept here so ``chuteflow --help`` need not import sympy).
MODEL_OPTIONS: dict[str, tuple[float, str]] = {
    "roughness": (0.05, "Floor roughness φ (eq:bc1, etastar)."),
    "wall_loss": (0.39, "Floor energy loss Φ (eq:bc2, gammastar)."),
    "restitution": (0.7, "Particle restitution coefficient e_p."),
    "nu_max": (0.6, "Maximum packing ν_m of g0(ν)."),
}


def model_option(name: str):
    """The typer option ``--<name>`` of a model parameter, with its default and help."""
    default, text = MODEL_OPTIONS[name]
    return typer.Option(default, "--" + name.replace("_", "-"), help=text)
