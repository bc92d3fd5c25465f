"""The ``chuteflow steady`` command without typer: a fresh process answers in a fraction of
a second.

typer (with the pydantic it uses to convert every option) and rich cost about 0.3 s to
import, more than solving the steady flow. :func:`fast_main` parses the plain forms of
``chuteflow steady`` (``--theta``, ``--nu0``, ``--nu-top``, ``--json`` and the model options
``--roughness`` … ``--transport``) itself and runs the command; anything else (``--help``, an
unknown option, a value that is not a number or not a registered closure name) returns
``None`` and goes to the typer application, which gives the usual help and usage errors.
Both paths run :func:`steady_command`, so their output is the same.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Sequence

from chuteflow.closures import CLOSURES, PARAMETERS, ChuteModel
from chuteflow.errors import ChuteflowError

__all__ = ["JSON_KEYS", "fast_main", "steady_command"]

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
    "converged",
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


def steady_command(
    theta: float, nu0: float, model: ChuteModel, nu_top: float, as_json: bool, strict: bool = False
) -> None:
    """Solve the steady flow at (θ, ν0(0)) and print it (one JSON object, or a table); a
    flow that misses the tolerance is printed flagged with a warning line, or with
    ``strict`` raises (:func:`~chuteflow.steady.solve_steady`)."""
    from chuteflow.steady import solve_steady

    flow = solve_steady(theta, nu0, model, nu_top=nu_top, strict=strict)
    if not flow.converged:
        print(f"warning: {flow.precision_warning()}", file=sys.stderr, flush=True)
    summary = flow.summary()
    if as_json:
        print(json.dumps({k: summary[k] for k in JSON_KEYS}), flush=True)
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


def _parse_steady(args: Sequence[str]) -> dict | None:
    """Options of a plain ``chuteflow steady`` call, or None (let typer handle it)."""
    floats = {"--theta": "theta", "--nu0": "nu0", "--nu-top": "nu_top"}
    floats.update({"--" + p.replace("_", "-"): p for p in PARAMETERS})
    names = {"--" + c.replace("_", "-"): c for c in CLOSURES}
    out: dict = {"nu_top": 1e-9, "as_json": False, "strict": False, "model": {}}
    i = 0
    while i < len(args):
        a = args[i]
        key, eq, value = a.partition("=")
        if a == "--json":
            out["as_json"] = True
            i += 1
            continue
        if a in ("--strict", "--no-strict"):
            out["strict"] = a == "--strict"
            i += 1
            continue
        if key not in floats and key not in names:
            return None
        if not eq:
            if i + 1 >= len(args):
                return None
            value = args[i + 1]
            i += 1
        i += 1
        if key in names:
            if value not in CLOSURES[names[key]].names():
                return None
            out["model"][names[key]] = value
            continue
        try:
            x = float(value)
        except ValueError:
            return None
        if floats[key] in PARAMETERS:
            out["model"][floats[key]] = x
        else:
            out[floats[key]] = x
    if "theta" not in out or "nu0" not in out:
        return None
    return out


def fast_main(argv: Sequence[str]) -> int | None:
    """Run ``chuteflow steady`` without typer if ``argv`` is a plain call of it; return the
    exit code, or None when the typer application has to handle ``argv``."""
    if not argv or argv[0] != "steady":
        return None
    opts = _parse_steady(argv[1:])
    if opts is None:
        return None
    try:
        steady_command(
            opts["theta"],
            opts["nu0"],
            ChuteModel(**opts["model"]),
            opts["nu_top"],
            opts["as_json"],
            strict=opts["strict"],
        )
    except (ChuteflowError, ValueError) as exc:
        if os.environ.get("CHUTEFLOW_DEBUG"):
            raise
        message = " ".join(str(exc).split()) or type(exc).__name__
        print(f"error: {message}", file=sys.stderr)
        return 2
    return 0
