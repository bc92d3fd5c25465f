"""Registry of reproduction stages and the context a stage receives.

A stage is a function ``stage(ctx) -> None`` registered with :func:`register_stage`;
stages run in increasing ``order`` (ties by name). Stages belong to a paper package
(:mod:`chuteflow.papers`): a module ``chuteflow.papers.NAME.stages.*`` registers its
stages when imported, and :func:`load_stages` imports the papers asked for::

    from chuteflow.report import Checkpoint, StageContext, register_stage

    @register_stage("steady", order=10, title="Steady flows (§3)")
    def steady(ctx: StageContext) -> None:
        ctx.progress("shooting for θ = 16°")
        ...
        ctx.report.add_figure(ctx.path("profiles.png"), "Steady profiles", source="figure 3")
        ctx.report.check("steady.h16", source="§3.2", statement="...", computed="...",
                         passed=True)
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from ..errors import ParameterError
from .papers import DEFAULT_PAPERS, import_errors
from .report import Report

__all__ = [
    "Stage",
    "StageContext",
    "ProgressCallback",
    "register_stage",
    "registered_stages",
    "get_stage",
    "select_stages",
    "load_stages",
    "isolated_registry",
]


class ProgressCallback(Protocol):
    """What ``ctx.progress`` accepts: a message and/or rich-style progress counts."""

    def __call__(
        self,
        message: str | None = None,
        *,
        advance: float | None = None,
        total: float | None = None,
        completed: float | None = None,
    ) -> None: ...


def _no_progress(message: str | None = None, **_: Any) -> None:
    """Default progress callback: does nothing."""


@dataclass
class StageContext:
    """What a stage function receives.

    Attributes
    ----------
    out : Path
        Output folder of the whole run (``report.md`` goes here). Created.
    quick : bool
        Quick mode (coarse grids, few parameter points; minutes) or full (the paper's
        resolution; hours).
    report : Report
        The report; ``check``/``add_checkpoint``/``add_figure``/``add_note`` go to this
        stage's section.
    progress : callable
        ``progress(message=None, *, advance=None, total=None, completed=None)``; in
        :func:`~chuteflow.report.reproduce.run_reproduce` a
        :class:`~chuteflow.report.reproduce.StageProgress`, which also has
        ``.track(iterable, description=None, total=None)``.
    stage : str
        Name of the running stage.
    shared : dict
        One dict shared by all stages of a run, for results a later stage reuses
        (e.g. steady solutions). Key by stage name to avoid clashes.
    """

    out: Path
    quick: bool
    report: Report
    progress: ProgressCallback | Callable[..., None] = _no_progress
    stage: str = ""
    shared: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.out = Path(self.out)

    @property
    def stage_dir(self) -> Path:
        """``out / stage`` (created): where this stage's files go."""
        d = self.out / (self.stage or "general")
        d.mkdir(parents=True, exist_ok=True)
        return d

    def path(self, name: str) -> Path:
        """Path of a file ``name`` in :attr:`stage_dir` (parent folders created)."""
        p = self.stage_dir / name
        p.parent.mkdir(parents=True, exist_ok=True)
        return p


StageFunc = Callable[[StageContext], None]


@dataclass(frozen=True)
class Stage:
    """A registered stage: ``func(ctx)`` run at position ``order``."""

    name: str
    order: float
    func: StageFunc
    title: str
    #: The paper package the stage belongs to (``None``: a stage registered elsewhere,
    #: e.g. in a test, which runs with any paper).
    paper: str | None = None
    #: Needs nothing from ``ctx.shared`` and leaves nothing there that another stage
    #: reads: it may run in a second process beside the others (see ``register_stage``).
    independent: bool = False

    def __call__(self, ctx: StageContext) -> None:
        self.func(ctx)


_REGISTRY: dict[str, Stage] = {}
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")


def _paper_of(module: str) -> str | None:
    """``NAME`` for a module ``chuteflow.papers.NAME[...]``, else ``None``."""
    parts = module.split(".")
    if len(parts) >= 3 and parts[:2] == ["chuteflow", "papers"]:
        return parts[2]
    return None


