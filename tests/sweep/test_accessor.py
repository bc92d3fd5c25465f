"""The ``ds.chute`` accessor: the dataset-level operations as methods, the same results as the
free functions, and the model a Dataset was computed with."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import chuteflow.reduced  # noqa: F401 - registers ds.chute.agreement
from chuteflow.closures import ChuteModel
from chuteflow.errors import ParameterError
from chuteflow.reduced import agreement
from chuteflow.sweep import ChuteAccessor, SweepConfig, classify
from chuteflow.sweep.classify import regime_summary

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


def test_agreement_method_and_extension_rule():
    full = _synthetic_ds()
    red = xr.Dataset(
        {"r1d_unstable": (("theta", "nu0"), full["unstable"].values.copy()), "h": full["h"]},
        coords=full.coords,
    )
    red["r1d_unstable"][0, 0] = 1 - red["r1d_unstable"].values[0, 0]
    assert red.chute.agreement(full, h_min=0) == agreement(red, full, h_min=0)
    assert red.chute.agreement(full, h_min=0)["fraction"] == pytest.approx(15 / 16)
    with pytest.raises(ValueError, match="already defined"):
        ChuteAccessor.method("classify")(lambda self: None)
    assert np.isfinite(red.chute.agreement(full)["fraction"])
