"""Run the registered reproduction stages and write the report.

:func:`run_reproduce` is what ``chuteflow reproduce`` calls. Each stage runs inside
its own report section; a stage that raises is recorded as a failed checkpoint
(``<stage>.completed``, with the traceback as detail) and the run goes on. The report
is rewritten after every stage, so an interrupted run still leaves one.
"""

from __future__ import annotations

import contextlib
import os
import time
import traceback
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)
from rich.table import Table

from .papers import DEFAULT_PAPERS, PAPERS
from .registry import Stage, StageContext, load_stages, select_stages
from .report import Checkpoint, Report, Section

__all__ = ["run_reproduce", "StageProgress", "summary_table"]

T = TypeVar("T")


class StageProgress:
    """``ctx.progress`` of a stage: a callable over a rich progress task.

    ``progress("message")`` sets the task's description; ``advance``, ``total`` and
    ``completed`` update its counts, as in :meth:`rich.progress.Progress.update`.
    :meth:`track` iterates and advances. Without a live display the calls are no-ops
    apart from remembering the last message.
    """

    def __init__(
        self, progress: Progress | None = None, task: TaskID | None = None, prefix: str = ""
    ) -> None:
        self._progress, self._task, self._prefix = progress, task, prefix
        self.message: str = ""

    def __call__(
        self,
        message: str | None = None,
        *,
        advance: float | None = None,
        total: float | None = None,
        completed: float | None = None,
    ) -> None:
        if message is not None:
            self.message = str(message)
        if self._progress is None or self._task is None:
            return
        kw: dict[str, Any] = {}
        if message is not None:
            kw["description"] = f"{self._prefix}{message}"
        if total is not None:
            kw["total"] = total
        if completed is not None:
            kw["completed"] = completed
        if advance is not None:
            kw["advance"] = advance
        self._progress.update(self._task, **kw)

    def track(
        self, iterable: Iterable[T], description: str | None = None, total: float | None = None
    ) -> Iterator[T]:
        """Yield from ``iterable``, advancing the task by one per item."""
        if total is None and hasattr(iterable, "__len__"):
            total = len(iterable)  # type: ignore[arg-type]
        self(description, total=total, completed=0)
        for item in iterable:
            yield item
            self(advance=1)


def summary_table(report: Report) -> Table:
    """Rich table of all checkpoints, coloured by result."""
    counts = report.counts()
    table = Table(
        title="chuteflow reproduce: checkpoints",
        caption=f"{counts['pass']} passed, {counts['fail']} failed, {counts['not checked']} not checked",
        show_lines=False,
    )
    for col in ("Stage", "Checkpoint", "Source", "Computed", "Result"):
        table.add_column(col, overflow="fold")
    style = {"pass": "green", "fail": "bold red", "not checked": "dim"}
    for stage, cp in report.iter_checkpoints():
        computed = cp.computed if len(cp.computed) <= 160 else cp.computed[:157] + "..."
        table.add_row(stage, cp.id, cp.source, computed, f"[{style[cp.status]}]{cp.status}[/]")
    return table


def _model_defaults() -> dict[str, Any]:
    try:
        from chuteflow.closures import ChuteModel

        return ChuteModel().as_dict()
    except Exception as exc:  # the header is informative only
        return {"error": f"{type(exc).__name__}: {exc}"}


def _run_stage(stage: Stage, ctx: StageContext) -> Section:
    """Run one stage into its section of ``ctx.report``: status, wall time, and a failed
    checkpoint ``NAME.completed`` with the traceback if it raised (the run goes on)."""
    report = ctx.report
    t0 = time.perf_counter()
    with report.stage(stage.name, stage.title) as section:
        section.status = "running"
        try:
            stage.func(ctx)
        except Exception as exc:  # recorded, run continues
            section.status = "failed"
            report.add_checkpoint(_failed(stage.name, f"{type(exc).__name__}: {exc}", traceback.format_exc()))
        else:
            section.status = "ok"
        section.wall_time = time.perf_counter() - t0
    return section


