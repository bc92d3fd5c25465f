"""Render a :class:`~chuteflow.report.report.Report` as Markdown or self-contained HTML.

It reads the records of :mod:`chuteflow.report.content` and, of the report, what
:class:`Renderable` names: it does not import :mod:`chuteflow.report.report`, which imports it.
"""

from __future__ import annotations

import base64
import html
import os
from dataclasses import replace
from datetime import datetime
from pathlib import Path
from typing import Any, Protocol

from .content import STATUS_FAIL, STATUS_NOT_CHECKED, STATUS_PASS, Section

__all__ = ["render_markdown", "render_html", "Renderable"]


class Renderable(Protocol):
    """What the renderers read of a report (:class:`chuteflow.report.report.Report`)."""

    title: str
    version: str
    created: datetime
    wall_time: float | None
    parameters: dict[str, Any]
    sections: dict[str, Section]

    @property
    def environment(self) -> dict[str, str]: ...

    def counts(self) -> dict[str, int]: ...


_MIME = {
    ".png": "image/png",
    ".jpg": "image/jpeg",
    ".jpeg": "image/jpeg",
    ".svg": "image/svg+xml",
    ".gif": "image/gif",
    ".webp": "image/webp",
}
_SYMBOL = {STATUS_PASS: "✅ pass", STATUS_FAIL: "❌ FAIL", STATUS_NOT_CHECKED: "– not checked"}


def _fmt_time(seconds: float | None) -> str:
    if seconds is None:
        return "–"
    if seconds < 120:
        return f"{seconds:.1f} s"
    return f"{seconds / 60:.1f} min"


def _fmt_value(value: Any) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k}={v}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return ", ".join(map(str, value)) or "–"
    return str(value)


def _header_rows(report: Renderable) -> list[tuple[str, str]]:
    counts = report.counts()
    rows = [
        ("chuteflow version", report.version),
        ("date (UTC)", report.created.strftime("%Y-%m-%d %H:%M:%S")),
        ("wall time", _fmt_time(report.wall_time)),
        (
            "checkpoints",
            f"{counts['pass']} passed, {counts['fail']} failed, {counts['not checked']} not checked",
        ),
    ]
    rows += [(str(k), _fmt_value(v)) for k, v in report.parameters.items()]
    rows += [(k, v) for k, v in report.environment.items()]
    return rows


# -- Markdown ---------------------------------------------------------------------------
def _md_cell(text: str) -> str:
    return str(text).replace("|", r"\|").replace("\r", "").replace("\n", "<br>") or " "


def _md_section(sec: Section, base: Path) -> list[str]:
    lines = [f"## {sec.title}", ""]
    meta = f"Stage `{sec.name}`: {sec.status}"
    if sec.wall_time is not None:
        meta += f", {_fmt_time(sec.wall_time)}"
    lines += [meta + ".", ""]
    for note in sec.notes:
        lines += [note, ""]
    if sec.checkpoints:
        lines += ["| ID | Source | Paper | Computed | Result |", "|---|---|---|---|---|"]
        for cp in sec.checkpoints:
            lines.append(
                "| "
                + " | ".join(
                    _md_cell(x)
                    for x in (f"`{cp.id}`", cp.source, cp.statement, cp.computed, _SYMBOL[cp.status])
                )
                + " |"
            )
        lines.append("")
        detailed = [cp for cp in sec.checkpoints if cp.detail]
        if detailed:
            lines += ["Details:", ""]
            for cp in detailed:
                if "\n" in cp.detail.strip():
                    lines += [f"- `{cp.id}`:", "", "  ```text"]
                    lines += ["  " + ln for ln in cp.detail.rstrip().splitlines()]
                    lines += ["  ```", ""]
                else:
                    lines.append(f"- `{cp.id}`: {cp.detail.strip()}")
            lines.append("")
    for fig in sec.figures:
        rel = Path(os.path.relpath(fig.path, base)).as_posix()
        label = f"{fig.id}: " if fig.id else ""
        src = f" (paper: {fig.source})" if fig.source else ""
        lines += [f"![{fig.caption}]({rel})", "", f"*{label}{fig.caption}{src}*", ""]
    return lines


def render_markdown(report: Renderable, base: Path) -> str:
    """Markdown text of ``report``; figure links relative to ``base``."""
    base = Path(base).resolve()
    lines = [f"# {report.title}", ""]
    lines += ["| | |", "|---|---|"]
    lines += [f"| {_md_cell(k)} | {_md_cell(v)} |" for k, v in _header_rows(report)]
    lines.append("")
    if not report.sections:
        lines += ["_No stage was run._", ""]
    for sec in report.sections.values():
        lines += _md_section(_resolved(sec), base)
    return "\n".join(lines).rstrip() + "\n"


