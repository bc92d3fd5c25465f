"""The fine-grid stability diagrams of chuteflow.papers.mitarai2004.adaptive (issue 9, item
6): α2 on a coarse sub-grid, computed exactly where the coarse values do not decide its
sign, interpolated (sign-preserving) elsewhere."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from chuteflow.papers.mitarai2004.adaptive import StridedLongWave, refine_longwave
from chuteflow.sweep import SweepConfig
from chuteflow.sweep.metrics import LongWaveMetric
from chuteflow.sweep.points import Point


def test_strided_metric_skips_off_grid_points():
    f = StridedLongWave(stride=3)
    assert f.compute(None, Point(1, 0, 16.0, 0.05)) == {}
    assert f.compute(None, Point(3, 2, 16.0, 0.05)) == {}
    assert [v.name for v in f.variables] == [v.name for v in LongWaveMetric.variables]
    assert f.inner().options == LongWaveMetric().options


def _dataset(cfg, a2_coarse):
    ni, nj = cfg.shape
    data = {
        v.name: (("theta", "nu0"), np.full((ni, nj), v.missing, dtype=v.dtype))
        for v in LongWaveMetric.variables
    }
    data["status"] = (("theta", "nu0"), np.zeros((ni, nj), dtype=np.int8))
    data["message"] = (("theta", "nu0"), np.full((ni, nj), "", dtype=object))
    for v in ("h", "nu_mean", "dU_drho"):
        data[v] = (("theta", "nu0"), np.ones((ni, nj)))
    ds = xr.Dataset(
        data, coords={"theta": np.asarray(cfg.theta), "nu0": np.asarray(cfg.nu0)}, attrs={"roughness": 0.05}
    )
    for (i, j), a in a2_coarse.items():
        ds["alpha2_re"].values[i, j] = a
    return ds


def test_agreeing_corners_are_interpolated_and_row_ends_computed():
    """All four corners of the one coarse cell stable: the inner points get a negative,
    flagged Re α2, without any computation except at each row's least dense flow (rows 1
    and 2, which the checks of §4.2 follow; computed exactly: P1's row is long-wave stable
    at ν0(0) = 0.08)."""
    cfg = SweepConfig.grid(
        0.05,
        shape=(4, 4),
        theta_range=(16.0, 16.3),
        nu0_range=(0.08, 0.1),
        metrics=("steady", StridedLongWave()),
    )
    corners = {(0, 0): -2.0, (0, 3): -1.0, (3, 0): -3.0, (3, 3): -0.5}
    ds, counts = refine_longwave(_dataset(cfg, corners), cfg, workers=1)
    assert counts == {"coarse": 4, "refined": 2, "inferred": 10, "failed": 0}
    flag = ds["alpha2_inferred"].values
    a2 = ds["alpha2_re"].values
    assert (flag[[0, 0, 3, 3], [0, 3, 0, 3]] == 0).all()
    assert flag[1, 0] == 0
    assert flag[2, 0] == 0
    assert flag[1, 1] == 1
    assert flag[2, 3] == 1
    assert np.isfinite(a2).all()
    assert (a2 < 0).all()
    assert (ds["unstable"].values == 0).all()


def test_sign_change_cell_is_computed():
    """Corners of opposite sign: every inner point is computed (none inferred)."""
    cfg = SweepConfig.grid(
        0.05,
        shape=(2, 2),
        theta_range=(16.0, 16.1),
        nu0_range=(0.05, 0.08),
        metrics=("steady", StridedLongWave()),
    )
    ds = _dataset(cfg, {(0, 0): 1.0, (1, 1): -1.0})
    out, counts = refine_longwave(ds, cfg, workers=1)
    assert counts["inferred"] == 0
    assert counts["refined"] == 2
    # P1 (16°, 0.05) is long-wave unstable, (16.1°, 0.05) too (paper §4.2, regime B)
    assert out["alpha2_re"].values[1, 0] > 0
    assert out["alpha2_inferred"].values[1, 0] == 0


def test_stride_validated():
    with pytest.raises(ValueError, match="stride"):
        StridedLongWave(stride=0)


def test_refine_reuses_the_sweeps_flows():
    """``Sweep.run(keep_flows=True)`` keeps the flows of the grid points, and
    ``refine_longwave(..., flows=...)`` computes α2 on them instead of solving the steady
    flows again: the same α2 as from fresh solves, within α2's own convergence estimate
    (both flows are converged to rtol = 1e-8 between two resolutions). The cell
    spans P1 (16°, 0.05: long-wave unstable) and P2's density (0.08: stable, §4.2), so its
    inner points are computed."""
    from chuteflow.sweep import Sweep

    cfg = SweepConfig.grid(
        0.05,
        shape=(4, 4),
        theta_range=(16.0, 16.3),
        nu0_range=(0.05, 0.08),
        metrics=("steady", StridedLongWave(stride=3)),
    )
    sweep = Sweep(cfg)
    ds = sweep.run(workers=1, keep_flows=True)
    ok = ds["status"].values == 0
    assert ok.all()
    assert set(sweep.flows) == {(i, j) for i in range(4) for j in range(4)}
    flow = sweep.flows[(3, 0)]
    assert flow.theta == pytest.approx(16.3)
    assert flow.nu0 == pytest.approx(0.05)
    a, ca = refine_longwave(ds, cfg, workers=1, flows=sweep.flows)
    b, cb = refine_longwave(ds, cfg, workers=1)
    assert ca == cb
    assert ca["coarse"] == 4
    assert ca["refined"] == 12
    ra, rb = a["alpha2_re"].values, b["alpha2_re"].values
    assert np.isfinite(ra).all()
    assert (ra[:, 0] > 0).all()
    assert (ra[:, 3] < 0).all()
    # the two flows differ within the steady rtol (1e-8); α2 moves by less than its own
    # convergence estimate (the relative change between its two finest resolutions;
    # measured: differences ≤ 2.6e-6 relative against estimates ≥ 6.7e-5)
    conv = a["alpha2_convergence"].values
    assert (np.abs(ra - rb) <= conv * np.abs(rb)).all(), (np.abs(ra / rb - 1).max(), conv.min())


def _row_ends_dataset(**grid):
    """A small diagram (``SweepConfig.grid(0.05, **grid)`` with the point functions that
    ``row_ends`` classifies with) and its dataset, every point a flow, no values yet."""
    import json

    cfg = SweepConfig.grid(0.05, metrics=("steady", "kinematic", StridedLongWave(stride=1)), **grid)
    ds = _dataset(cfg, {})
    ds.attrs["config_json"] = json.dumps(cfg.to_dict(), sort_keys=True)
    return cfg, ds


def test_row_ends_take_the_sweeps_flows():
    """:func:`~chuteflow.papers.mitarai2004.edges.row_ends` with ``flows=`` (the sweep's
    steady flows) starts a row's bisection below its least dense grid flow from that flow
    instead of solving it again from the cold start; the row end it reports is that flow
    here (every bisection step below it is refused) and it is classified with the sweep's
    point functions (P2, θ = 16°, ν0(0) = 0.08: long-wave stable, §4.2)."""
    from unittest import mock

    from chuteflow.errors import NoSteadyFlowError
    from chuteflow.papers.mitarai2004 import edges
    from chuteflow.steady import solve_steady

    cfg, ds = _row_ends_dataset(shape=(1, 2), theta_range=(16.0, 16.0), nu0_range=(0.07, 0.08))
    ds["status"].values[0, 0] = 2  # the least dense point has no flow: bisect towards it
    flow = solve_steady(16.0, 0.08)
    calls = []

    def refused(theta, nu0, model=None, **kw):
        calls.append(kw.get("guess"))
        raise NoSteadyFlowError("refused in this test")

    with mock.patch.object(edges, "solve_steady", refused):
        (end,) = edges.row_ends(ds, flows={(0, 1): flow}, bisections=2)
    assert len(calls) == 2
    assert all(g is flow for g in calls)
    assert end["nu0"] == flow.nu0
    assert end["how"] == "grid"
    assert end["h"] == flow.h
    assert end["kind"] == "stable"
    assert end["alpha2_re"] < 0


def test_row_ends_below_the_grid_leave_the_sweeps_flows_alone():
    """A row whose least dense flow is the grid's first column is followed below the grid
    by a steady family; its list of flows overwrote ``flows`` (the sweep's dict), and the
    next row failed with "AttributeError: 'list' object has no attribute 'get'" — the full
    (100 × 100) diagrams stage of ``chuteflow reproduce --full`` at φ = 0.1. Two such rows
    (P2's θ = 16° and 16.1°, ν0(0) = 0.08 first): both answered, the second from the
    sweep's flow."""

    from chuteflow.papers.mitarai2004 import edges
    from chuteflow.steady import solve_steady

    cfg, ds = _row_ends_dataset(shape=(2, 1), theta_range=(16.0, 16.1), nu0_range=(0.08, 0.08))
    flows = {(i, 0): solve_steady(float(th), 0.08) for i, th in enumerate(cfg.theta)}
    ends = edges.row_ends(ds, flows=flows, halvings=1)
    assert len(ends) == 2
    assert all(e["kind"] != "error" for e in ends)
    assert all(e["nu0"] <= 0.08 and e["how"] in ("below grid", "grid, no flow found below") for e in ends)


def test_row_end_without_a_long_wave_value_is_a_failed_row():
    """The long-wave metric leaves Re α/k² missing (None) where it has no finite value; the
    full φ = 0.1 diagram's row θ = 20.14° ended (continued below the grid) at ν0(0) = 3.1e-4,
    h = 84, where it is NaN at N = 160, and ``row_ends`` failed with "TypeError: '>' not
    supported between instances of 'NoneType' and 'int'". Now that row is an error with the
    metric's reason, which the §4.2 check lists as a failed row, not as a judged one."""
    from types import SimpleNamespace

    from chuteflow.papers.mitarai2004 import checks, edges

    class Fixed:
        def __init__(self, values, note=""):
            self.values, self.note_text = values, note

        def compute(self, flow, point):
            if self.note_text:
                point.note(self.note_text)
            return dict(self.values)

    flow = SimpleNamespace(theta=20.14, nu0=3.1e-4)
    fns = [Fixed({"dU_drho": -9226.9}), Fixed({"alpha2_re": None}, "longwave: Re α/k² = nan")]
    rec = edges._classify_flow(flow, fns)
    assert rec["kind"] == "error"
    assert "Re α/k² = nan" in rec["error"]
    assert not rec["consistent"]
    end = {"theta": 20.14, "nu0": 3.1e-4, "h": 84.0, **rec}
    ok = {
        "theta": 16.0,
        "nu0": 0.01,
        "h": 5.0,
        "alpha2_re": 1.0,
        "dU_drho": 1.0,
        "kind": "A",
        "consistent": True,
    }
    c = checks.check_low_density_unstable(xr.Dataset(attrs={"roughness": 0.1}), [ok, end])
    assert "1 of 1 θ rows" in c["computed"]
    assert "1 rows failed" in c["computed"]
    assert "undetermined" not in c["computed"]
