"""``chuteflow spatial`` and ``chuteflow absolute`` at the paper's P1 (θ = 16°, ν0(0) = 0.05)."""

import json
import math
import warnings

import pytest
from typer.testing import CliRunner

from chuteflow.cli import app, main

P1 = ["--theta", "16", "--nu0", "0.05"]

runner = CliRunner()


def _json(args):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = runner.invoke(app, args)
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_spatial_json_at_p1():
    """−Im k = 1.4745e-4 at ω = 0.02 (measured 1.474466e-4), checked independently by Gaster's
    relation Re α(k0)/c_g(k0) = 1.4724e-4 (0.14 % away; tests/spatial/test_spatial_branch.py);
    the command takes about 1 s."""
    out = _json(["spatial", *P1, "--omega", "0.02", "--json"])
    for key in ("omega", "k_re", "k_im", "spatial_growth", "group_velocity", "converged", "note"):
        assert key in out, key
    assert {"theta", "nu0", "roughness", "transport", "nu_top"} <= set(out)
    assert out["theta"] == 16
    assert out["nu0"] == 0.05
    assert out["nu_top"] == 1e-9
    assert out["omega"] == 0.02
    assert out["converged"] is True
    assert out["note"] == ""
    assert out["spatial_growth"] == pytest.approx(1.4745e-4, rel=1e-2)
    assert out["k_im"] == -out["spatial_growth"]
    assert out["spatial_growth"] == pytest.approx(out["gaster_growth"], rel=1e-2)
    # c_g ≈ 7.96 lies inside the growing packet (V−, V+) = (4.15, 9.00) of `absolute`
    assert 4.15 < out["group_velocity"] < 9.0


@pytest.mark.parametrize("omega", ["0", "-0.02", "nan"])
def test_spatial_bad_omega_is_one_line_exit_2(omega, capsys):
    """ω ≤ 0 (or not a number): one ``error:`` line on standard error, exit 2, before any solve."""
    code = main(["spatial", *P1, f"--omega={omega}", "--json"])
    err = capsys.readouterr()
    assert code == 2
    assert err.out == ""
    lines = err.err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("error:")
    assert "omega" in lines[0]


@pytest.mark.slow
def test_absolute_json_at_p1():
    """P1 is convective: the packet's edges V− = 4.15255, V+ = 9.00427 (measured; 5–20 s)."""
    out = _json(["absolute", *P1, "--json"])
    assert out["verdict"] == "convective"
    assert out["converged"] is True
    assert out["v_minus"] == pytest.approx(4.1525, rel=1e-4)
    assert out["v_plus"] == pytest.approx(9.004, rel=1e-3)
    assert out["v_minus"] < out["v_peak"] < out["v_plus"]
    assert out["absolute_growth"] is None or out["absolute_growth"] < 0
    assert math.isfinite(out["growth_peak"])
    assert out["growth_peak"] > 0
