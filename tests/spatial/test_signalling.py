"""The signalling problem in physical units (:func:`chuteflow.spatial.signalling`) at the
paper's P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05): the unit conversion against its analytic
identities, one physics number against :func:`~chuteflow.spatial.spatial_point`, bad input,
and the CLI ``chuteflow signalling``."""

import json
import math
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from chuteflow.cli import app, main
from chuteflow.closures import ChuteModel
from chuteflow.errors import ParameterError
from chuteflow.spatial import SignallingResult, signalling, spatial_point
from chuteflow.steady import solve_steady

P1 = ["--theta", "16", "--nu0", "0.05"]
SIGMA, X, G = 1e-3, 2.0, 9.81  # 1 mm beads on a 2 m chute
F = (0.1, 0.27, 0.5)  # Hz


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))


@pytest.fixture(scope="module")
def res(p1):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return signalling(p1, grain_diameter=SIGMA, chute_length=X, g=G, frequencies=F)


def test_units_are_the_papers(res):
    """The paper's scaling (§2): length σ, time √(σ/g). So f = ω̂ √(g/σ)/(2π),
    −Im k = −Im k̂/σ and the gain is exp(−Im k̂ X/σ) — exact identities (round-off only)."""
    assert isinstance(res, SignallingResult)
    assert res.converged, res.note
    t = math.sqrt(SIGMA / G)
    assert res.time_unit == pytest.approx(t, rel=1e-15)
    np.testing.assert_allclose(res.frequency, F, rtol=1e-13)
    np.testing.assert_allclose(res.omega, 2 * np.pi * np.array(F) * t, rtol=1e-13)
    np.testing.assert_allclose(res.frequency, res.omega / (2 * np.pi) * math.sqrt(G / SIGMA), rtol=1e-13)
    g_hat = res.spatial_growth * SIGMA  # back to 1/σ
    np.testing.assert_allclose(res.amplification, np.exp(g_hat * X / SIGMA), rtol=1e-13)
    np.testing.assert_allclose(res.amplification, np.exp(res.spatial_growth * X), rtol=1e-13)
    assert res.length_to_threshold == pytest.approx(math.log(10.0) / res.spatial_growth_max, rel=1e-13)
    assert res.frequency_max == pytest.approx(res.omega_max / (2 * math.pi * t), rel=1e-13)
    assert res.frequency_cutoff == pytest.approx(res.omega_c / (2 * math.pi * t), rel=1e-13)


def test_scaling_with_the_grain_size(p1):
    """Halving σ (same dimensionless flow): the frequencies scale as σ^(−1/2), the growth per
    metre as 1/σ — so the same ω̂ is asked for with f·√2 and grows twice as fast per metre."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        a = signalling(p1, grain_diameter=SIGMA, chute_length=X, frequencies=[0.27])
        b = signalling(p1, grain_diameter=SIGMA / 2, chute_length=X, frequencies=[0.27 * math.sqrt(2)])
    np.testing.assert_allclose(b.omega, a.omega, rtol=1e-13)
    np.testing.assert_allclose(b.spatial_growth, 2 * a.spatial_growth, rtol=1e-9)


def test_p1_growth_per_metre_is_spatial_points(p1, res):
    """One physics number: at 0.27 Hz (ω̂ = 0.27 · 2π √(σ/g) = 0.017127) the growth per metre
    is spatial_point's −Im k̂ / σ (the same solve: to 1e-9, the Newton tolerance on k), and
    −Im k̂ ≈ 1.4886e-4 (near the maximum 1.48862e-4 at ω̂ = 0.0171871, measured;
    tests/spatial/test_spatial_metric.py)."""
    w = 2 * math.pi * 0.27 * math.sqrt(SIGMA / G)
    pt = spatial_point(p1, w)
    assert pt.converged, pt.note
    assert res.spatial_growth[1] == pytest.approx(pt.spatial_growth / SIGMA, rel=1e-9)
    assert res.spatial_growth[1] == pytest.approx(0.14886, rel=1e-3)
    # 2 m of 1 mm beads: gain 1.35 (< 10: no visible waves); 15.5 m would be needed
    assert res.amplification_max == pytest.approx(1.3468, rel=1e-3)
    assert res.visible is False
    assert res.length_to_threshold == pytest.approx(15.47, rel=1e-3)
    assert res.depth == pytest.approx(p1.h * SIGMA, rel=1e-15)


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"grain_diameter": 0.0}, "grain_diameter"),
        ({"grain_diameter": -1e-3}, "grain_diameter"),
        ({"chute_length": 0.0}, "chute_length"),
        ({"chute_length": math.inf}, "chute_length"),
        ({"g": -9.81}, "g"),
        ({"threshold": 1.0}, "threshold"),
        ({"frequencies": [0.1, -0.2]}, "frequencies"),
    ],
)
def test_bad_input_names_the_parameter(p1, kw, name):
    args = {"grain_diameter": SIGMA, "chute_length": X, **kw}
    with pytest.raises(ParameterError, match=rf"^{name} = .* is outside") as e:
        signalling(p1, **args)
    assert "\n" not in str(e.value)


def test_to_dict_and_xarray(res):
    """The results convention (chuteflow.results.Result; strict=False by default)."""
    import inspect

    from chuteflow.results import Result

    assert isinstance(res, Result)
    assert inspect.signature(signalling).parameters["strict"].default is False
    d = res.to_dict()
    json.dumps(d, allow_nan=True)
    assert len(d["spectrum"]) == len(F)
    assert d["spectrum"][0]["frequency"] == pytest.approx(F[0])
    assert d["visible"] is False
    ds = res.to_xarray()
    assert ds["frequency"].attrs["units"] == "Hz"
    assert ds["spatial_growth"].attrs["units"] == "1/m"
    np.testing.assert_array_equal(ds["amplification"].values, res.amplification)


def test_cli_json(res):
    """``chuteflow signalling --json`` prints exactly SIGNALLING_KEYS (documented in
    docs/cli.md) with the API's numbers."""
    from chuteflow.cli.spatial import SIGNALLING_KEYS, SPECTRUM_KEYS

    args = ["signalling", *P1, "--diameter", "1e-3", "--chute-length", "2"]
    args += [x for f in F for x in ("-f", str(f))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = CliRunner().invoke(app, [*args, "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert set(out) == set(SIGNALLING_KEYS)
    assert set(out["spectrum"][0]) == set(SPECTRUM_KEYS)
    assert out["amplification_max"] == pytest.approx(res.amplification_max, rel=1e-12)
    assert out["visible"] is False


@pytest.mark.parametrize(
    ("opt", "name"),
    [("--diameter=0", "diameter"), ("--chute-length=-2", "chute_length"), ("--g=0", "g")],
)
def test_cli_bad_input_is_one_line_exit_2(opt, name, capsys):
    args = {"--diameter": "1e-3", "--chute-length": "2"}
    key = opt.split("=")[0]
    rest = [f"{k}={v}" for k, v in args.items() if k != key]
    code = main(["signalling", *P1, *rest, opt, "--json"])
    err = capsys.readouterr()
    assert code == 2
    assert err.out == ""
    lines = err.err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"error: {name} = ")
