"""The typer application shared by the command modules, its error handling, and the model
options: one option per :class:`~chuteflow.closures.ChuteModel` field, generated from the
fields (defaults, help, and the registered closure names as choices), and ``--preset`` (a
closure set of :data:`~chuteflow.closures.PRESETS`), added to a command by
:func:`with_model_options`. Generating them imports :mod:`chuteflow.closures` (and so sympy,
~0.3 s) at start-up; nothing is derived or compiled until a command runs."""

from __future__ import annotations

import dataclasses
import enum
import functools
import inspect
import os
from collections.abc import Callable, Collection, Iterator
from contextlib import contextmanager
from typing import Any

import typer
from typer.core import TyperGroup

from chuteflow.closures import CLOSURES, PARAMETERS, PRESETS, ChuteModel
from chuteflow.errors import ChuteflowError, ParameterError

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


#: Help of ``--preset`` (the rule for explicit closure options is documented in docs/cli.md).
PRESET_HELP = (
    "Closure set of another code (ChuteModel.preset): one of "
    + ", ".join(sorted(PRESETS))
    + ". It sets --transport, --radial and --wall; any of these given explicitly overrides the preset's."
)


def model_from_options(
    preset: str | None = None, explicit: Collection[str] | None = None, **values: Any
) -> ChuteModel:
    """The ChuteModel of parsed model options (``roughness=…, radial=…``; enum choices are
    taken by value). Raises ParameterError (a one-line CLI error) for bad values.

    ``preset``: a name of :data:`~chuteflow.closures.PRESETS` (``--preset``). The preset
    sets its fields (the closures); an option named in ``explicit`` (given on the command
    line) overrides the preset's value, the others take the preset's. ``explicit=None``
    counts as explicit the values that differ from ChuteModel()'s defaults. An unknown
    preset is a one-line ParameterError listing the known ones.
    """
    vals = {k: (v.value if isinstance(v, enum.Enum) else v) for k, v in values.items()}
    if preset is None:
        return ChuteModel(**vals)
    if preset not in PRESETS:
        raise ParameterError(f"--preset: unknown preset {preset!r}; choose one of {sorted(PRESETS)}")
    if explicit is None:
        default = ChuteModel().to_dict()
        explicit = {k for k, v in vals.items() if v != default.get(k)}
    fixed = PRESETS[preset]["model"]
    return ChuteModel.preset(preset, **{k: v for k, v in vals.items() if k in explicit or k not in fixed})


#: Default of the ``model`` parameter of a command decorated with :func:`with_model_options`
#: (the decorator puts the model options in its place; the command receives a ChuteModel).
MODEL_OPTIONS_HERE: Any = None


#: Name of the typer.Context parameter :func:`with_model_options` adds to a command (to tell
#: options given on the command line from defaults).
_CONTEXT = "model_options_context__"


def with_model_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator of a command function with a parameter ``model``: the command gets one option
    per ChuteModel field instead (``--roughness --wall-loss --restitution --nu-max --radial
    --wall --transport``) and ``--preset``, in place of ``model``, and is called with the
    ChuteModel built from them by :func:`model_from_options` (explicit closure options
    override the preset's). Put it below ``@app.command(...)``.
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
    extra = [
        inspect.Parameter(
            "preset", kind, default=typer.Option(None, "--preset", help=PRESET_HELP), annotation=str | None
        ),
        inspect.Parameter(_CONTEXT, kind, annotation=typer.Context),
    ]
    clash = set(names) & {p.name for p in options + extra}
    if clash:
        raise TypeError(f"{command.__name__}: parameters {sorted(clash)} clash with the model options")
    # the context parameter has no default: it goes first (typer fills it in)
    new = [extra[1]] + params[:i] + options + [extra[0]] + params[i + 1 :]

    @functools.wraps(command)
    def wrapper(**kwargs: Any) -> Any:
        ctx = kwargs.pop(_CONTEXT)
        preset = kwargs.pop("preset")
        values = {p.name: kwargs.pop(p.name) for p in options}
        explicit = {n for n in values if _explicit(ctx, n)}
        return command(**kwargs, model=model_from_options(preset, explicit, **values))

    wrapper.__signature__ = sig.replace(parameters=new)  # type: ignore[attr-defined]
    wrapper.__annotations__ = {p.name: p.annotation for p in new}
    return wrapper


def _explicit(ctx: Any, name: str) -> bool:
    """Whether the option ``name`` was given (command line or environment), not defaulted."""
    source = ctx.get_parameter_source(name) if ctx is not None else None
    return source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")


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
