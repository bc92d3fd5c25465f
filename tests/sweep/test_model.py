"""Sweeps carry the whole ChuteModel: the closures reach the computation, the hash, the NetCDF
attributes and the reloaded configuration (the bug: a Carnahan–Starling sweep reused
Lun–Savage results, and a 1D diagram silently computed with Lun–Savage).

Reference values are the steady solver's own (``solve_steady`` with the same model), so the
sweep must reproduce them to the steady solver's tolerance (rtol 1e-8, margin 10).
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from chuteflow.closures import CarnahanStarling, ChuteModel
from chuteflow.reduced import reduced_diagram
from chuteflow.reduced.diagram import reduced_diagram_config
from chuteflow.steady import solve_steady
from chuteflow.sweep import (
    ConfigMismatchError,
    PartStore,
    SweepConfig,
    load_sweep,
    resolve_model,
    run_sweep,
)

LS = ChuteModel()
CS = ChuteModel(radial="carnahan_starling")
GRID = {"theta": (16.0,), "nu0": (0.05, 0.08), "metrics": ("steady",), "markers": ()}


def test_config_holds_the_model():
    cfg = SweepConfig(**GRID, model=CS)
    assert cfg.model == CS
    assert cfg.radial == CarnahanStarling()
    assert cfg.roughness == 0.05
    # keyword convenience replaces fields of the model; the model stays the source of truth
    kw = SweepConfig(**GRID, radial="carnahan_starling")
    assert kw == cfg
    assert hash(kw) == hash(cfg)
    assert kw.digest() == cfg.digest()
    assert SweepConfig(**GRID, model=CS, roughness=0.1).model == ChuteModel(
        roughness=0.1, radial="carnahan_starling"
    )
    assert resolve_model(CS.to_dict()) == CS
    again = dataclasses.replace(cfg, chunk=1)
    assert again.model == CS
    assert again.chunk == 1
    assert dataclasses.replace(cfg) == cfg
    with pytest.raises(ValueError, match="unknown parameters"):
        SweepConfig(**GRID, roughnes=0.1)


def test_closures_change_hash_and_round_trip():
    a, b = SweepConfig(**GRID), SweepConfig(**GRID, model=CS)
    assert a != b
    assert hash(a) != hash(b)
    assert a.digest() != b.digest()
    assert a.to_dict()["model"] == LS.to_dict()
    back = SweepConfig.from_dict(json.loads(json.dumps(b.to_dict())))
    assert back == b
    assert back.model == CS
    assert back.digest() == b.digest()
    # the flat model keys of older files are read too
    old = {k: v for k, v in a.to_dict().items() if k != "model"}
    old.update(roughness=0.05, wall_loss=0.39, restitution=0.7, nu_max=0.6)
    assert SweepConfig.from_dict(old) == a
    g = SweepConfig.grid(shape=(2, 2), model=CS, metrics=("steady",))
    assert g.model == CS
    assert g.digest() != SweepConfig.grid(shape=(2, 2), metrics=("steady",)).digest()


def test_sweep_with_carnahan_starling(tmp_path):
    """Values differ from Lun–Savage and equal direct solves with Carnahan–Starling; the file
    records the model and loading restores it; parts of the other model are refused."""
    out = tmp_path / "cs.nc"
    cs = run_sweep(SweepConfig(**GRID, model=CS), out, workers=1)
    ls = run_sweep(SweepConfig(**GRID), workers=1)
    for j, nu0 in enumerate(GRID["nu0"]):
        ref = solve_steady(16.0, nu0, CS, min_thickness=0.0)
        assert cs["h"].values[0, j] == pytest.approx(ref.h, rel=1e-7)
        assert cs["rho_bar"].values[0, j] == pytest.approx(ref.rho_bar, rel=1e-7)
    # g0 differs by O(ν) at these densities: so do the flows (here by > 1 %)
    assert np.all(np.abs(cs["h"].values / ls["h"].values - 1) > 1e-2)
    back = load_sweep(out)
    assert back.attrs["radial"] == "carnahan_starling"
    assert back.attrs["model_key"] == CS.key()
    assert ls.attrs["radial"] == "lun_savage"
    assert SweepConfig.from_dataset(back).model == CS
    assert SweepConfig.from_dataset(back) == SweepConfig(**GRID, model=CS)
    PartStore(tmp_path / "parts.nc", SweepConfig(**GRID, model=CS))
    with pytest.raises(ConfigMismatchError, match="another model"):
        PartStore(tmp_path / "parts.nc", SweepConfig(**GRID))


def test_reduced_diagram_computes_with_the_model_given():
    grid = ((16.0,), (0.05, 0.08))
    cs = reduced_diagram(model=CS, grid=grid, workers=1)
    ls = reduced_diagram(grid=grid, workers=1)
    assert cs.attrs["radial"] == "carnahan_starling"
    assert ls.attrs["radial"] == "lun_savage"
    for name in ("h", "r1d_margin", "r1d_U"):
        assert np.all(np.abs(cs[name].values / ls[name].values - 1) > 1e-3), name
    ref = solve_steady(16.0, 0.08, CS, min_thickness=0.0)
    assert cs["h"].values[0, 1] == pytest.approx(ref.h, rel=1e-7)
    a = reduced_diagram_config(grid=grid, model=CS)
    b = reduced_diagram_config(grid=grid)
    assert a.model == CS
    assert a.digest() != b.digest()
    # the walk engine (no sweep) uses the model too
    walk = reduced_diagram(model=CS, grid=grid, engine="walk")
    assert walk.attrs["radial"] == "carnahan_starling"
    assert walk["h"].values[0, 1] == pytest.approx(ref.h, rel=1e-7)
