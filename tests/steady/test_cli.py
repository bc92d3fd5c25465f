"""``chuteflow steady``: JSON object, table, one-line errors (issue 2, CLI)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from chuteflow.cli import app
from chuteflow.steady import solve_steady

runner = CliRunner()


def test_json_output():
    r = runner.invoke(app, ["steady", "--theta", "16", "--nu0", "0.05", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    for k in (
        "theta",
        "nu0",
        "roughness",
        "wall_loss",
        "restitution",
        "nu_max",
        "u_floor",
        "T_floor",
        "h",
        "nu_mean",
        "rho_bar",
        "Q",
        "monotonic",
        "y_max",
        "convergence",
    ):
        assert k in d, k
    f = solve_steady(16, 0.05)
    assert d["rho_bar"] == pytest.approx(f.rho_bar, rel=1e-12)
    assert d["monotonic"] is True
    assert d["roughness"] == 0.05


def test_model_options_reach_the_solver():
    r = runner.invoke(
        app,
        [
            "steady",
            "--theta",
            "20",
            "--nu0",
            "0.1",
            "--roughness",
            "0.1",
            "--wall-loss",
            "0.39",
            "--restitution",
            "0.7",
            "--nu-max",
            "0.6",
            "--nu-top",
            "1e-9",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    from chuteflow.closures import ChuteModel

    f = solve_steady(20, 0.1, ChuteModel(roughness=0.1))
    assert d["roughness"] == 0.1
    assert d["h"] == pytest.approx(f.h, rel=1e-12)


def test_table_output():
    r = runner.invoke(app, ["steady", "--theta", "16", "--nu0", "0.05"])
    assert r.exit_code == 0, r.output
    assert "slip velocity" in r.stdout
    assert "8.19453" in r.stdout


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--theta", "16", "--nu0", "0.7"], ["nu0", "nu_max"]),
        (["--theta", "-2", "--nu0", "0.05"], ["theta"]),
        (["--theta", "16", "--nu0", "0.05", "--roughness", "-1"], ["roughness"]),
        (["--theta", "16", "--nu0", "0.05", "--restitution", "1.5"], ["restitution"]),
    ],
)
def test_bad_input_one_line_error(args, words):
    r = runner.invoke(app, ["steady", *args])
    assert r.exit_code == 2
    err = r.stderr.strip()
    assert "Traceback" not in r.output
    assert len(err.splitlines()) == 1
    assert err.startswith("error: ")
    for w in words:
        assert w in err


@pytest.mark.slow
def test_no_steady_flow_is_a_user_error():
    r = runner.invoke(app, ["steady", "--theta", "12", "--nu0", "0.1"])
    assert r.exit_code == 2
    err = r.stderr.strip()
    assert len(err.splitlines()) == 1
    assert "too small" in err


def test_unresolved_flow_is_printed_with_a_warning():
    """Where the steady flow misses rtol (θ = 16.2712°, ν0(0) = 0.25: change 3.6e-8 between
    the last two resolutions, tests/steady/test_solver.py), ``chuteflow steady`` prints it
    with ``converged`` false and one warning line on stderr, exit status 0 — not an error."""
    r = CliRunner().invoke(app, ["steady", "--theta", "16.2712", "--nu0", "0.25", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["h"] == pytest.approx(9.137, rel=1e-3)
    if not d["converged"]:
        assert d["convergence"] > 1e-8
        assert r.stderr.startswith("warning: the steady flow at theta = 16.2712 deg")
        assert len(r.stderr.strip().splitlines()) == 1


def test_strict_option_makes_an_unresolved_flow_an_error():
    """``--strict``: the same flow (change 3.6e-8 > 1e-8) is a one-line error, exit 2 —
    through typer and through the fast path of a plain call (``fast_main``)."""
    from chuteflow.cli._fast import fast_main

    argv = ["steady", "--theta", "16.2712", "--nu0", "0.25", "--json", "--strict"]
    r = CliRunner().invoke(app, argv)
    code = fast_main(argv)
    if r.exit_code == 0:  # resolved after all (then both paths print it)
        assert json.loads(r.stdout)["converged"] is True
        assert code == 0
    else:
        assert r.exit_code == 2
        assert code == 2
        assert "did not converge" in r.stderr
        assert "Traceback" not in r.stderr


def test_transverse_at_an_unresolved_flow_prints_one_warning():
    """``chuteflow transverse`` on that flow (α2z ≈ −490, no k_z computed past the lost
    branch): the flagged flow's warning is the only line on stderr — no numpy RuntimeWarning
    from the empty dispersion (its drift/tail maxima are JSON null)."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = CliRunner().invoke(app, ["transverse", "--theta", "16.2712", "--nu0", "0.25", "--json"])
    assert r.exit_code == 0, r.output
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)]
    d = json.loads(r.stdout)
    assert d["alpha2_z"] < 0
    if d["kz_computed"] == 0:
        assert d["drift_max"] is None
        assert d["tail_max"] is None
    lines = r.stderr.strip().splitlines()
    assert len(lines) <= 1
    assert all(x.startswith("warning: the steady flow") for x in lines)
