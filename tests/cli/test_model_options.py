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
from chuteflow.closures import CLOSURES, FIELDS, PRESETS, ChuteModel
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
    assert "--preset" in r.output


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


def test_preset_rule_explicit_closure_options_override_the_preset():
    """--preset sets the closures; a closure option given explicitly overrides the preset's,
    the numeric parameters apply as always (docs/cli.md, "Presets")."""
    assert model_from_options("mfix-lun") == ChuteModel.preset("mfix-lun")
    assert model_from_options("mfix-gd", roughness=0.1) == ChuteModel.preset("mfix-gd", roughness=0.1)
    # explicit transport: the preset's radial g0 stays
    m = model_from_options("mfix-gd", {"transport"}, transport="garzo_dufty", radial="lun_savage")
    assert m == ChuteModel(transport="garzo_dufty", radial="carnahan_starling")
    # the same value given explicitly (here the default) still overrides
    m = model_from_options("mfix-lun", {"radial"}, transport="lun", radial="lun_savage")
    assert m == ChuteModel(transport={"name": "lun_mfix", "alpha": 1.6}, radial="lun_savage")
    # without the list of explicit options: values other than the defaults count as explicit
    assert model_from_options("mfix-gd", radial="ma_ahmadi").radial == ChuteModel(radial="ma_ahmadi").radial
    assert model_from_options("paper", transport="lun_full") == ChuteModel(transport="lun_full")


def test_preset_on_the_command_line():
    base = ["steady", "--theta", "16", "--nu0", "0.05", "--json"]
    r = runner.invoke(app, [*base, "--preset", "mfix-lun"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert (out["transport"], out["radial"]) == ({"name": "lun_mfix", "alpha": 1.6}, "carnahan_starling")
    ref = solve_steady(16, 0.05, ChuteModel.preset("mfix-lun"))
    assert out["h"] == pytest.approx(ref.h, rel=1e-12)
    r = runner.invoke(app, [*base, "--preset", "mfix-lun", "--transport", "lun"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert (out["transport"], out["radial"]) == ("lun", "carnahan_starling")
    # an explicit option equal to the default still overrides the preset
    r = runner.invoke(app, [*base, "--preset", "mfix-lun", "--radial", "lun_savage"])
    assert json.loads(r.stdout)["radial"] == "lun_savage"


def test_unknown_preset_is_one_line_listing_the_known_ones():
    r = runner.invoke(app, ["steady", "--theta", "16", "--nu0", "0.05", "--preset", "mfix"])
    assert r.exit_code == 2
    assert "Traceback" not in r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1, r.output
    assert lines[0].startswith("error: --preset: unknown preset 'mfix'; choose one of")
    for name in PRESETS:
        assert repr(name) in lines[0]
