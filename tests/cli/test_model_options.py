"""Model options generated from ChuteModel's fields: every model command has them all, their
defaults are ChuteModel()'s, and ``--radial`` reaches the solver.

The reference is ``solve_steady`` with the same model (the CLI must print exactly its numbers).
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from chuteflow.cli import app
from chuteflow.cli._app import CLOSURE_OPTIONS, MODEL_OPTIONS, model_from_options
from chuteflow.closures import CLOSURES, FIELDS, ChuteModel
from chuteflow.steady import solve_steady

runner = CliRunner()
MODEL_COMMANDS = (
    "steady",
    "eig",
    "dispersion",
    "longwave",
    "mode",
    "diagram",
    "reduced",
    "simulate",
    "spatial",
    "absolute",
)


def test_options_cover_every_field_with_the_model_defaults():
    assert set(MODEL_OPTIONS) | set(CLOSURE_OPTIONS) == set(FIELDS)
    defaults = {k: v[0] for k, v in {**MODEL_OPTIONS, **CLOSURE_OPTIONS}.items()}
    assert model_from_options(**defaults) == ChuteModel()
    for name, (_, _, choices) in CLOSURE_OPTIONS.items():
        assert tuple(c.value for c in choices) == CLOSURES[name].names()


@pytest.mark.parametrize("command", MODEL_COMMANDS)
def test_every_model_command_has_all_model_options(command):
    r = runner.invoke(app, [command, "--help"], terminal_width=200)
    assert r.exit_code == 0, r.output
    for name in FIELDS:
        assert "--" + name.replace("_", "-") in r.output, (command, name)
    assert "carnahan_starling" in r.output


def test_radial_changes_the_steady_result():
    base = ["steady", "--theta", "16", "--nu0", "0.05", "--json"]
    ls = json.loads(runner.invoke(app, base).stdout)
    r = runner.invoke(app, [*base, "--radial", "carnahan_starling"])
    assert r.exit_code == 0, r.output
    cs = json.loads(r.stdout)
    assert ls["radial"] == "lun_savage"
    assert cs["radial"] == "carnahan_starling"
    assert cs["wall"] == "johnson_jackson"
    assert cs["transport"] == "lun"
    ref = solve_steady(16, 0.05, ChuteModel(radial="carnahan_starling"))
    assert cs["h"] == pytest.approx(ref.h, rel=1e-12)
    assert cs["rho_bar"] == pytest.approx(ref.rho_bar, rel=1e-12)
    assert abs(cs["h"] / ls["h"] - 1) > 1e-2


def test_unknown_closure_name_is_a_usage_error():
    r = runner.invoke(app, ["steady", "--theta", "16", "--nu0", "0.05", "--radial", "nope"])
    assert r.exit_code == 2
    assert "Traceback" not in r.output
    assert "lun_savage" in r.output
