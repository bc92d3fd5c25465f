"""Sweep engine: values, per-point status, persistence, resume after SIGKILL, config hashing."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from chuteflow.errors import ParameterError
from chuteflow.papers.mitarai2004 import markers as paper_markers
from chuteflow.steady import solve_steady
from chuteflow.sweep import (
    STATUS,
    ConfigMismatchError,
    PartStore,
    Sweep,
    SweepConfig,
    load_sweep,
    parse_grid,
    parts_dir,
    point_function,
    run_sweep,
)

from ._helpers import NU0, THETA

REPO = Path(__file__).resolve().parents[2]


def _cfg(**kw):
    kw.setdefault("metrics", ("steady", "kinematic"))
    return SweepConfig(theta=THETA, nu0=NU0[:3], roughness=0.05, chunk=2, **kw)


def test_values_equal_direct_solves(tmp_path):
    """Every grid point equals an independent cold-start solve (continuation only changes
    the Newton start): h, ν̄, ρ̄0, Q0 to the steady solver's own tolerance (rtol 1e-8, a
    margin of 10 for the round-off of the converged Newton iterate)."""
    cfg = _cfg()
    ds = run_sweep(cfg, workers=1)
    assert (ds["status"].values == STATUS["ok"]).all()
    for i, th in enumerate(cfg.theta):
        for j, nu in enumerate(cfg.nu0):
            f = solve_steady(th, nu, cfg.model, min_thickness=0.0)
            for name in ("h", "nu_mean", "rho_bar", "Q", "u_floor", "T_floor"):
                assert ds[name].values[i, j] == pytest.approx(getattr(f, name), rel=1e-7)
            assert ds["monotonic"].values[i, j] == int(f.monotonic)
    # U = Q0/ρ̄0 and dU/dρ̄0 = (dQ0/dρ̄0 − U)/ρ̄0: identities of the definitions
    np.testing.assert_allclose(ds["U"], ds["Q"] / ds["rho_bar"], rtol=1e-14)
    np.testing.assert_allclose(ds["dU_drho"], (ds["dQ_drho"] - ds["U"]) / ds["rho_bar"], rtol=1e-12)
    # reference value of the project (θ = 16°, ν0 = 0.05): dQ0/dρ̄0 = 4.1524 (eq:dqdh)
    assert ds["dQ_drho"].sel(theta=16.0, nu0=0.05).item() == pytest.approx(4.1524, rel=1e-4)


def test_point_status_and_messages():
    """No steady flow, a metric that does not converge, one that crashes, and one returning
    an undeclared variable each become the point's status, with a message; the other points
    are unaffected."""
    metrics = (
        "steady",
        {"name": "test_faulty", "options": {"diverge_at": 0.05, "crash_at": 0.06, "undeclared_at": 0.07}},
    )
    # θ = 13°, ν0 = 0.1 has h ≈ 2.3: with min_thickness = 3 it is rejected as too thin
    cfg = SweepConfig(theta=(13.0,), nu0=(0.1,), metrics=metrics, min_thickness=3.0)
    ds = run_sweep(cfg, workers=1)
    assert ds["status"].values[0, 0] == STATUS["no_steady_flow"]
    assert ds["message"].values[0, 0].startswith("steady: no steady flow")
    assert np.isnan(ds["h"].values[0, 0])
    cfg = SweepConfig(theta=(16.0,), nu0=(0.04, 0.05, 0.06, 0.07), metrics=metrics)
    ds = run_sweep(cfg, workers=1)
    st, msg = ds["status"].values[0], ds["message"].values[0]
    assert list(st) == [STATUS["ok"], STATUS["not_converged"], STATUS["error"], STATUS["error"]]
    assert msg[0] == ""
    assert "test_faulty" in msg[1]
    assert "on purpose" in msg[1]
    assert "ZeroDivisionError" in msg[2]
    assert "undeclared" in msg[3]
    assert "not_declared" in msg[3]
    # the steady quantities are kept where only a later metric failed
    assert np.isfinite(ds["h"].values[0]).all()
    assert ds["twice_h"].values[0, 0] == pytest.approx(2 * ds["h"].values[0, 0], rel=1e-15)
    assert np.isnan(ds["twice_h"].values[0, 1:]).all()


def test_netcdf_round_trip_with_attrs(tmp_path):
    out = tmp_path / "s.nc"
    cfg = _cfg(markers=(("P1", 16.0, 0.05),))
    ds = run_sweep(cfg, out)
    assert out.exists()
    assert not parts_dir(out).exists()
    back = load_sweep(out)
    xr.testing.assert_identical(ds, back)
    from chuteflow import __version__

    a = back.attrs
    assert a["chuteflow_version"] == __version__
    assert a["config_digest"] == cfg.digest()
    for k in ("roughness", "wall_loss", "restitution", "nu_max", "nu_top", "chunk"):
        assert a[k] == getattr(cfg, k)
    assert back["h"].attrs["units"] == "sigma"
    assert back["theta"].attrs["units"] == "degree"
    assert back["status"].attrs["flag_meanings"] == "ok no_steady_flow not_converged error"
    assert str(back["marker"].values[0]) == "P1"
    assert back["marker_h"].values[0] == pytest.approx(back["h"].sel(theta=16, nu0=0.05).item(), rel=1e-7)
    assert SweepConfig.from_dict(__import__("json").loads(a["config_json"])) == cfg
    # same command again: the final file is returned, nothing is computed
    sw = Sweep(cfg, out)
    again = sw.run(workers=1)
    assert sw.stats.computed == 0
    xr.testing.assert_identical(again, back)


def test_config_mismatch_refused_then_recomputed(tmp_path):
    out = tmp_path / "s.nc"
    a = _cfg()
    b = _cfg(nu_top=1e-8)
    assert a.digest() != b.digest()
    run_sweep(a, out, workers=1)
    with pytest.raises(ConfigMismatchError, match="different sweep"):
        run_sweep(b, out, workers=1)
    # parts of another configuration are refused too
    out2 = tmp_path / "t.nc"
    PartStore(out2, a)
    with pytest.raises(ConfigMismatchError, match="partial results"):
        run_sweep(b, out2, workers=1)
    # --fresh discards them and computes b from scratch
    got = run_sweep(b, out, workers=1, fresh=True)
    xr.testing.assert_identical(got, run_sweep(b, workers=1))
    assert load_sweep(out).attrs["config_digest"] == b.digest()


def test_foreign_part_is_ignored(tmp_path):
    """A part file whose stored digest is not this configuration's is recomputed."""
    out = tmp_path / "s.nc"
    cfg = _cfg()
    store = PartStore(out, cfg)
    sw = Sweep(cfg, out, keep_parts=True)
    full = sw.run(workers=1)
    key = cfg.tasks()[0].key
    res = store.read(key)
    res.digest = "0" * 64
    res.values["h"][:] = -1.0
    store.write(res)
    out.unlink()
    sw = Sweep(cfg, out, keep_parts=True)
    again = sw.run(workers=1)
    assert sw.stats.computed == 1
    assert sw.stats.reused == len(cfg.tasks()) - 1
    xr.testing.assert_identical(again, full)


