"""``chuteflow reproduce``: run the reproduction stages and write the report."""
from __future__ import annotations

from pathlib import Path

import typer

from ._app import app


@app.command("reproduce")
def reproduce(
    out: Path = typer.Option(Path("reproduce-out"), "--out", "-o",
                             help="Output folder for report.md, report.html and figures."),
    quick: bool = typer.Option(True, "--quick/--full",
                               help="Quick mode (minutes) or the paper's full resolution."),
    stage: list[str] | None = typer.Option(None, "--stage", "-s",
                                           metavar="NAME", help="Run only this stage (repeatable)."),
    list_stages: bool = typer.Option(False, "--list", help="List the stages and exit."),
) -> None:
    """Reproduce the paper's results; exit code 1 if any checkpoint fails."""
    from chuteflow.report import load_stages, registered_stages, run_reproduce

    if list_stages:
        load_stages()
        stages = registered_stages()
        for s in stages:
            typer.echo(f"{s.name}\t{s.title}")
        if not stages:
            typer.echo("(no stages registered)")
        return
    report = run_reproduce(out, quick=quick, stages=stage or None)
    if not report.ok:
        raise typer.Exit(1)