def _failed(name: str, computed: str, detail: str) -> Checkpoint:
    return Checkpoint(
        id=f"{name}.completed",
        source=f"chuteflow stage '{name}'",
        statement="The stage runs to completion.",
        computed=computed,
        passed=False,
        detail=detail,
    )


def _run_detached_stages(names: list[str], out: Path, quick: bool) -> list[Section]:
    """In the second process: the independent stages in order, each into a report of its
    own; their sections go back to the parent. At the lowest priority (nice 19): they take
    the cores that the other stages leave idle (their serial parts) and do not slow down
    the parallel ones."""
    from chuteflow._memory import keep_freed_memory
    from chuteflow._threads import limit_blas_threads

    from .registry import get_stage

    limit_blas_threads(1)
    keep_freed_memory()
    if hasattr(os, "nice"):
        with contextlib.suppress(OSError):  # not permitted here: same priority, still beside the others
            os.nice(19)
    report = Report()
    sections = []
    for name in names:
        stage = get_stage(name)
        ctx = StageContext(out=out, quick=quick, report=report, stage=name, shared={})
        sections.append(_run_stage(stage, ctx))
    return sections


class _Detached:
    """The independent stages in one forked process (nothing when ``stages`` is empty).
    ``result()`` waits for their sections; a process that dies (killed, out of memory)
    gives each stage a failed ``NAME.completed`` checkpoint instead."""

    def __init__(self, stages: list[Stage], out: Path, quick: bool) -> None:
        self.stages, self.out, self.quick = stages, out, quick
        self.pool: Any = None
        self.future: Any = None

    def __enter__(self) -> _Detached:
        if self.stages:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
            self.pool = ProcessPoolExecutor(max_workers=1, mp_context=ctx)
            self.future = self.pool.submit(
                _run_detached_stages, [s.name for s in self.stages], self.out, self.quick
            )
        return self

    def result(self) -> list[Section]:
        try:
            return list(self.future.result())
        except Exception as exc:
            out = []
            for stage in self.stages:
                sec = Section(stage.name, stage.title, status="failed", wall_time=0.0)
                sec.checkpoints.append(
                    _failed(stage.name, f"the second process ended: {type(exc).__name__}: {exc}", "")
                )
                out.append(sec)
            return out

    def __exit__(self, *exc: object) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=exc[0] is None, cancel_futures=True)


