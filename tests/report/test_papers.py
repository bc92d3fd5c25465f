"""Paper packages: the paper's points defined once, stage discovery per paper, and the layer
rule (nothing in the library imports chuteflow.papers except report discovery and the CLI)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import chuteflow
from chuteflow.errors import ParameterError
from chuteflow.papers import DEFAULT_PAPERS, PAPERS, load_paper
from chuteflow.papers.mitarai2004 import PAPER_UNSTABLE, POINTS, markers
from chuteflow.papers.mitarai2004.points import FIGURES, figure
from chuteflow.report import isolated_registry, load_stages, register_stage, registered_stages, select_stages

SRC = Path(chuteflow.__file__).parent  # the installed package (site-packages in CI)
DOCS = Path(__file__).resolve().parents[2] / "docs"  # the repository's docs/


def test_points_are_the_papers():
    """§4.2: P1–P5 at φ = 0.05, Q1–Q3 at φ = 0.10 (θ in degrees, ν0(0))."""
    assert [m[0] for m in markers(0.05)] == ["P1", "P2", "P3", "P4", "P5"]
    assert markers(0.10) == (("Q1", 20.0, 0.10), ("Q2", 20.0, 0.15), ("Q3", 20.0, 0.17))
    assert markers(0.2) == ()
    assert POINTS["P4"].theta == 14.0
    assert POINTS["P4"].nu0 == 0.05
    assert set(PAPER_UNSTABLE) <= set(POINTS)


def test_figure_numbers_match_the_label_table():
    table = (DOCS / "paper-labels.md").read_text(encoding="utf-8")
    for label, num in FIGURES.items():
        assert f"| `{label}` | figure | figure {num} |" in table
    assert figure("disp", "(a)") == "figure 7(a)"


def test_stages_belong_to_the_default_paper():
    assert DEFAULT_PAPERS == ("mitarai2004",)
    assert set(DEFAULT_PAPERS) <= set(PAPERS)
    assert load_stages() == {}
    names = [s.name for s in registered_stages(DEFAULT_PAPERS)]
    assert names == [
        "steady",
        "stability",
        "diagrams",
        "reduced",
        "waves",
        "transverse",
        "dns",
        "spatial",
        "closures",
    ]
    assert {s.paper for s in registered_stages(DEFAULT_PAPERS)} == {"mitarai2004"}
    # the stages that read nothing from the others run in the second process (reduced reads
    # the diagrams' sweeps; waves, issue 9, does not and must stay off the main path)
    independent = {s.name for s in registered_stages(DEFAULT_PAPERS) if s.independent}
    assert independent == {"stability", "waves", "transverse", "dns", "spatial", "closures"}
    with pytest.raises(ParameterError, match="unknown paper"):
        load_paper("nope")


def test_a_second_paper_is_a_sibling():
    with isolated_registry():

        @register_stage("other_steady", order=5, paper="other2030")
        def other_steady(ctx):
            """Another paper's stage."""

        @register_stage("generic", order=6)
        def generic(ctx):
            """A stage of no paper (runs with any)."""

        assert [s.name for s in select_stages(None, ["mitarai2004"])] == ["generic"]
        assert [s.name for s in select_stages(None, ["other2030"])] == ["other_steady", "generic"]


def test_library_does_not_import_papers():
    """Layer rule: only report (stage discovery) and cli import chuteflow.papers."""
    pat = re.compile(
        r"^\s*(from\s+(chuteflow|\.+)\s*\.?\s*papers\b|from\s+chuteflow\.papers\b|"
        r"import\s+chuteflow\.papers\b|from\s+\.\.papers\b)",
        re.M,
    )
    bad = []
    for f in SRC.rglob("*.py"):
        rel = f.relative_to(SRC).parts
        if rel[0] in ("papers", "report", "cli"):
            continue
        if pat.search(f.read_text(encoding="utf-8")):
            bad.append(str(f.relative_to(SRC)))
    assert bad == []


def test_the_full_wave_map_runs_each_point_where_it_is_unstable(flows):
    """The full `dns` stage maps P1, P4, P5 each at a period where the fundamental grows
    (§4.2: all three are unstable; at L = 1000 P4 decays, Re α = −2.3e-4): Re α > 0 of the
    least-stable mode at k = 2π/L (P4 9.8e-6 at L ≈ 6283, P5 3.4e-4 at L = 2000, docs/dns.md),
    and the settings are valid map settings."""
    import math

    from chuteflow.dns import WaveMapSettings
    from chuteflow.papers.mitarai2004.stages import dns as stage
    from chuteflow.stability import least_stable

    WaveMapSettings(**stage.FULL_MAP)
    WaveMapSettings(**stage.LONG_MAP)
    runs = [("P1", stage.FULL_MAP["length"]), *stage.LONG_POINTS]
    assert sorted(n for n, _ in runs) == sorted(stage.FULL_POINTS)
    for name, length in runs:
        assert least_stable(flows(name), 2 * math.pi / length).alpha.real > 0, name
