"""The ``ds.chute`` accessor: the dataset-level operations as methods, the same results as the
free functions, and the model a Dataset was computed with."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from chuteflow.closures import ChuteModel
from chuteflow.errors import ParameterError
from chuteflow.reduced import agreement
from chuteflow.sweep import ChuteAccessor, SweepConfig, classify
from chuteflow.sweep.regimes import regime_summary

from .test_classify import _synthetic_ds


def _raw():
    return _synthetic_ds().drop_vars(["unstable", "regime"], errors="ignore")


def test_classify_and_summary_match_the_free_functions():
    ds = _raw()
    a, b = ds.chute.classify(), classify(ds)
    xr.testing.assert_identical(a, b)
    assert a.chute.regime_summary() == regime_summary(b)
    assert "unstable" not in ds  # a copy, as the free function


def test_model_from_attributes():
    ds = _raw()
    assert ds.chute.config is None
    with pytest.raises(ParameterError, match="no model"):
        _ = ds.chute.model
    ds.attrs.update(wall_loss=0.39, restitution=0.7, nu_max=0.6)  # roughness 0.05 is there
    assert ds.chute.model == ChuteModel(roughness=0.05)
    cfg = SweepConfig(theta=(16.0,), nu0=(0.05,), roughness=0.10, metrics=("steady",))
    ds.attrs["config_json"] = json.dumps(cfg.to_dict())
    assert ds.chute.config == cfg
    assert ds.chute.model.roughness == 0.10


def test_accessor_methods_do_not_depend_on_other_imports():
    full = _synthetic_ds()
    red = xr.Dataset(
        {"r1d_unstable": (("theta", "nu0"), full["unstable"].values.copy()), "h": full["h"]},
        coords=full.coords,
    )
    red["r1d_unstable"][0, 0] = 1 - red["r1d_unstable"].values[0, 0]
    # a higher layer's operation is its function, not a method added on import
    assert not hasattr(red.chute, "agreement")
    assert not hasattr(ChuteAccessor, "method")
    assert agreement(red, full, h_min=0)["fraction"] == pytest.approx(15 / 16)
    assert np.isfinite(agreement(red, full)["fraction"])


_LEAN = """
import sys
import chuteflow.sweep
from chuteflow.sweep import SweepConfig, run_task
assert "xarray" not in sys.modules and "pandas" not in sys.modules, "imported by chuteflow.sweep"
cfg = SweepConfig.grid(0.05, shape=(2, 3), theta_range=(15.9, 16.1), nu0_range=(0.04, 0.06))
res = run_task(cfg, cfg.tasks()[0])
assert (res.status == 0).all(), res.message
assert "xarray" not in sys.modules and "pandas" not in sys.modules, "imported by a task"
import xarray as xr
assert hasattr(xr.Dataset(), "chute")
print(type(xr.Dataset().chute).__name__)
"""


def test_sweep_workers_need_no_xarray():
    """Importing chuteflow.sweep and running a task (what a forked worker does) leaves xarray
    and pandas unimported (~44 MiB a worker: 60 × 60 diagram, worker peak 329 → 277 MiB), and
    ``ds.chute`` is registered as soon as xarray is imported."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    src = Path(__file__).resolve().parents[2] / "src"
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(src))
    done = subprocess.run([sys.executable, "-c", _LEAN], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "ChuteAccessor"
