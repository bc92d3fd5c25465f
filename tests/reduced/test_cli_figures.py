"""``chuteflow reduced`` / ``chuteflow simulate`` and the figures of the 1D model."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr
from typer.testing import CliRunner

from chuteflow.cli import app

runner = CliRunner()


def test_reduced_json_reports_the_family_and_the_state():
    res = runner.invoke(
        app, ["reduced", "--theta", "16", "--nu0", "0.12", "--json", "--nu0-min", "0.04", "--nu0-max", "0.2"]
    )
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["theta"] == 16.0
    assert d["roughness"] == 0.05
    assert d["accuracy"]["F"] <= 1e-4
    assert len(d["points"]) >= 8
    assert d["nu0_range"] == pytest.approx([0.04, 0.2])
    rhos = [p["rho0"] for p in d["points"]]
    assert rhos == sorted(rhos)
    st = d["state"]
    assert st["unstable"] is True
    assert st["short_wave_unstable"] is False
    assert st["L_c"] == pytest.approx(2 * math.pi / st["k_c"])
    assert st["phase_velocity"] == pytest.approx(st["dq0"])  # c = −Im α1
    # the paper's P1 (16°, 0.05) is on the family: every k grows there, k_c is "inf"
    p1 = min(d["points"], key=lambda p: abs(p["nu0"] - 0.05))
    if abs(p1["nu0"] - 0.05) < 0.01:
        assert p1["short_wave_unstable"] is True
        assert p1["k_c"] == "inf"


def test_functions_figure(rm16, tmp_path):
    from chuteflow.figures.reduced import plot_functions, save

    png = save(plot_functions(rm16, n=60), tmp_path / "f.png")
    assert png.stat().st_size > 10_000


def test_simulate_writes_netcdf_and_figure(tmp_path):
    nc, png = tmp_path / "run.nc", tmp_path / "run.png"
    res = runner.invoke(
        app,
        [
            "simulate",
            "--theta",
            "16",
            "--nu0",
            "0.12",
            "--length",
            "40",
            "--time",
            "30",
            "--cells",
            "128",
            "--out",
            str(nc),
            "--plot",
            str(png),
            "--json",
            "--nu0-min",
            "0.04",
            "--nu0-max",
            "0.2",
        ],
    )
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout.strip().splitlines()[-1])
    assert s["status"] == "completed"
    assert s["n_cells"] == 128
    assert s["t_end"] == 30.0
    assert s["mass_drift"] < 1e-13
    ds = xr.load_dataset(nc)
    assert ds["rho"].shape == (200, 128)
    assert float(ds.attrs["rho0"]) == pytest.approx(s["rho0"])
    assert png.stat().st_size > 10_000


def test_simulate_bad_input_is_one_line_error():
    res = runner.invoke(app, ["simulate", "--theta", "16", "--nu0", "0.12", "--length", "-5"])
    assert res.exit_code == 2
    assert "length" in res.output
    assert "Traceback" not in res.output


def test_phase_diagram_figure_with_full_model(tmp_path):
    from chuteflow.figures.reduced import plot_phase_diagrams, save

    th, nu = np.linspace(14, 16, 4), np.linspace(0.05, 0.2, 5)
    T, N = np.meshgrid(th, nu, indexing="ij")
    h = 30 * N / (T - 13)  # any smooth one-to-one map will do for drawing
    nb = N / 3
    base = {
        "h": (("theta", "nu0"), h),
        "nu_mean": (("theta", "nu0"), nb),
        "status": (("theta", "nu0"), np.zeros(T.shape, dtype=np.int8)),
        "monotonic": (("theta", "nu0"), (N < 0.12).astype(np.int8)),
    }
    red = xr.Dataset(
        {
            **base,
            "r1d_unstable": (("theta", "nu0"), (T > 14.5).astype(np.int8)),
            "r1d_short_wave": (("theta", "nu0"), (N < 0.07).astype(np.int8)),
        },
        coords={"theta": th, "nu0": nu},
        attrs={"roughness": 0.05},
    )
    full = xr.Dataset(
        {**base, "unstable": (("theta", "nu0"), (T > 15.0).astype(np.int8))},
        coords={"theta": th, "nu0": nu},
        attrs={"roughness": 0.05},
    )
    from chuteflow.reduced import agreement

    a = agreement(red, full, h_min=0)
    assert a["compared"] == 20
    assert a["only_1d_unstable"] == 5
    png = save(plot_phase_diagrams([red], [full], agreement=[a]), tmp_path / "pd.png")
    assert png.stat().st_size > 10_000


def test_reduced_at_the_lowest_floor_density_of_the_family_answers():
    # paper point P4 (θ = 14°, ν0(0) = 0.05) is the lowest flow of the 14° family (below it
    # h < 1): the state there is a knot and was answered by scipy's raw "f(a) and f(b) must
    # have different signs". A family starting at 0.05 reproduces it cheaply.
    res = runner.invoke(
        app, ["reduced", "--theta", "14", "--nu0", "0.05", "--json", "--nu0-min", "0.05", "--nu0-max", "0.1"]
    )
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["nu0_range"][0] == 0.05
    st = d["state"]
    assert st["nu0"] == 0.05
    assert st["rho0"] == d["points"][0]["rho0"]
    # a wave about the end of the family has nowhere to go: one line naming nu0 and the range
    res = runner.invoke(
        app,
        [
            "simulate",
            "--theta",
            "14",
            "--nu0",
            "0.05",
            "--length",
            "300",
            "--nu0-min",
            "0.05",
            "--nu0-max",
            "0.1",
        ],
    )
    assert res.exit_code == 2
    assert "nu0 = 0.05" in res.output
    assert "[0.05, 0.1]" in res.output
    assert "Traceback" not in res.output
    assert "f(a) and f(b)" not in res.output
