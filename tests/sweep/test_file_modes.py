"""Sweep outputs get the mode the umask implies (0644 under umask 022), not mkstemp's 0600,
so that colleagues on a shared cluster can read them."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest
import xarray as xr

from chuteflow._files import atomic_target, atomic_write, umask_mode
from chuteflow.sweep import SweepConfig, parts_dir, run_sweep, write_dataset

from ._helpers import NU0, THETA


@pytest.fixture(params=[0o022, 0o077, 0o002])
def umask(request):
    old = os.umask(request.param)
    try:
        yield request.param
    finally:
        os.umask(old)


def _mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def test_atomic_files_follow_the_umask(tmp_path, umask):
    assert umask_mode() == 0o666 & ~umask
    atomic_write(tmp_path / "a.bin", lambda fh: fh.write(b"x"))
    with atomic_target(tmp_path / "b.nc") as tmp:
        xr.Dataset({"v": ("x", np.arange(3.0))}).to_netcdf(tmp, engine="h5netcdf")
    write_dataset(xr.Dataset({"v": ("x", np.arange(3.0))}), tmp_path / "c.nc")
    for name in ("a.bin", "b.nc", "c.nc"):
        assert _mode(tmp_path / name) == 0o666 & ~umask, name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin", "b.nc", "c.nc"]


def test_sweep_outputs_are_0644_under_umask_022(tmp_path):
    old = os.umask(0o022)
    try:
        cfg = SweepConfig(theta=THETA[:1], nu0=NU0[:2], roughness=0.05, metrics=("steady",))
        out = tmp_path / "d.nc"
        run_sweep(cfg, out=out, workers=1, keep_parts=True)
    finally:
        os.umask(old)
    assert _mode(out) == 0o644
    parts = list(parts_dir(out).iterdir())
    assert any(p.suffix == ".npz" for p in parts)
    assert any(p.name == "config.json" for p in parts)
    for p in parts:
        assert _mode(p) == 0o644, p.name
