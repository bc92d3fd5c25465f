"""Command line: help, one-line user errors (exit 2), ``reproduce`` and the report."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
import typer
from typer.testing import CliRunner

from chuteflow import __version__
from chuteflow.cli import app, main
from chuteflow.cli._app import ChuteflowGroup
from chuteflow.report import Checkpoint, isolated_registry, register_stage, run_reproduce

runner = CliRunner()


def _one_line_error(result) -> str:
    err = result.stderr.strip()
    assert "Traceback" not in result.output
    assert len(err.splitlines()) == 1, err
    assert err.startswith("error: "), err
    return err


def test_help():
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0, result.output
    assert "reproduce" in result.output
    result = runner.invoke(app, ["reproduce", "--help"])
    assert result.exit_code == 0, result.output
    assert "--quick" in result.output
    assert "--stage" in result.output


def test_version():
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0
    assert __version__ in result.output


def test_unknown_stage_is_a_one_line_error():
    with isolated_registry():
        result = runner.invoke(app, ["reproduce", "--stage", "no-such-stage"])
    assert result.exit_code == 2
    assert "no-such-stage" in _one_line_error(result)


def test_parameter_error_is_a_one_line_error():
    """A ParameterError from the model layer, raised inside any command."""
    from chuteflow.closures import ChuteModel

    demo = typer.Typer(cls=ChuteflowGroup)

    @demo.command()
    def build(restitution: float = 0.7) -> None:
        ChuteModel(restitution=restitution)

    @demo.command()
    def other() -> None:  # a second command keeps `demo` a group
        pass

    result = runner.invoke(demo, ["build", "--restitution", "1.5"])
    assert result.exit_code == 2
    err = _one_line_error(result)
    assert "restitution" in err
    assert "(0, 1]" in err
    assert runner.invoke(demo, ["build", "--restitution", "0.9"]).exit_code == 0


def test_main_returns_2_on_user_error(capsys):
    with isolated_registry():
        code = main(["reproduce", "--stage", "no-such-stage"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ")
    assert len(err.splitlines()) == 1


def test_reproduce_with_no_stages_writes_report(tmp_path):
    out = tmp_path / "out"
    with isolated_registry():
        result = runner.invoke(app, ["reproduce", "--out", str(out)])
    assert result.exit_code == 0, result.output
    md = (out / "report.md").read_text(encoding="utf-8")
    html = (out / "report.html").read_text(encoding="utf-8")
    assert __version__ in md
    assert "mode | quick" in md
    assert html.startswith("<!DOCTYPE html>")
    assert __version__ in html
    data = json.loads((out / "checkpoints.json").read_text(encoding="utf-8"))
    assert data["counts"] == {"pass": 0, "fail": 0, "not checked": 0}


def test_reproduce_failing_stage_is_recorded_and_run_continues(tmp_path):
    import matplotlib.pyplot as plt

    with isolated_registry():

        @register_stage("broken", order=1)
        def broken(ctx):
            """A stage that crashes."""
            ctx.progress("about to fail")
            raise RuntimeError("boom")

        @register_stage("works", order=2, title="Working stage")
        def works(ctx):
            for _ in ctx.progress.track(range(3), "looping"):
                pass
            fig, ax = plt.subplots()
            ax.plot([0, 1], [0, 1])
            fig.savefig(ctx.path("line.png"))
            plt.close(fig)
            ctx.report.add_figure(ctx.path("line.png"), "A line", id="fig1", source="figure 1")
            ctx.report.add_note("Note with <html> & | pipes.")
            ctx.report.check("works.ok", source="§3", statement="1 = 1", computed="1", passed=True)
            ctx.report.add_checkpoint(
                Checkpoint.compare(
                    "works.h",
                    source="§3.2",
                    statement="h ≈ 23",
                    value=23.4,
                    expected=23.0,
                    rtol=0.05,
                    name="h",
                )
            )
            ctx.report.check(
                "works.qual", source="fig:x", statement="qualitative", computed="see figure", passed=None
            )

        result = runner.invoke(app, ["reproduce", "--out", str(tmp_path), "--full"])
        assert result.exit_code == 1, result.output
        assert "Traceback" not in result.stderr

        # Selecting one stage runs only that one.
        sub = tmp_path / "sub"
        report = run_reproduce(sub, stages=["works"])
        assert report.ok
        assert list(report.sections) == ["works"]

    md = (tmp_path / "report.md").read_text(encoding="utf-8")
    html = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert "broken.completed" in md
    assert "RuntimeError: boom" in md
    assert "## Working stage" in md
    assert "![A line](works/line.png)" in md
    assert "mode | full" in md
    assert "data:image/png;base64," in html  # self-contained
    assert 'class="fail"' in html
    assert 'class="pass"' in html
    assert 'class="not-checked"' in html
    assert "&lt;html&gt;" in html
    data = json.loads((tmp_path / "checkpoints.json").read_text(encoding="utf-8"))
    assert data["counts"] == {"pass": 2, "fail": 1, "not checked": 1}
    assert [s["status"] for s in data["stages"]] == ["failed", "ok"]


def test_independent_stages_run_in_a_second_process(tmp_path):
    """Stages registered ``independent`` run in a forked process beside the others: their
    sections come back in the stages' order, with their checkpoints (a failure included),
    and their files are written; ``concurrent=False`` runs everything here."""
    import os

    with isolated_registry():

        @register_stage("first", order=1)
        def first(ctx):
            """In this process."""
            ctx.shared["first"] = os.getpid()
            ctx.report.check("first.pid", source="-", statement="-", computed=str(os.getpid()), passed=True)

        @register_stage("side", order=2, independent=True)
        def side(ctx):
            """Beside the others."""
            ctx.path("side.txt").write_text("written")
            ctx.report.check("side.pid", source="-", statement="-", computed=str(os.getpid()), passed=True)

        @register_stage("side_fails", order=3, independent=True)
        def side_fails(ctx):
            """Fails beside the others."""
            raise RuntimeError("boom beside")

        @register_stage("last", order=4)
        def last(ctx):
            """Reads what the first stage left."""
            ctx.report.check(
                "last.shared", source="-", statement="-", computed="-", passed="first" in ctx.shared
            )

        for concurrent in (True, False):
            rep = run_reproduce(tmp_path / str(concurrent), show_progress=False, concurrent=concurrent)
            assert list(rep.sections) == ["first", "side", "side_fails", "last"]
            pids = {cp.id: cp.computed for _, cp in rep.iter_checkpoints()}
            assert (pids["side.pid"] != pids["first.pid"]) is concurrent
            assert [s.status for s in rep.sections.values()] == ["ok", "ok", "failed", "ok"]
            assert rep.counts() == {"pass": 3, "fail": 1, "not checked": 0}
            assert "boom beside" in (tmp_path / str(concurrent) / "report.md").read_text(encoding="utf-8")
            assert (tmp_path / str(concurrent) / "side" / "side.txt").read_text() == "written"


def test_duplicate_stage_name_rejected():
    with isolated_registry():

        @register_stage("dup", order=1)
        def first(ctx):
            pass

        with pytest.raises(ValueError, match="already registered"):

            @register_stage("dup", order=2)
            def second(ctx):
                pass


def test_python_dash_m(tmp_path):
    """``python -m chuteflow`` works (subprocess: the real entry point)."""
    result = subprocess.run(
        [sys.executable, "-m", "chuteflow", "--help"], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert "reproduce" in result.stdout


def test_cli_model_defaults_are_the_model_defaults():
    """The CLI's model-option defaults equal ChuteModel's (paper §2: e_p 0.7, ν_m 0.6, φ 0.05, Φ 0.39)."""
    from chuteflow.cli._app import MODEL_OPTIONS
    from chuteflow.closures import ChuteModel

    m = ChuteModel()
    assert {k: v[0] for k, v in MODEL_OPTIONS.items()} == {k: getattr(m, k) for k in MODEL_OPTIONS}


def test_steady_options_are_declared_once():
    """The typer command ``steady`` is generated from STEADY_OPTIONS (and the model options):
    the same parameters, flags, defaults and help as the plain-call parser reads."""
    import typer.main

    from chuteflow.cli._fast import REQUIRED, STEADY_OPTIONS

    cmd = typer.main.get_command(app).commands["steady"]  # type: ignore[attr-defined]
    params = {p.name: p for p in cmd.params}
    for o in STEADY_OPTIONS:
        p = params[o.name]
        assert set(o.flags()) == set(p.opts) | set(p.secondary_opts)
        assert p.required == (o.default is REQUIRED)
        if o.default is not REQUIRED:
            assert p.default == o.default
        assert p.help == o.help


def test_fast_steady_path_matches_typer(capsys):
    """The plain parser of ``chuteflow steady`` (cli/_fast.py) prints what the typer command
    prints, and leaves what it does not know (help, bad values) to typer."""
    from chuteflow.cli._fast import _parse_steady, fast_main

    argv = [
        "steady",
        "--theta",
        "16",
        "--nu0=0.05",
        "--wall-loss",
        "0.39",
        "--radial",
        "lun_savage",
        "--json",
    ]
    assert fast_main(argv) == 0
    fast = capsys.readouterr().out
    res = CliRunner().invoke(app, argv)
    assert res.exit_code == 0
    assert res.stdout == fast
    for bad in (["--theta", "abc", "--nu0", "0.05"], ["--theta", "16"], ["--help"], ["--radial", "nope"]):
        assert _parse_steady(bad) is None
    opts = _parse_steady(["--theta", "16", "--nu0", "0.05", "--no-strict", "--nu-top=1e-8", "--strict"])
    assert opts is not None
    assert (opts["strict"], opts["nu_top"], opts["as_json"]) == (True, 1e-8, False)
    assert fast_main(["steady", "--theta", "95", "--nu0", "0.05"]) == 2
    assert capsys.readouterr().err.startswith("error: theta = 95")