def _resolved(sec: Section) -> Section:
    """Copy of ``sec`` with absolute figure paths (so relpath works from any base)."""
    figs = [replace(f, path=f.path.resolve()) for f in sec.figures]
    return replace(sec, figures=figs)


# -- HTML -------------------------------------------------------------------------------
_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1100px;
margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.5em}h2{margin-top:2em;border-bottom:1px solid #ddd;padding-bottom:.2em}
table{border-collapse:collapse;margin:.6em 0;width:100%}
th,td{border:1px solid #ccc;padding:.3em .5em;text-align:left;vertical-align:top;font-size:.92em}
th{background:#f3f3f3}table.header{width:auto}table.header td:first-child{font-weight:600}
tr.pass td.status{background:#d9f2d9;color:#155724;font-weight:600}
tr.fail td.status{background:#f8d7da;color:#721c24;font-weight:700}
tr.fail{background:#fff5f5}
tr.not-checked td.status{background:#eee;color:#555}
.meta{color:#555;font-size:.9em}.failed{color:#721c24;font-weight:700}
figure{margin:1.2em 0}figure img{max-width:100%;border:1px solid #eee}
figcaption{font-size:.9em;color:#444}pre{background:#f7f7f7;padding:.5em;overflow-x:auto;
font-size:.85em}code{font-size:.9em}details summary{cursor:pointer;color:#555}
.summary-ok{color:#155724;font-weight:600}.summary-fail{color:#721c24;font-weight:700}
"""


def _e(text: Any) -> str:
    return html.escape(str(text))


def _img(fig) -> str:
    mime = _MIME.get(fig.path.suffix.lower())
    if mime is None or not fig.path.is_file():
        what = "missing figure" if not fig.path.is_file() else "figure"
        return (
            f'<p><a href="{_e(fig.path.as_uri() if fig.path.is_absolute() else fig.path)}">'
            f"{what}: {_e(fig.path.name)}</a></p>"
        )
    data = base64.b64encode(fig.path.read_bytes()).decode("ascii")
    return f'<img src="data:{mime};base64,{data}" alt="{_e(fig.caption)}">'


def _html_section(sec: Section) -> str:
    parts = [f'<section id="stage-{_e(sec.name)}"><h2>{_e(sec.title)}</h2>']
    status = f'<span class="failed">{_e(sec.status)}</span>' if sec.status == "failed" else _e(sec.status)
    parts.append(
        f'<p class="meta">Stage <code>{_e(sec.name)}</code>: {status}'
        f"{', ' + _fmt_time(sec.wall_time) if sec.wall_time is not None else ''}.</p>"
    )
    parts += [f"<p>{_e(n)}</p>" for n in sec.notes]
    if sec.checkpoints:
        parts.append(
            "<table><thead><tr><th>ID</th><th>Source</th><th>Paper</th>"
            "<th>Computed</th><th>Result</th></tr></thead><tbody>"
        )
        for cp in sec.checkpoints:
            cls = cp.status.replace(" ", "-")
            detail = ""
            if cp.detail:
                open_ = " open" if cp.passed is False else ""
                detail = (
                    f"<details{open_}><summary>detail</summary><pre>{_e(cp.detail.rstrip())}</pre></details>"
                )
            parts.append(
                f'<tr class="{cls}"><td><code>{_e(cp.id)}</code></td>'
                f"<td>{_e(cp.source)}</td><td>{_e(cp.statement)}</td>"
                f"<td>{_e(cp.computed)}{detail}</td>"
                f'<td class="status">{_e(_SYMBOL[cp.status])}</td></tr>'
            )
        parts.append("</tbody></table>")
    for fig in sec.figures:
        label = f"<b>{_e(fig.id)}</b>: " if fig.id else ""
        src = f" (paper: {_e(fig.source)})" if fig.source else ""
        parts.append(f"<figure>{_img(fig)}<figcaption>{label}{_e(fig.caption)}{src}</figcaption></figure>")
    parts.append("</section>")
    return "\n".join(parts)


def render_html(report: Renderable) -> str:
    """Self-contained HTML page of ``report`` (inline CSS, figures as data URIs)."""
    counts = report.counts()
    summary_cls = "summary-fail" if counts["fail"] else "summary-ok"
    header = "".join(f"<tr><td>{_e(k)}</td><td>{_e(v)}</td></tr>" for k, v in _header_rows(report))
    body = [
        f"<h1>{_e(report.title)}</h1>",
        f'<p class="{summary_cls}">{counts["pass"]} passed, {counts["fail"]} failed, '
        f"{counts['not checked']} not checked</p>",
        f'<table class="header">{header}</table>',
    ]
    if not report.sections:
        body.append("<p><em>No stage was run.</em></p>")
    body += [_html_section(sec) for sec in report.sections.values()]
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{_e(report.title)}</title><style>{_CSS}</style></head><body>\n"
        + "\n".join(body)
        + "\n</body></html>\n"
    )
