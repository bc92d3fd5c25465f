"""The ``chuteflow steady`` command: its options declared once, and its plain calls answered
without typer (a fresh process answers in a fraction of a second).

typer (with the pydantic it uses to convert every option) and rich cost about 0.3 s to
import, more than solving the steady flow. The command's options are declared once, in
:data:`STEADY_OPTIONS` (and the model options, one per :class:`ChuteModel` field): the typer
command of :mod:`chuteflow.cli.steady` is generated from that declaration, and
:func:`fast_main` reads plain calls (``--flag value``, ``--flag=value``, the boolean flags)
with the same declaration; anything else (``--help``, an unknown option, a value that is not
a number or not a registered closure name) returns ``None`` and goes to the typer
application, which gives the usual help and usage errors. Both paths run
:func:`steady_command`, so their output is the same.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from chuteflow.closures import CLOSURES, PARAMETERS, ChuteModel
from chuteflow.errors import ChuteflowError

from ._keys import COMMON_KEYS

__all__ = ["JSON_KEYS", "REQUIRED", "STEADY_OPTIONS", "Option", "fast_main", "steady_command"]

#: Default of a required option.
REQUIRED: Any = ...


@dataclass(frozen=True)
class Option:
    """One option of ``chuteflow steady``: the parameter ``name`` of :func:`steady_command`,
    its ``flag`` (a boolean's ``"--on/--off"`` pair, or one flag that sets True), type,
    default (:data:`REQUIRED` if none) and help."""

    name: str
    flag: str
    kind: type
    default: Any
    help: str

    def flags(self) -> dict[str, Any]:
        """Each flag and the value it gives a boolean (None: the flag takes a value)."""
        if self.kind is not bool:
            return {self.flag: None}
        on, _, off = self.flag.partition("/")
        return {on: True, **({off: False} if off else {})}


#: The options of ``chuteflow steady`` besides the model's, in the order of its ``--help``.
STEADY_OPTIONS: tuple[Option, ...] = (
    Option("theta", "--theta", float, REQUIRED, "Inclination θ in degrees."),
    Option("nu0", "--nu0", float, REQUIRED, "Floor packing fraction ν0(0)."),
    Option("nu_top", "--nu-top", float, 1e-9, "Density where the domain ends (paper: 1e-9)."),
    Option("as_json", "--json", bool, False, "Print one JSON object."),
    Option(
        "strict",
        "--strict/--no-strict",
        bool,
        False,
        "Fail (exit 2) where the flow misses the tolerance 1e-8 between two resolutions, "
        "or print it, flagged converged = false, with a warning (default).",
    ),
)

#: Keys of the JSON output, in order (the summary of :class:`~chuteflow.steady.SteadyFlow`).
JSON_KEYS = (
    *COMMON_KEYS[:-1],  # the flow's parameters and the model's fields (nu_top comes later)
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
        print(f"warning: {flow.note}", file=sys.stderr, flush=True)
    summary = flow.to_dict()
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
    """Options of a plain ``chuteflow steady`` call by :data:`STEADY_OPTIONS` and the model
    options, or None (let typer handle it)."""
    values: dict[str, Any] = {"--" + p.replace("_", "-"): ("model", p, float) for p in PARAMETERS}
    values.update({"--" + c.replace("_", "-"): ("model", c, str) for c in CLOSURES})
    switches: dict[str, tuple[str, bool]] = {}
    for opt in STEADY_OPTIONS:
        for flag, value in opt.flags().items():
            if value is None:
                values[flag] = ("command", opt.name, opt.kind)
            else:
                switches[flag] = (opt.name, value)
    out: dict = {o.name: o.default for o in STEADY_OPTIONS}
    out["model"] = {}
    i = 0
    while i < len(args):
        a = args[i]
        if a in switches:
            name, on = switches[a]
            out[name] = on
            i += 1
            continue
        key, eq, value = a.partition("=")
        if key not in values:
            return None
        if not eq:
            if i + 1 >= len(args):
                return None
            value = args[i + 1]
            i += 1
        i += 1
        where, name, kind = values[key]
        if kind is str:
            if value not in CLOSURES[name].names():
                return None
            out["model"][name] = value
            continue
        try:
            x = kind(value)
        except ValueError:
            return None
        if where == "model":
            out["model"][name] = x
        else:
            out[name] = x
    if any(out[o.name] is REQUIRED for o in STEADY_OPTIONS):
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
        model = ChuteModel(**opts.pop("model"))
        steady_command(model=model, **opts)
    except (ChuteflowError, ValueError) as exc:
        if os.environ.get("CHUTEFLOW_DEBUG"):
            raise
        message = " ".join(str(exc).split()) or type(exc).__name__
        print(f"error: {message}", file=sys.stderr)
        return 2
    return 0
