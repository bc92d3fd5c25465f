"""``chuteflow reproduce``: run the reproduction stages and write the report."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app


@app.command("reproduce")
def reproduce(
    out: Path = typer.Option(
        Path("reproduce-out"), "--out", "-o", help="Output folder for report.md, report.html and figures."
    ),
    quick: bool = typer.Option(
        True, "--quick/--full", help="Quick mode (minutes) or the paper's full resolution."
    ),
    stage: list[str] | None = typer.Option(
        None, "--stage", "-s", metavar="NAME", help="Run only this stage (repeatable)."
    ),
    list_stages: bool = typer.Option(False, "--list", help="List the stages and exit."),
    paper: list[str] | None = typer.Option(
        None,
        "--paper",
        "-p",
        metavar="NAME",
        # the registry (chuteflow.report.papers) is imported by the command, not at start-up
        help="Reproduce this paper (repeatable; default: mitarai2004, the papers of "
        "chuteflow.report.papers.DEFAULT_PAPERS).",
    ),
) -> None:
    """Reproduce the papers' results; exit code 1 if any checkpoint fails."""
    from chuteflow.report import load_stages, registered_stages, run_reproduce
    from chuteflow.report.papers import DEFAULT_PAPERS

    papers = tuple(paper) if paper else DEFAULT_PAPERS
    if list_stages:
        load_stages(papers)
        stages = registered_stages(papers)
        for s in stages:
            typer.echo(f"{s.name}\t{s.paper or '-'}\t{s.title}")
        if not stages:
            typer.echo("(no stages registered)")
        return
    report = run_reproduce(out, quick=quick, stages=stage or None, papers=papers)
    if not report.ok:
        raise typer.Exit(1)