_KILL_SCRIPT = textwrap.dedent("""
    import sys
    sys.path.insert(0, {src!r}); sys.path.insert(0, {repo!r})
    import tests.sweep._helpers as H
    from chuteflow.sweep import SweepConfig, Sweep
    cfg = SweepConfig(**{cfg!r})
    Sweep(cfg, {out!r}).run(workers=2)
""")


def _kill_config():
    return dict(
        theta=THETA,
        nu0=NU0,
        roughness=0.05,
        chunk=2,
        metrics=({"name": "test_slow", "options": {"seconds": 0.2}},),
    )


def test_resume_after_sigkill_equals_uninterrupted(tmp_path):
    """Kill a real sweep (two worker processes) with SIGKILL mid-run, run it again: the
    finished tasks are not recomputed and the final file equals an uninterrupted run's."""
    out = tmp_path / "killed.nc"
    kw = _kill_config()
    script = _KILL_SCRIPT.format(src=str(REPO / "src"), repo=str(REPO), cfg=kw, out=str(out))
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(REPO / "src"))
    proc = subprocess.Popen(
        [sys.executable, "-c", script],
        env=env,
        start_new_session=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    parts = parts_dir(out)
    ntasks = len(SweepConfig(**kw).tasks())
    t0 = time.monotonic()
    try:
        while time.monotonic() - t0 < 60:
            done = [p for p in parts.glob("*.npz") if not p.name.startswith(".")] if parts.exists() else []
            if len(done) >= 2 or proc.poll() is not None:
                break
            time.sleep(0.01)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its workers
        proc.wait()
    err = proc.stderr.read().decode()
    assert proc.returncode == -signal.SIGKILL, err
    assert not out.exists()
    saved = {p.name: p.stat().st_mtime_ns for p in parts.glob("*.npz")}
    assert 2 <= len(saved) < ntasks, f"kill not mid-run: {len(saved)} of {ntasks} parts"

    cfg = SweepConfig(**kw)
    sw = Sweep(cfg, out, keep_parts=True)
    resumed = sw.run(workers=2)
    assert sw.stats.reused == len(saved)
    assert sw.stats.computed == ntasks - len(saved)
    for name, mtime in saved.items():  # finished parts untouched
        assert (parts / name).stat().st_mtime_ns == mtime

    ref_out = tmp_path / "reference.nc"
    run_sweep(cfg, ref_out, workers=2)
    xr.testing.assert_identical(load_sweep(out), load_sweep(ref_out))
    xr.testing.assert_identical(resumed, load_sweep(ref_out))


@pytest.mark.slow
def test_ctrl_c_then_resume(tmp_path):
    """SIGINT (Ctrl-C) to the process group: the CLI exits 130, keeps the finished parts,
    and the same command completes the sweep."""
    out = tmp_path / "c.nc"
    args = [
        sys.executable,
        "-m",
        "chuteflow",
        "diagram",
        "--grid",
        "2x6",
        "--theta-range",
        "15",
        "16",
        "--nu0-range",
        "0.04",
        "0.09",
        "--metrics",
        "steady,kinematic",
        "--chunk",
        "1",
        "--out",
        str(out),
        "-j",
        "2",
        "--no-progress",
    ]
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(REPO / "src"))
    proc = subprocess.Popen(
        args, env=env, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    parts = parts_dir(out)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60 and proc.poll() is None:
        if parts.exists() and len(list(parts.glob("t*.npz"))) >= 2:
            break
        time.sleep(0.005)
    os.killpg(proc.pid, signal.SIGINT)
    proc.wait(timeout=60)
    err = proc.stderr.read().decode()
    if proc.returncode == 0:
        pytest.skip("the sweep finished before SIGINT arrived")
    assert proc.returncode == 130, err
    assert "run the same command again" in err
    assert not out.exists()
    assert parts.exists()
    done = subprocess.run(args, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert out.exists()
    assert not parts.exists()


def test_config_validation():
    with pytest.raises(ParameterError, match="theta"):
        SweepConfig(theta=(16.0, 15.0), nu0=(0.05,))
    with pytest.raises(ParameterError, match="nu0"):
        SweepConfig(theta=(16.0,), nu0=(0.05, 0.7))
    with pytest.raises(ParameterError, match="roughness"):
        SweepConfig(theta=(16.0,), nu0=(0.05,), roughness=-1.0)
    with pytest.raises(ParameterError, match="chunk"):
        SweepConfig(theta=(16.0,), nu0=(0.05,), chunk=0)
    with pytest.raises(ParameterError, match="unknown point function"):
        SweepConfig(theta=(16.0,), nu0=(0.05,), metrics=("nope",))
    with pytest.raises(ParameterError, match="needs"):
        SweepConfig(theta=(16.0,), nu0=(0.05,), metrics=("kinematic",))
    with pytest.raises(ParameterError, match="unknown option"):
        point_function({"name": "longwave", "options": {"bogus": 1}})
    with pytest.raises(ParameterError, match="grid"):
        parse_grid("60by60")
    with pytest.raises(ParameterError, match="markers"):
        SweepConfig(theta=(16.0,), nu0=(0.05,), markers=(("P", 100.0, 0.05),))
    with pytest.raises(ParameterError, match="workers"):
        run_sweep(_cfg(), workers=0)
    assert parse_grid("60x40") == (60, 40)


def test_tasks_cover_grid_once_and_hash_is_stable():
    # the paper's points are passed explicitly (SweepConfig.grid adds none by default)
    cfg = SweepConfig.grid(0.05, shape=(3, 7), chunk=3, markers=paper_markers(0.05))
    cover = np.zeros(cfg.shape, int)
    for t in cfg.tasks():
        if t.i >= 0:
            cover[t.i, t.j0 : t.j1] += 1
    assert (cover == 1).all()
    assert max(t.size for t in cfg.tasks() if t.i >= 0) <= 3
    assert [t for t in cfg.tasks() if t.i < 0][0].size == 5  # P1–P5 for φ = 0.05
    assert SweepConfig.grid(0.05, shape=(3, 7), chunk=3, markers=paper_markers(0.05)).digest() == cfg.digest()
    assert SweepConfig.grid(0.05, shape=(3, 7), chunk=4, markers=paper_markers(0.05)).digest() != cfg.digest()


def test_steady_family_statuses_map_to_point_status(monkeypatch):
    """The steady flows of a task come from steady_row (continuation in ν0, the solves of
    steady_family); its statuses become the points' status, its messages their message:
    no_steady_flow and thin → no steady flow, not_converged → not_converged, unreached →
    not_converged 'not attempted'."""
    import types

    import chuteflow.sweep.runner as runner

    nus = (0.04, 0.05, 0.06, 0.07, 0.08)
    fam_status = ["unreached", "no_steady_flow", "ok", "thin", "not_converged"]
    seen = {}

    def fake(theta, nu0_values, model, **kw):
        seen.update(kw, theta=theta, nus=list(nu0_values))
        return [(s, types.SimpleNamespace(h=1.5) if s == "ok" else None, f"why {s}") for s in fam_status]

    monkeypatch.setattr(runner, "steady_row", fake)
    cfg = SweepConfig(
        theta=(16.0,), nu0=nus, metrics=({"name": "test_faulty"},), min_thickness=0.5, nu_top=1e-10
    )
    ds = run_sweep(cfg, workers=1)
    assert seen["nus"] == list(nus)
    assert seen["theta"] == 16.0
    assert seen["min_thickness"] == 0.5
    assert seen["nu_top"] == 1e-10
    st, msg = ds["status"].values[0], ds["message"].values[0]
    assert list(st) == [
        STATUS["not_converged"],
        STATUS["no_steady_flow"],
        STATUS["ok"],
        STATUS["no_steady_flow"],
        STATUS["not_converged"],
    ]
    assert msg[0] == "steady: not attempted: why unreached"
    assert msg[1] == "steady: why no_steady_flow"
    assert msg[2] == ""
    assert ds["twice_h"].values[0, 2] == 3.0
    assert np.isnan(ds["twice_h"].values[0, [0, 1, 3, 4]]).all()


def test_non_critical_metric_failure_keeps_status():
    """A cross-check metric (critical = False) that raises leaves its variables missing and
    the point ok; a point function's notes go to the message."""
    from chuteflow.sweep import PointFunction, Variable, register_point_function

    @register_point_function
    class Check(PointFunction):
        name = "test_check"
        critical = False
        variables = (Variable("checked", "1", "test"),)

        def compute(self, flow, point):
            if point.j == 0:
                raise ValueError("test: check failed")
            point.note("test: a remark")
            return {"checked": 1.0}

    cfg = SweepConfig(theta=(16.0,), nu0=(0.05, 0.06), metrics=("steady", "test_check"))
    ds = run_sweep(cfg, workers=1)
    assert list(ds["status"].values[0]) == [STATUS["ok"], STATUS["ok"]]
    assert np.isnan(ds["checked"].values[0, 0])
    assert ds["checked"].values[0, 1] == 1.0
    assert "test: check failed" in ds["message"].values[0, 0]
    assert ds["message"].values[0, 1] == "test: a remark"
