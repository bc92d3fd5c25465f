"""The 1D diagram of stage ``reduced`` taken from the full model's diagram sweep
(metric ``reduced1d_diagram``): the same numbers as the 1D model's own sweep, point by
point, at the cost of one family tangent per flow."""

from __future__ import annotations

import numpy as np

from chuteflow.papers.mitarai2004.stages.diagrams import DiagramReduced1D
from chuteflow.papers.mitarai2004.stages.reduced import _from_full
from chuteflow.reduced import agreement, reduced_diagram
from chuteflow.sweep import SweepConfig, classify, run_sweep

GRID = ((15.5, 16.0), (0.05, 0.08, 0.12))


def test_diagram_metric_equals_reduced_sweep():
    """Same flows, same eqs (5.13)/(5.14): the values agree to the steady solver's
    tolerance (both sweeps continue along the same rows from the same cold starts)."""
    cfg = SweepConfig(
        theta=GRID[0],
        nu0=GRID[1],
        model=None,
        metrics=("steady", "kinematic", DiagramReduced1D(), "longwave"),
    )
    full = classify(run_sweep(cfg, None, workers=1, progress=False))
    own = reduced_diagram(0.05, grid=GRID)
    red = _from_full(full)
    assert (red["status"].values == 0).all()
    assert (own["status"].values == 0).all()
    for v in ("r1d_margin", "r1d_alpha2", "r1d_dq0", "r1d_dP", "r1d_Tbar", "h"):
        np.testing.assert_allclose(red[v].values, own[v].values, rtol=1e-6, err_msg=v)
    np.testing.assert_array_equal(red["r1d_unstable"].values, own["r1d_unstable"].values)
    agr = agreement(red, full)
    assert agr["compared"] == 6
    assert agr == agreement(own, full)


def test_not_critical_and_status_from_full():
    """A failure of the 1D criterion leaves the full model's point alone; the 1D diagram
    marks a point without r1d values as not converged (2), and keeps 'no flow' (1)."""
    assert DiagramReduced1D.critical is False
    cfg = SweepConfig(theta=(16.0,), nu0=(0.05, 0.08), model=None, metrics=("steady", DiagramReduced1D()))
    full = run_sweep(cfg, None, workers=1, progress=False)
    full["r1d_margin"].values[0, 1] = np.nan
    full["status"].values[0, 0] = 1
    full["r1d_margin"].values[0, 0] = np.nan
    st = _from_full(full)["status"].values
    assert st.tolist() == [[1, 2]]
