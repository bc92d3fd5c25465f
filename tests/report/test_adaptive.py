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
    assert (flag[[0, 0, 3, 3], [0, 3, 0, 3]] == 0).all() and flag[1, 0] == 0 and flag[2, 0] == 0
    assert flag[1, 1] == 1 and flag[2, 3] == 1
    assert np.isfinite(a2).all() and (a2 < 0).all()
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
    assert counts["inferred"] == 0 and counts["refined"] == 2
    # P1 (16°, 0.05) is long-wave unstable, (16.1°, 0.05) too (paper §4.2, regime B)
    assert out["alpha2_re"].values[1, 0] > 0 and out["alpha2_inferred"].values[1, 0] == 0


def test_stride_validated():
    with pytest.raises(ValueError, match="stride"):
        StridedLongWave(stride=0)
