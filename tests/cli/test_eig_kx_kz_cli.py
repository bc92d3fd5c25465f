"""``chuteflow eig --kx --kz``, ``mode --kx --kz --plot`` and ``transverse --plane-plot``
(issue 10) at P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from chuteflow.cli import app
from chuteflow.cli.stability import EIG_KEYS

runner = CliRunner()
P1 = ["--theta", "16", "--nu0", "0.05"]


def _json(r):
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_eig_kx_kz_transverse_mode():
    """The growing real transverse mode α = 6.1655e-5 at (0, 0.002) (the dense scan of
    tests/stability/test_transverse.py; relative 1e-4 as there)."""
    out = _json(runner.invoke(app, ["eig", *P1, "--kx", "0", "--kz", "0.002", "--json"]))
    assert set(EIG_KEYS) <= set(out)
    assert out["alpha_re"] == pytest.approx(6.1655e-5, rel=1e-4)
    assert out["kx"] == 0.0
    assert out["k"] == 0.0
    assert out["kz"] == 0.002
    assert out["physical"]
    assert out["stationary"]
    assert out["unstable"]


def test_eig_k_is_kx_with_kz_zero():
    a = _json(runner.invoke(app, ["eig", *P1, "--k", "0.002", "--json"]))
    b = _json(runner.invoke(app, ["eig", *P1, "--kx", "0.002", "--json"]))
    assert a["alpha_re"] == b["alpha_re"]
    assert a["alpha_im"] == b["alpha_im"]
    assert a["kz"] == 0.0
    assert a["kx"] == 0.002


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--k", "0.002", "--kx", "0.002"], "--k and --kx"),
        (["--kx", "0", "--kz", "0"], "kx = 0"),
        (["--kx", "-1", "--kz", "0.1"], "kx = -1"),
        ([], "--k K"),
    ],
)
def test_eig_bad_wavevector(args, needle):
    r = runner.invoke(app, ["eig", *P1, *args])
    assert r.exit_code == 2
    assert needle in r.output


def test_mode_cross_section_plot(tmp_path):
    png = tmp_path / "cs.png"
    out = _json(runner.invoke(app, ["mode", *P1, "--kx", "0", "--kz", "0.002", "--plot", str(png), "--json"]))
    assert png.stat().st_size > 10_000
    assert out["plot"] == str(png)
    assert out["alpha_re"] == pytest.approx(6.1655e-5, rel=1e-4)


def test_eig3d_is_hidden():
    r = runner.invoke(app, ["--help"])
    assert "eig3d" not in r.output


@pytest.mark.slow
def test_transverse_plane_plot(tmp_path):
    """Re α over (k_x, k_z) ∈ [0, 0.004]²: the maximum lies on the longitudinal axis at
    k_x = 0.002 (1.179e-3, the 2D branch), not transverse (6.2e-5) nor oblique (9.4e-4)."""
    png = tmp_path / "plane.png"
    args = ["transverse", *P1, "--json", "--plane-plot", str(png), "--plane-max", "0.004", "--plane-num", "3"]
    out = _json(runner.invoke(app, args))
    assert png.stat().st_size > 10_000
    assert out["plane"]["direction"] == "longitudinal"
    assert out["plane"]["kx_max"] == 0.002
    assert out["plane"]["growth_max"] == pytest.approx(1.178967e-3, rel=1e-5)
