"""Sweep metric ``spatial`` (:class:`chuteflow.sweep.spatial.SpatialMetric`): at P1 its numbers
are the direct API's, at the stable P2 it is "stable" with nothing else computed, and
``chuteflow diagram --metrics steady,spatial`` runs end to end."""

from __future__ import annotations

import math
import time
import warnings

import pytest
from typer.testing import CliRunner

from chuteflow.closures import ChuteModel
from chuteflow.errors import ParameterError
from chuteflow.spatial import absolute_instability, spatial_dispersion, spatial_point
from chuteflow.steady import solve_steady
from chuteflow.sweep import Point
from chuteflow.sweep.spatial import VERDICT_CODES, SpatialMetric


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))


def _compute(flow, **options):
    pt = Point(0, 0, flow.theta, flow.nu0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = SpatialMetric(**options).compute(flow, pt)
    return out, pt


def test_p1_most_amplified_is_a_spatial_point(p1):
    """The metric's maximum, found directly (Re α = Re α' = 0), is a point of the spatial
    branch: spatial_point at its ω has the same −Im k (to 1e-9: Newton's tolerances) and
    Re α'(k) = 0 there (d(−Im k)/dω = Re(1/α') = 0). Measured at P1: ω_max = 0.01718706,
    −Im k = 1.488616e-4."""
    out, pt = _compute(p1, absolute=False)
    assert out["spatial_converged"] is True, pt.notes
    assert out["spatial_verdict"] == 1  # unstable, not classified without Briggs–Bers
    sp = spatial_point(p1, out["omega_max"])
    assert sp.converged, sp.note
    assert sp.spatial_growth == pytest.approx(out["spatial_growth_max"], rel=1e-9)
    assert sp.k.real == pytest.approx(out["k_spatial_max"], rel=1e-9)
    assert abs(sp.dalpha.real) < 1e-8 * abs(sp.dalpha)
    assert out["omega_max"] == pytest.approx(0.01718706, rel=1e-6)
    assert out["spatial_growth_max"] == pytest.approx(1.488616e-4, rel=1e-6)


@pytest.mark.slow
def test_p1_metric_equals_the_direct_api(p1):
    """With Briggs–Bers (5–15 s): the verdict and edges are absolute_instability's, the maximum
    spatial_dispersion's (sampled ω refined by the secant on Re α' = 0: the same root, measured
    2e-11 apart; tolerance 1e-8)."""
    out, pt = _compute(p1)
    assert out["spatial_converged"] is True, pt.notes
    res = absolute_instability(p1)
    assert VERDICT_CODES[out["spatial_verdict"]] == res.verdict == "convective"
    assert out["v_minus"] == pytest.approx(res.v_minus, rel=1e-10)
    assert out["v_plus"] == pytest.approx(res.v_plus, rel=1e-10)
    assert "absolute_growth" not in out  # the lab-frame saddle is not reached at P1
    ds = spatial_dispersion(p1)
    assert out["omega_max"] == pytest.approx(ds.attrs["omega_max"], rel=1e-8)
    assert out["spatial_growth_max"] == pytest.approx(ds.attrs["spatial_growth_max"], rel=1e-8)


def test_stable_point_is_stable_and_cheap():
    """P2 (θ = 16°, ν0(0) = 0.08) is stable (the paper, §4.2): verdict 0, nothing else; the
    temporal scan is the whole cost (0.3 s measured; bound 10 s on a loaded machine)."""
    flow = solve_steady(16.0, 0.08, ChuteModel(roughness=0.05))
    t0 = time.perf_counter()
    out, pt = _compute(flow)
    assert time.perf_counter() - t0 < 10
    assert out == {"spatial_verdict": 0, "spatial_converged": True}, pt.notes
    res = absolute_instability(flow)
    assert res.verdict == "stable"
    assert res.converged
    assert math.isnan(res.v_minus)


def test_options_are_checked():
    with pytest.raises(ParameterError, match="spatial: absolute"):
        SpatialMetric(absolute="yes")
    with pytest.raises(ParameterError, match="k_max"):
        SpatialMetric(k_max=0)


@pytest.mark.slow
def test_diagram_cli_with_the_spatial_metric(tmp_path):
    """``chuteflow diagram --metrics steady,spatial`` over a 2 × 2 grid (about 30 s): the
    verdicts are stored and the diagram is drawn."""
    from chuteflow.cli import app
    from chuteflow.sweep import load_sweep

    out = tmp_path / "d.nc"
    args = ["diagram", "--roughness", "0.05", "--grid", "2x2", "--theta-range", "16", "17"]
    args += ["--nu0-range", "0.05", "0.1", "--metrics", "steady,spatial", "--no-markers", "-j", "1"]
    args += ["--no-progress", "-o", str(out)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    ds = load_sweep(out)
    v = ds["spatial_verdict"].values
    assert set(v.ravel()) <= set(VERDICT_CODES)
    # (16°, 0.05) is P1: convective; (17°, 0.1) is P5: convective
    assert v[0, 0] == 2
    assert v[1, 1] == 2
    assert out.with_suffix(".png").exists()


def test_the_diagram_marks_the_verdicts():
    """chuteflow.figures.diagram marks convective (2), absolute (3) and undetermined (4)
    points, and neither stable (0) nor missing (−1) ones; one legend entry per verdict present."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from chuteflow.figures.diagram import SPATIAL_MARKS, _spatial_marks

    fig, ax = plt.subplots()
    try:
        handles = _spatial_marks(ax, [1.0, 2.0, 3.0, 4.0], [0.1, 0.2, 0.3, 0.4], [0, 2, 2, -1])
        assert [h.get_label() for h in handles] == [SPATIAL_MARKS[2][2]]
        (line,) = ax.get_lines()
        assert list(line.get_xdata()) == [2.0, 3.0]
    finally:
        plt.close(fig)
