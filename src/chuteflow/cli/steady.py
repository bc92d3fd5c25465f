"""``chuteflow steady``: one steady flow (paper §3) as a table or one JSON object.

The command's options are declared once, in :data:`chuteflow.cli._fast.STEADY_OPTIONS`; the
typer command below is generated from that declaration (and the model options), and so is
the plain-call parser of :mod:`chuteflow.cli._fast`.
"""

from __future__ import annotations

import inspect
from typing import Any

import typer

from ._app import MODEL_OPTIONS_HERE, app, with_model_options
from ._fast import JSON_KEYS, STEADY_OPTIONS, steady_command

__all__ = ["JSON_KEYS", "steady"]


def _declared(command):
    """Give ``command(**kwargs)`` the signature of :data:`STEADY_OPTIONS` plus ``model``."""
    kind = inspect.Parameter.POSITIONAL_OR_KEYWORD
    params = [
        inspect.Parameter(
            o.name,
            kind,
            default=typer.Option(o.default, o.flag, help=o.help),
            annotation=o.kind,
        )
        for o in STEADY_OPTIONS
    ]
    params.insert(2, inspect.Parameter("model", kind, default=MODEL_OPTIONS_HERE, annotation=Any))
    command.__signature__ = inspect.Signature(params)
    command.__annotations__ = {p.name: p.annotation for p in params}
    return command


@app.command("steady")
@with_model_options
@_declared
def steady(**options: Any) -> None:
    """Solve for the steady flow at (θ, ν0(0)) and print its quantities."""
    steady_command(**options)
