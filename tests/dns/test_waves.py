"""``chuteflow.dns.map_waves``: the same map in this process, in a process pool and on Dask.

Tiny runs (the linear phase of noise at nx = 5, N = 24, 10 steps): what is checked is the
driver — every flow run once, the rows in the order of the points, the same numbers on every
backend (each run is deterministic: same seed, same steps), and a finished map read back.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr

from chuteflow.dns import WaveMapSettings, map_waves
from chuteflow.dns.discretisation import padded_points
from chuteflow.dns.waves import WAVE_KEYS
from chuteflow.errors import ParameterError

POINTS = [(16.0, 0.05), (16.5, 0.06)]
SETTINGS = WaveMapSettings(length=1000.0, time=40.0, dt=4.0, modes=2, n=24, amplitude=1e-4)


def _same(a, b):
    for k in WAVE_KEYS:
        if k == "wall_time":
            continue
        va, vb = a[k].values, b[k].values
        if va.dtype.kind in "OUS":
            assert list(va) == list(vb), k
        else:
            np.testing.assert_array_equal(va, vb, err_msg=k)
    np.testing.assert_array_equal(a["shape"].values, b["shape"].values)


@pytest.fixture(scope="module")
def serial():
    return map_waves(POINTS, SETTINGS, workers=1)


def test_rows_follow_the_points(serial, tmp_path):
    assert list(serial["theta"].values) == [16.0, 16.5]
    # the map is written as NetCDF with the default settings (max_modes, max_n left at None:
    # `reproduce --full` failed on it) and read back the same
    serial.to_netcdf(tmp_path / "map.nc", engine="h5netcdf")
    back = xr.load_dataset(tmp_path / "map.nc", engine="h5netcdf")
    assert "setting_max_modes" not in back.attrs
    assert back.attrs["setting_n"] == 24
    assert list(serial["nu0"].values) == [0.05, 0.06]
    assert set(serial["verdict"].values) <= {"growing", "decaying"}  # a 1e-4 wave after 40 time units
    assert np.all(np.abs(serial["mass_drift"].values) < 1e-12)


def test_dask_local_cluster_equals_the_serial_map(serial, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        got = map_waves(POINTS, SETTINGS, client=client, out_dir=tmp_path)
    _same(got, serial)
    assert len(list(tmp_path.glob("*.nc"))) == 2
    again = map_waves(POINTS, SETTINGS, out_dir=tmp_path)  # read back, not rerun
    _same(again, serial)
    np.testing.assert_array_equal(again["wall_time"].values, got["wall_time"].values)


def test_dask_needs_one_of_client_and_scheduler():
    with pytest.raises(ParameterError, match="not both"):
        map_waves(POINTS, SETTINGS, client=object(), scheduler="tcp://127.0.0.1:1")


def test_wall_limit_pauses_each_flow_and_the_same_call_continues(serial, tmp_path):
    """map_waves(..., wall_limit=) pauses a flow still running after that much wall time
    (here after its first step): the row says so (status "paused at t = 4: …", the wave so
    far judged, not "stopped"), the checkpoint is kept, and calls again continue to the
    uninterrupted map's numbers. The output folder need not exist (the checkpoint is written
    there before the NetCDF file)."""
    out = tmp_path / "map" / "waves"
    first = map_waves(POINTS[:1], SETTINGS, out_dir=out, wall_limit=1e-9)
    assert str(first["status"].values[0]).startswith("paused at t = 4:")
    assert first["verdict"].values[0] in ("growing", "decaying")
    assert len(list(out.glob("*.checkpoint.npz"))) == 1
    done = map_waves(POINTS[:1], SETTINGS, out_dir=out)  # no limit: runs to the end
    assert done["status"].values[0] == "ok"
    assert not list(out.glob("*.checkpoint.npz"))
    for k in ("rho_min_rel", "rho_max_rel", "mass_drift"):
        np.testing.assert_allclose(done[k].values, serial[k].values[:1], rtol=1e-9, atol=1e-15, err_msg=k)
    with pytest.raises(ParameterError, match="wall_limit"):
        map_waves(POINTS, SETTINGS, wall_limit=-1.0)


def test_each_flow_may_have_its_own_period(serial, tmp_path):
    """Points (θ, ν0, L): each flow runs at its own period (here the second at L = 1500); a
    flow at the settings' L is the same run as before, the file of another L is named by it,
    a map run again reads both back, and a new L for a flow is a new run, not the old file."""
    pts = [(*POINTS[0], 1000.0), (*POINTS[1], 1500.0)]
    got = map_waves(pts, SETTINGS, out_dir=tmp_path)
    assert list(got["length"].values) == [1000.0, 1500.0]
    for k in ("rho_min_rel", "rho_max_rel", "growth_rate_linear"):
        assert got[k].values[0] == serial[k].values[0], k
    # k = 2π/1500 is another wavenumber: another linear growth rate
    assert got["growth_rate_linear"].values[1] != serial["growth_rate_linear"].values[1]
    names = sorted(p.name for p in tmp_path.glob("*.nc"))
    assert names == ["theta16.5_nu00.06_L1500.nc", "theta16_nu00.05.nc"]
    again = map_waves(pts, SETTINGS, out_dir=tmp_path)
    np.testing.assert_array_equal(again["wall_time"].values, got["wall_time"].values)
    other = map_waves([(*POINTS[1], 1200.0)], SETTINGS, out_dir=tmp_path)
    assert other["length"].values[0] == 1200.0
    assert other["growth_rate_linear"].values[0] != got["growth_rate_linear"].values[1]
    assert got["phase"].values[0] == 0.0
    assert got["phase"].values[-1] < 1.0
    for bad, match in (([(16.0,)], "theta, nu0"), ([(16.0, 0.05, -1.0)], "length")):
        with pytest.raises(ParameterError, match=match):
            map_waves(bad, SETTINGS)


def test_the_map_lets_each_grid_follow_its_wave(monkeypatch):
    """WaveMapSettings(max_modes=): each run refines its x grid where its tail rises towards
    the tolerance (noise of 1e-2 on M = 2: the tails reach 1e-3 against a tolerance of 2e-3,
    refined at a quarter of it); the row says the nx it ended with and the shapes lie on
    that grid (15 padded points for M = 4, against 8 for M = 2: :func:`padded_points`). The
    map's plumbing only: these 30 steps are all the noise's transient, which a run from noise
    waits out before it refines (test_trackers.py), so here the transient counts as over from
    the start."""
    import chuteflow.trackers

    monkeypatch.setattr(chuteflow.trackers, "_transient_end", lambda v: 0)
    base = dataclasses.replace(SETTINGS, amplitude=1e-2, resolution_tol=2e-3, time=120.0)
    kept = map_waves(POINTS, base)
    got = map_waves(POINTS, dataclasses.replace(base, max_modes=8))
    assert list(kept["nx"].values) == [5, 5]
    assert kept["shape"].shape == (2, padded_points(2)) == (2, 8)
    assert list(got["nx"].values) == [9, 9]
    assert got["shape"].shape == (2, padded_points(4)) == (2, 15)
    # the same waves, one grid finer: their size agrees to the coarse grid's tail (1e-3)
    np.testing.assert_allclose(got["rho_max_rel"].values, kept["rho_max_rel"].values, rtol=0.05)
    with pytest.raises(ParameterError, match="max_modes"):
        WaveMapSettings(modes=4, max_modes=2)


def test_a_map_with_x_map_reruns_what_was_run_without(serial, tmp_path):
    """WaveMapSettings(x_map=True): its repr is the same as without (so that the runs of a map
    made before x_map existed are read back), the runs' ``x_map`` attribute tells them apart: a
    flow run without the map is rerun with it (the wall time differs) and read back after; the
    setting is stored as 0/1 (NetCDF has no bool). A smooth 1e-4 wave on nx = 5 is never
    mapped (x_map_beta 1), so the numbers are the serial map's."""
    mapped = dataclasses.replace(SETTINGS, x_map=True)
    assert repr(mapped) == repr(SETTINGS)
    first = map_waves(POINTS[:1], SETTINGS, out_dir=tmp_path)
    got = map_waves(POINTS[:1], mapped, out_dir=tmp_path)
    assert got["wall_time"].values[0] != first["wall_time"].values[0]  # rerun, not read back
    again = map_waves(POINTS[:1], mapped, out_dir=tmp_path)
    np.testing.assert_array_equal(again["wall_time"].values, got["wall_time"].values)
    assert got.attrs["setting_x_map"] == 1
    for k in ("rho_min_rel", "rho_max_rel", "mass_drift"):
        np.testing.assert_allclose(got[k].values, serial[k].values[:1], rtol=1e-9, atol=1e-15)
    (one,) = tmp_path.glob("*.nc")
    assert xr.load_dataset(one, engine="h5netcdf").attrs["x_map_beta"] == 1.0
