"""The typer application shared by the command modules, its error handling, and the model
options: one option per :class:`~chuteflow.closures.ChuteModel` field, generated from the
fields (defaults, help, and the registered closure names as choices), added to a command by
:func:`with_model_options`. Generating them imports :mod:`chuteflow.closures` (and so sympy,
~0.3 s) at start-up; nothing is derived or compiled until a command runs."""

from __future__ import annotations

import dataclasses
import enum
import functools
import inspect
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import typer
from typer.core import TyperGroup

from chuteflow.closures import CLOSURES, PARAMETERS, ChuteModel
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

    # TyperGroup hands its own typer.Context here; the base class declares the (vendored)
    # click Context it subclasses, so this narrower annotation is an override mypy flags
    def invoke(self, ctx: typer.Context) -> Any:  # type: ignore[override]
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
    version: bool = typer.Option(
        False, "--version", callback=_version_callback, is_eager=True, help="Show the version and exit."
    ),
) -> None:
    """chuteflow: steady chute flows, linear stability, stability diagrams."""


def _closure_choices(name: str) -> type[enum.Enum]:
    """A str Enum of the names registered for the closure field ``name`` (typer's choices)."""
    names = CLOSURES[name].names()
    return enum.Enum(name.title() + "Choice", {n: n for n in names}, type=str)  # type: ignore[return-value]


_FIELDS = {f.name: f for f in dataclasses.fields(ChuteModel)}

#: CLI defaults and help of the numeric model parameters, taken from ChuteModel's fields
#: (tests/cli/test_cli.py checks them against ChuteModel()).
MODEL_OPTIONS: dict[str, tuple[float, str]] = {
    name: (float(_FIELDS[name].default), _FIELDS[name].metadata["help"])  # type: ignore[arg-type]
    for name in PARAMETERS
}
#: CLI defaults (registered names), help and choices of the closure fields of ChuteModel.
CLOSURE_OPTIONS: dict[str, tuple[str, str, type[enum.Enum]]] = {
    name: (str(reg.spec(_FIELDS[name].default)), _FIELDS[name].metadata["help"], _closure_choices(name))
    for name, reg in CLOSURES.items()
}


def model_option(name: str):
    """The typer option ``--<name>`` of the ChuteModel field ``name``, with default and help
    (closure fields: the registered names as choices)."""
    flag = "--" + name.replace("_", "-")
    if name in CLOSURE_OPTIONS:
        choice, text, _ = CLOSURE_OPTIONS[name]
        return typer.Option(choice, flag, help=text)
    value, text = MODEL_OPTIONS[name]
    return typer.Option(value, flag, help=text)


def model_from_options(**values: Any) -> ChuteModel:
    """The ChuteModel of parsed model options (``roughness=…, radial=…``; enum choices are
    taken by value). Raises ParameterError (a one-line CLI error) for bad values."""
    return ChuteModel(**{k: (v.value if isinstance(v, enum.Enum) else v) for k, v in values.items()})


#: Default of the ``model`` parameter of a command decorated with :func:`with_model_options`
#: (the decorator puts the model options in its place; the command receives a ChuteModel).
MODEL_OPTIONS_HERE: Any = None


def with_model_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator of a command function with a parameter ``model``: the command gets one option
    per ChuteModel field instead (``--roughness --wall-loss --restitution --nu-max --radial
    --wall --transport``, in place of ``model``), and is called with the ChuteModel built
    from them by :func:`model_from_options`. Put it below ``@app.command(...)``.
    """
    sig = inspect.signature(command, eval_str=True)
    params = list(sig.parameters.values())
    names = [p.name for p in params]
    if "model" not in names:
        raise TypeError(f"{command.__name__}: with_model_options needs a parameter 'model'")
    i = names.index("model")
    kind = inspect.Parameter.POSITIONAL_OR_KEYWORD
    options = [
        inspect.Parameter(
            name,
            kind,
            default=model_option(name),
            annotation=(CLOSURE_OPTIONS[name][2] if name in CLOSURE_OPTIONS else float),
        )
        for name in ChuteModel.__dataclass_fields__
    ]
    clash = set(names) & {p.name for p in options}
    if clash:
        raise TypeError(f"{command.__name__}: parameters {sorted(clash)} clash with the model options")
    new = params[:i] + options + params[i + 1 :]

    @functools.wraps(command)
    def wrapper(**kwargs: Any) -> Any:
        values = {p.name: kwargs.pop(p.name) for p in options}
        return command(**kwargs, model=model_from_options(**values))

    wrapper.__signature__ = sig.replace(parameters=new)  # type: ignore[attr-defined]
    wrapper.__annotations__ = {p.name: p.annotation for p in new}
    return wrapper


@contextmanager
def time_progress(label: str, console: Any, *, disable: bool, digits: int = 4) -> Iterator[Callable]:
    """A transient progress bar over simulated time; yields ``progress(t, t_end)`` to update it."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(
        TextColumn(label),
        BarColumn(),
        TextColumn("t = {task.fields[t]}"),
        TimeElapsedColumn(),
        console=console,
        transient=True,
        disable=disable,
    ) as prog:
        task = prog.add_task("run", total=1.0, t="0")

        def progress(t: float, t_end: float) -> None:
            prog.update(task, completed=t / t_end, t=f"{t:.{digits}g} / {t_end:.{digits}g}")

        yield progress
