"""Checkpoint and Report without the runner."""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.report import Checkpoint, Report


def test_checkpoint_status_and_coercion():
    assert Checkpoint("a", "§1", "s", "c", np.bool_(True)).passed is True
    assert Checkpoint("a", "§1", "s", "c", False).status == "fail"
    assert Checkpoint("a", "§1", "s", "c", None).status == "not checked"
    with pytest.raises(ValueError, match="non-empty string"):
        Checkpoint("", "§1", "s", "c", True)


def test_checkpoint_compare():
    ok = Checkpoint.compare(
        "h", source="§3", statement="h ≈ 23", value=23.5, expected=23.0, rtol=0.05, name="h"
    )
    assert ok.passed
    assert "h = 23.5" in ok.computed
    assert "paper 23" in ok.computed
    bad = Checkpoint.compare("h2", source="§3", statement="h ≈ 23", value=30.0, expected=23.0, rtol=0.05)
    assert bad.passed is False
    assert (
        Checkpoint.compare("h3", source="", statement="", value=math.nan, expected=1.0, atol=1.0).passed
        is False
    )


def test_report_sections_and_duplicates(tmp_path):
    rep = Report(parameters={"theta": 16})
    rep.check("g1", source="s", statement="x", computed="y", passed=True)
    with rep.stage("steady", "Steady flows"):
        rep.check("s1", source="s", statement="x", computed="y", passed=False)
        rep.add_figure(tmp_path / "missing.png", "not written")
    assert list(rep.sections) == ["general", "steady"]
    assert rep.counts() == {"pass": 1, "fail": 1, "not checked": 0}
    assert not rep.ok
    with pytest.raises(ValueError, match="duplicate"):
        rep.check("s1", source="s", statement="x", computed="y", passed=True)
    paths = rep.write(tmp_path, wall_time=1.5)
    html = paths["html"].read_text(encoding="utf-8")
    assert "missing figure" in html
    assert "theta" in html
    assert "1.5 s" in html
    assert "## Steady flows" in paths["md"].read_text(encoding="utf-8")


def test_adopt_replaces_a_section_in_place():
    """A section made in another process takes the place of its placeholder (same
    position); its checkpoint ids must be new to the rest of the report."""
    from chuteflow.report.report import Section

    rep = Report()
    rep.section("a")
    rep.section("b")
    rep.check("a.x", source="-", statement="-", computed="-", passed=True, stage="a")
    other = Section("b", "B", status="ok")
    other.checkpoints.append(Checkpoint(id="b.y", source="-", statement="-", computed="-", passed=True))
    rep.adopt(other)
    assert list(rep.sections) == ["a", "b"]
    assert rep.sections["b"] is other
    clash = Section("b", "B")
    clash.checkpoints.append(Checkpoint(id="a.x", source="-", statement="-", computed="-", passed=True))
    with pytest.raises(ValueError, match="duplicate checkpoint id 'a.x'"):
        rep.adopt(clash)
    assert rep.sections["b"] is other
    with pytest.raises(ValueError, match="duplicate"):
        rep.check("b.y", source="-", statement="-", computed="-", passed=True, stage="a")
