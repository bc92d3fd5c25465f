"""``chuteflow transverse`` and ``chuteflow eig3d`` (issue 10) at P1 (θ = 16°, ν0(0) = 0.05)."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from chuteflow.cli import app
from chuteflow.cli.transverse import EIG3D_KEYS, TRANSVERSE_KEYS

runner = CliRunner()


def test_eig3d_json():
    r = runner.invoke(
        app, ["eig3d", "--theta", "16", "--nu0", "0.05", "--kx", "0", "--kz", "0.002", "--json"]
    )
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert set(EIG3D_KEYS) <= set(out)
    assert abs(out["alpha_re"] - 6.1655e-5) < 1e-8  # the growing real mode (issue 10)
    assert out["alpha_im"] == 0.0
    assert out["physical"]
    assert out["stationary"]


def test_transverse_json_and_plot(tmp_path):
    png = tmp_path / "t.png"
    r = runner.invoke(
        app,
        [
            "transverse",
            "--theta",
            "16",
            "--nu0",
            "0.05",
            "--kz-max",
            "0.003",
            "--num",
            "4",
            "--json",
            "--plot",
            str(png),
        ],
    )
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert set(TRANSVERSE_KEYS) <= set(out)
    assert out["unstable"]
    assert out["stationary"]
    assert abs(out["alpha2_z"] - 75.844) < 2e-3
    assert png.stat().st_size > 0


def test_transverse_bad_range_is_a_user_error():
    r = runner.invoke(app, ["transverse", "--theta", "16", "--nu0", "0.05", "--kz-max", "-1"])
    assert r.exit_code == 2


def test_diagram_with_transverse_metric_and_winner_plot(tmp_path):
    """``chuteflow diagram --metrics ...,transverse`` on P1 and ν0 = 0.06 next to it, then the
    ``winner`` figure: P1 (θ = 16°, ν0 = 0.05) is unstable in both directions (class 3)."""
    nc = tmp_path / "w.nc"
    r = runner.invoke(
        app,
        [
            "diagram",
            "--grid",
            "1x2",
            "--theta-range",
            "16",
            "16",
            "--nu0-range",
            "0.05",
            "0.06",
            "--no-markers",
            "--workers",
            "1",
            "--no-progress",
            "--metrics",
            "steady,kinematic,longwave,transverse",
            "--out",
            str(nc),
        ],
    )
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["winner", str(nc), "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["both"] >= 1
    assert sum(out[k] for k in ("stable", "longitudinal only", "transverse only", "both")) == 2


def test_winner_needs_the_metric(tmp_path):
    r = runner.invoke(app, ["winner", str(tmp_path / "none.nc")])
    assert r.exit_code == 2
