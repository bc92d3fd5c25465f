"""Modes and long-wave coefficients record the model they were computed with (and put it in
their summaries), so results of different closures cannot be mixed up."""

from __future__ import annotations

from chuteflow.closures import ChuteModel
from chuteflow.longwave import LongWave, longwave
from chuteflow.stability import least_stable


def test_mode_records_the_model(p1_flow):
    mode = least_stable(p1_flow, 0.01)
    assert mode.model == p1_flow.model == ChuteModel()
    s = mode.to_dict()
    assert {k: s[k] for k in ChuteModel().to_dict()} == ChuteModel().to_dict()
    assert mode.to_xarray().attrs["radial"] == "lun_savage"


def test_longwave_records_the_model(p1_flow):
    lw = longwave(p1_flow, rtol=0.2)
    assert isinstance(lw, LongWave)
    assert lw.model == p1_flow.model
    assert lw.to_dict()["radial"] == "lun_savage"
    assert hash(lw) == hash(lw)