def run_reproduce(
    out: str | Path = "reproduce-out",
    quick: bool = True,
    stages: Sequence[str] | None = None,
    *,
    console: Console | None = None,
    show_progress: bool | None = None,
    parameters: dict[str, Any] | None = None,
    papers: Sequence[str] | None = None,
    concurrent: bool = True,
) -> Report:
    """Run the reproduction stages and write ``report.md`` / ``report.html`` in ``out``.

    Parameters
    ----------
    out : path
        Output folder (created).
    quick : bool
        Quick mode (default) or the paper's full resolution.
    stages : sequence of str, optional
        Names of the stages to run (in registry order); ``None`` runs all, ``[]`` none.
        An unknown name raises :class:`~chuteflow.errors.ParameterError` before
        anything runs.
    console : rich.console.Console, optional
        Where the stage lines and the summary table go (default: standard output).
    show_progress : bool, optional
        Live progress bars; default when ``console`` is a terminal.
    parameters : dict, optional
        Extra header parameters.
    papers : sequence of str, optional
        Paper packages (:mod:`chuteflow.papers`) whose stages run; default
        ``chuteflow.papers.DEFAULT_PAPERS``.
    concurrent : bool
        Run the stages registered ``independent`` in a second process beside the others
        when the machine has two or more cores (default); False: all in order, in this
        process.

    Returns
    -------
    Report
        The written report; ``report.ok`` is False if any checkpoint failed and
        ``report.paths`` holds the written files.
    """
    from chuteflow._threads import limit_blas_threads

    t_start = time.perf_counter()
    console = console or Console()
    papers = tuple(DEFAULT_PAPERS if papers is None else papers)
    import_errors = load_stages(papers)
    selected = select_stages(stages, papers)  # validates names before anything runs
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("MPLBACKEND", "Agg")
    limit_blas_threads(1)

    params: dict[str, Any] = {
        "mode": "quick" if quick else "full",
        "stages": [s.name for s in selected] if stages is not None else "all",
        "papers": list(papers),
        "model defaults": _model_defaults(),
        "BLAS threads": 1,
    }
    params.update(parameters or {})
    report = Report(
        title="chuteflow: reproduction of " + "; ".join(PAPERS.get(p, p) for p in papers), parameters=params
    )
    for module, exc in import_errors.items():
        paper, _, name = module.partition(".")
        report.add_checkpoint(
            Checkpoint(
                id=f"import.{name}",
                source=f"chuteflow.papers.{paper}.stages.{name}",
                statement="The stage module imports.",
                computed=f"{type(exc).__name__}: {exc}",
                passed=False,
                detail="".join(traceback.format_exception(exc)),
            ),
            stage="import",
        )
    report.write(out, wall_time=time.perf_counter() - t_start)

    live = console.is_terminal if show_progress is None else show_progress
    shared: dict[str, Any] = {}
    n = len(selected)
    progress = Progress(
        SpinnerColumn(),
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
        disable=not live,
    )
    # independent stages run in a second process beside the others (two or more cores)
    detached = [s for s in selected if s.independent] if concurrent else []
    if len(detached) == len(selected) or (os.cpu_count() or 1) < 2:
        detached = []
    for stage in selected:  # the report keeps the stages' order, whichever finishes first
        report.section(stage.name, stage.title)

    def announce(i: int, section: Section, suffix: str = "") -> None:
        n_fail = sum(cp.passed is False for cp in section.checkpoints)
        colour = "red" if section.status == "failed" or n_fail else "green"
        console.print(
            f"[{i}/{n}] {section.name}: [{colour}]{section.status}[/]"
            f"{f', {n_fail} failed checkpoint(s)' if n_fail else ''}"
            f" ({section.wall_time:.1f} s{suffix})",
            highlight=False,
        )

    with progress, _Detached(detached, out, quick) as side:
        overall = progress.add_task("stages", total=n)
        if detached:
            side_task = progress.add_task(
                f"in a second process: {', '.join(s.name for s in detached)}", total=None
            )
        for i, stage in enumerate(selected, 1):
            if stage in detached:
                continue
            task = progress.add_task(f"{stage.name}", total=None)
            ctx = StageContext(
                out=out,
                quick=quick,
                report=report,
                stage=stage.name,
                progress=StageProgress(progress, task, f"{stage.name}: "),
                shared=shared,
            )
            section = _run_stage(stage, ctx)
            progress.remove_task(task)
            progress.advance(overall)
            announce(i, section)
            report.write(out, wall_time=time.perf_counter() - t_start)
        if detached:
            for stage, section in zip(detached, side.result(), strict=True):
                report.adopt(section)
                progress.advance(overall)
                announce(selected.index(stage) + 1, section, ", in a second process")
            progress.remove_task(side_task)

    report.write(out, wall_time=time.perf_counter() - t_start)
    if report.checkpoints:
        console.print(summary_table(report))
    counts = report.counts()
    console.print(
        f"{len(selected)} stage(s) run in {report.wall_time:.1f} s; "
        f"{counts['pass']} passed, {counts['fail']} failed, "
        f"{counts['not checked']} not checked checkpoints",
        highlight=False,
    )
    console.print(f"report: {report.paths['md']}  {report.paths['html']}", highlight=False, soft_wrap=True)
    return report
