"""Checkpoints, figures and the :class:`Report` that collects them by stage.

A *checkpoint* pairs one statement of the paper (with its section, equation or figure number)
with what chuteflow computed for it and whether the two agree. A *stage* is one part of
the reproduction (steady flows, dispersion relations, stability diagrams, …); the report
keeps one :class:`Section` per stage and writes ``report.md``, a self-contained
``report.html`` and ``checkpoints.json``. The records themselves are defined in
:mod:`chuteflow.report.content` (and importable from here); the rendering is
:mod:`chuteflow.report.render`.
"""

from __future__ import annotations

import json
import platform
import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from .content import STATUS_FAIL, STATUS_NOT_CHECKED, STATUS_PASS, Checkpoint, Figure, Section
from .render import render_html, render_markdown

__all__ = ["Checkpoint", "Figure", "Section", "Report", "DEFAULT_TITLE", "GENERAL"]

#: Title of a report that is not given one (``run_reproduce`` names the papers it runs).
DEFAULT_TITLE = "chuteflow: reproduction report"
#: Section that receives checkpoints and figures added outside any stage.
GENERAL = "general"


class Report:
    """Figures and checkpoints of a reproduction run, grouped by stage.

    Parameters
    ----------
    title : str
        Report title.
    parameters : mapping, optional
        Run parameters shown in the header (mode, model defaults, …). Stages may add
        to :attr:`parameters` as they run.

    Notes
    -----
    Stages add content through :meth:`check` / :meth:`add_checkpoint`,
    :meth:`add_figure` and :meth:`add_note`; these go to the current stage's section
    (set by the runner with :meth:`stage`) unless ``stage=`` is given. :meth:`write`
    renders ``report.md``, ``report.html`` (self-contained: figures embedded) and
    ``checkpoints.json``.
    """

    def __init__(self, title: str = DEFAULT_TITLE, *, parameters: Mapping[str, Any] | None = None) -> None:
        from chuteflow import __version__

        self.title = title
        self.version: str = __version__
        self.created: datetime = datetime.now(UTC).replace(microsecond=0)
        self.parameters: dict[str, Any] = dict(parameters or {})
        self.wall_time: float | None = None
        self.sections: dict[str, Section] = {}
        self.paths: dict[str, Path] = {}
        self._current: str | None = None
        self._ids: set[str] = set()

    @property
    def environment(self) -> dict[str, str]:
        """Python, platform and versions of the numerical libraries loaded so far."""
        return _environment()

    # -- structure -------------------------------------------------------------------
    def section(self, name: str, title: str | None = None) -> Section:
        """The section for stage ``name``, created on first use."""
        if name not in self.sections:
            self.sections[name] = Section(name, title or name)
        elif title:
            self.sections[name].title = title
        return self.sections[name]

    @contextmanager
    def stage(self, name: str, title: str | None = None) -> Iterator[Section]:
        """Make ``name`` the current section inside the ``with`` block."""
        previous, self._current = self._current, name
        try:
            yield self.section(name, title)
        finally:
            self._current = previous

    def adopt(self, section: Section) -> Section:
        """Put ``section``, made elsewhere (a stage run in another process), in place of the
        section of the same name, keeping its position; its checkpoint ids must be new to
        the rest of this report."""
        old = self.sections.get(section.name)
        others = self._ids - {cp.id for cp in old.checkpoints} if old is not None else self._ids
        dup = [cp.id for cp in section.checkpoints if cp.id in others]
        if dup:
            raise ValueError(f"duplicate checkpoint id {dup[0]!r}")
        self._ids = others | {cp.id for cp in section.checkpoints}
        self.sections[section.name] = section
        return section

    def _target(self, stage: str | None) -> Section:
        return self.section(stage or self._current or GENERAL)

    # -- content ---------------------------------------------------------------------
    def add_checkpoint(self, checkpoint: Checkpoint, *, stage: str | None = None) -> Checkpoint:
        """Add a checkpoint; its id must be new to this report."""
        if not isinstance(checkpoint, Checkpoint):
            raise TypeError(f"expected a Checkpoint, got {type(checkpoint).__name__}")
        if checkpoint.id in self._ids:
            raise ValueError(f"duplicate checkpoint id {checkpoint.id!r}")
        self._ids.add(checkpoint.id)
        self._target(stage).checkpoints.append(checkpoint)
        return checkpoint

    def check(
        self,
        id: str,
        *,
        source: str,
        statement: str,
        computed: str,
        passed: bool | None,
        detail: str = "",
        stage: str | None = None,
    ) -> Checkpoint:
        """Build a :class:`Checkpoint` from the fields and add it."""
        return self.add_checkpoint(Checkpoint(id, source, statement, computed, passed, detail), stage=stage)

    def add_figure(
        self,
        path: str | Path,
        caption: str,
        *,
        id: str | None = None,
        source: str = "",
        stage: str | None = None,
    ) -> Figure:
        """Add a figure file (written by the stage, usually under ``ctx.out``)."""
        fig = Figure(Path(path), caption, id, source)
        self._target(stage).figures.append(fig)
        return fig

    def add_note(self, text: str, *, stage: str | None = None) -> None:
        """Add a paragraph of plain text to a section."""
        self._target(stage).notes.append(str(text))

    # -- queries ---------------------------------------------------------------------
    def iter_checkpoints(self) -> Iterator[tuple[str, Checkpoint]]:
        """``(stage name, checkpoint)`` in stage order, then insertion order."""
        for name, sec in self.sections.items():
            for cp in sec.checkpoints:
                yield name, cp

    @property
    def checkpoints(self) -> list[Checkpoint]:
        return [cp for _, cp in self.iter_checkpoints()]

    @property
    def failed(self) -> list[Checkpoint]:
        return [cp for cp in self.checkpoints if cp.passed is False]

    @property
    def ok(self) -> bool:
        """True when no checkpoint failed (unchecked ones do not count)."""
        return not self.failed

    def counts(self) -> dict[str, int]:
        """Number of checkpoints per status: ``pass``, ``fail``, ``not checked``."""
        out = {STATUS_PASS: 0, STATUS_FAIL: 0, STATUS_NOT_CHECKED: 0}
        for cp in self.checkpoints:
            out[cp.status] += 1
        return out

    # -- output ----------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return {
            "title": self.title,
            "chuteflow_version": self.version,
            "date": self.created.isoformat(),
            "wall_time_s": self.wall_time,
            "parameters": {k: _plain(v) for k, v in self.parameters.items()},
            "environment": self.environment,
            "counts": self.counts(),
            "stages": [
                {
                    "name": s.name,
                    "title": s.title,
                    "status": s.status,
                    "wall_time_s": s.wall_time,
                    "checkpoints": [cp.to_dict() for cp in s.checkpoints],
                    "figures": [
                        {"path": str(f.path), "caption": f.caption, "id": f.id, "source": f.source}
                        for f in s.figures
                    ],
                    "notes": list(s.notes),
                }
                for s in self.sections.values()
            ],
        }

    def to_markdown(self, base: str | Path = ".") -> str:
        """Markdown text; figure links are relative to ``base`` (the output folder)."""
        return render_markdown(self, Path(base))

    def to_html(self) -> str:
        """Self-contained HTML (figures embedded as data URIs)."""
        return render_html(self)

    def write(self, out: str | Path, *, wall_time: float | None = None) -> dict[str, Path]:
        """Write ``report.md``, ``report.html`` and ``checkpoints.json`` into ``out``.

        Returns the paths by kind (``"md"``, ``"html"``, ``"json"``), also kept in
        :attr:`paths`.
        """
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        if wall_time is not None:
            self.wall_time = float(wall_time)
        paths = {"md": out / "report.md", "html": out / "report.html", "json": out / "checkpoints.json"}
        paths["md"].write_text(self.to_markdown(out), encoding="utf-8")
        paths["html"].write_text(self.to_html(), encoding="utf-8")
        paths["json"].write_text(
            json.dumps(self.to_dict(), indent=2, ensure_ascii=False) + "\n", encoding="utf-8"
        )
        self.paths = paths
        return paths


def _plain(value: Any) -> Any:
    """JSON-friendly version of a parameter value."""
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return str(value)


def _environment() -> dict[str, str]:
    env = {"python": sys.version.split()[0], "platform": platform.platform()}
    for mod in ("numpy", "scipy", "sympy", "matplotlib"):
        m = sys.modules.get(mod)
        if m is not None:
            env[mod] = getattr(m, "__version__", "?")
    return env