def register_stage(
    name: str,
    order: float,
    *,
    title: str | None = None,
    paper: str | None = None,
    independent: bool = False,
) -> Callable[[StageFunc], StageFunc]:
    """Decorator registering ``func(ctx) -> None`` as stage ``name``.

    Parameters
    ----------
    name : str
        Stage name used on the command line (``chuteflow reproduce --stage NAME``) and
        as its output sub-folder: letters, digits, ``-`` and ``_``.
    order : float
        Stages run in increasing order; a stage that needs another's results in
        ``ctx.shared`` must come after it.
    title : str, optional
        Section heading in the report (default: first line of the docstring, else name).
    paper : str, optional
        The paper package the stage belongs to (default: taken from the module,
        ``chuteflow.papers.NAME...``).
    independent : bool
        The stage reads nothing from ``ctx.shared`` and writes nothing there that another
        stage reads. :func:`~chuteflow.report.reproduce.run_reproduce` then runs it in a
        second process beside the other stages on a machine with two or more cores (its
        section, checkpoints and files are the same; its wall time overlaps theirs).
        Meant for stages that use one core while the others wait on serial work.

    Returns the function unchanged. Registering another function under a taken name
    raises ``ValueError``.
    """
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"stage name {name!r}: use letters, digits, '-' and '_' (starting with a letter)")

    def decorator(func: StageFunc) -> StageFunc:
        doc_lines = (func.__doc__ or "").strip().splitlines()
        heading = title or (doc_lines[0].rstrip(".") if doc_lines else name)
        old = _REGISTRY.get(name)
        if old is not None and (old.func.__module__, old.func.__qualname__) != (
            func.__module__,
            func.__qualname__,
        ):
            raise ValueError(
                f"stage {name!r} is already registered by {old.func.__module__}.{old.func.__qualname__}"
            )
        owner = paper if paper is not None else _paper_of(func.__module__)
        _REGISTRY[name] = Stage(name, float(order), func, heading, owner, bool(independent))
        return func

    return decorator


def load_stages(papers: Sequence[str] | None = None) -> dict[str, BaseException]:
    """Import the stages of the given papers (default: ``chuteflow.papers.DEFAULT_PAPERS``).

    Returns the stage modules that failed to import, as ``"paper.module"`` → exception
    (the other stages are registered all the same). An unknown paper raises
    :class:`~chuteflow.errors.ParameterError`.
    """
    errors: dict[str, BaseException] = {}
    for paper in DEFAULT_PAPERS if papers is None else papers:
        for module, exc in import_errors(paper).items():
            errors[f"{paper}.{module}"] = exc
    return errors


def registered_stages(papers: Sequence[str] | None = None) -> list[Stage]:
    """Registered stages in run order (by ``order``, then name).

    With ``papers``, only the stages of those papers (and stages that belong to none).
    """
    stages = sorted(_REGISTRY.values(), key=lambda s: (s.order, s.name))
    if papers is None:
        return stages
    return [s for s in stages if s.paper is None or s.paper in papers]


def get_stage(name: str) -> Stage:
    """The stage called ``name``; :class:`~chuteflow.errors.ParameterError` if none."""
    try:
        return _REGISTRY[name]
    except KeyError:
        avail = ", ".join(s.name for s in registered_stages()) or "none registered"
        raise ParameterError(f"stage: unknown stage {name!r} (available: {avail})") from None


def select_stages(names: Sequence[str] | None, papers: Sequence[str] | None = None) -> list[Stage]:
    """Stages to run: all (of ``papers``, if given) for ``None``; else the named ones,
    deduplicated, in run order."""
    if names is None:
        return registered_stages(papers)
    chosen = {get_stage(n).name for n in names}
    return [s for s in registered_stages() if s.name in chosen]


@contextmanager
def isolated_registry() -> Iterator[dict[str, Stage]]:
    """Run with an empty registry (for tests); the real one is restored on exit.

    The default papers' stage modules are imported first, so that their registration
    does not land in the temporary registry.
    """
    load_stages()
    saved = dict(_REGISTRY)
    _REGISTRY.clear()
    try:
        yield _REGISTRY
    finally:
        _REGISTRY.clear()
        _REGISTRY.update(saved)
