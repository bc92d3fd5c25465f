"""The same sweep on a Dask LocalCluster equals the local run (optional extra chuteflow[dask])."""

from __future__ import annotations

import sys

import pytest
import xarray as xr

from chuteflow.errors import ParameterError
from chuteflow.sweep import Sweep, SweepConfig, run_sweep

from ._helpers import NU0, THETA


def _cfg():
    return SweepConfig(
        theta=THETA,
        nu0=NU0[:3],
        roughness=0.05,
        chunk=2,
        metrics=("steady", "kinematic"),
        markers=(("P1", 16.0, 0.05),),
    )


def test_dask_local_cluster_equals_local_run(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    cfg = _cfg()
    local = run_sweep(cfg, workers=1)
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        sw = Sweep(cfg, tmp_path / "dask.nc")
        got = sw.run(client=client)
    assert sw.stats.backend == "dask"
    assert sw.stats.computed == len(cfg.tasks())
    xr.testing.assert_identical(got, local)


def test_missing_dask_gives_clear_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    with pytest.raises(ParameterError, match=r"chuteflow\[dask\]"):
        run_sweep(_cfg(), scheduler="tcp://127.0.0.1:1")


def test_client_and_scheduler_exclusive():
    with pytest.raises(ParameterError, match="not both"):
        run_sweep(_cfg(), client=object(), scheduler="tcp://127.0.0.1:1")
