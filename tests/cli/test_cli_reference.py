"""docs/cli.md documents every key that the commands print with ``--json``.

The page has one table per command (``## `chuteflow NAME` ``) and one of the keys common to
all; nested objects are written ``steady.h``, lists of objects ``points[].rho0``, and
``steady.*`` stands for the keys of ``chuteflow steady``. The commands run here at P1
(θ = 16°, ν0(0) = 0.05, §4.2) with the cheapest options: ``steady``, ``eig`` (2D),
``dispersion`` with three k, ``longwave`` and ``spatial`` (about 11 s together);
``absolute`` (5–20 s) is checked against its key list, and run in a slow test.
"""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import pytest
from typer.testing import CliRunner

from chuteflow.cli import app

DOC = Path(__file__).resolve().parents[2] / "docs" / "cli.md"
P1 = ["--theta", "16", "--nu0", "0.05"]
COMMON = "common"

runner = CliRunner()


def documented() -> dict[str, set[str]]:
    """{command: keys of its table} from docs/cli.md (``COMMON``: the shared table)."""
    out: dict[str, set[str]] = {}
    section = None
    for line in DOC.read_text(encoding="utf-8").splitlines():
        h = re.match(r"## `chuteflow (\w+)`", line)
        if h:
            section = h.group(1)
            out.setdefault(section, set())
            continue
        if line.startswith("## Keys common"):
            section = COMMON
            out.setdefault(section, set())
            continue
        if line.startswith("## "):
            section = None
        row = re.match(r"\| `([^`]+)` \|", line)
        if row and section is not None:
            out[section].add(row.group(1))
    return out


def flat_keys(obj: dict, prefix: str = "") -> set[str]:
    """Dotted names of every key of a JSON object (``[]`` for lists of objects)."""
    keys = set()
    for k, v in obj.items():
        name = prefix + k
        keys.add(name)
        if isinstance(v, dict):
            keys |= flat_keys(v, name + ".")
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for x in v:
                keys |= flat_keys(x, name + "[].")
    return keys


def undocumented(command: str, out: dict, docs: dict[str, set[str]]) -> set[str]:
    own, common = docs[command], docs[COMMON]
    steady = docs["steady"] | common
    missing = set()
    for key in flat_keys(out):
        if key in own or key in common:
            continue
        head, _, rest = key.partition(".")
        if rest and f"{head}.*" in own and (head != "steady" or rest in steady):
            continue
        if not rest and f"{key}.*" in own:  # the object itself (``steady``)
            continue
        missing.add(key)
    return missing


@pytest.fixture(scope="module")
def outputs() -> dict[str, dict]:
    runs = {
        "steady": ["steady", *P1, "--json"],
        "eig": ["eig", *P1, "--k", "0.002", "--json"],
        "dispersion": ["dispersion", *P1, "--k-max", "0.006", "--num", "3", "--json"],
        "longwave": ["longwave", *P1, "--rtol", "0.2", "--json"],
        "spatial": ["spatial", *P1, "--omega", "0.02", "--json"],
    }
    res = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for name, args in runs.items():
            r = runner.invoke(app, args)
            assert r.exit_code == 0, r.output
            res[name] = json.loads(r.stdout)
    return res


def test_the_page_has_a_table_for_every_json_command():
    docs = documented()
    for cmd in ("steady", "eig", "mode", "dispersion", "longwave", "transverse", "winner", "reduced"):
        assert docs.get(cmd), cmd
    assert {"simulate", "dns", "eig3d", "spatial", "absolute"} <= set(docs)
    assert {"theta", "nu0", "nu_top"} <= docs[COMMON]


@pytest.mark.parametrize("command", ["steady", "eig", "dispersion", "longwave", "spatial"])
def test_every_json_key_is_documented(command, outputs):
    assert not undocumented(command, outputs[command], documented()), command


@pytest.mark.parametrize("command", ["steady", "eig", "dispersion", "longwave", "spatial"])
def test_every_documented_key_is_printed(command, outputs):
    """No stale rows: the table's keys (other than ``only with …`` ones) are all printed."""
    keys = flat_keys(outputs[command])
    stale = {k for k in documented()[command] if not k.endswith(".*") and k not in keys}
    assert not stale, (command, stale)


def test_the_check_sees_a_new_key(outputs):
    """The check itself: an added top-level or nested key is reported."""
    docs = documented()
    out = dict(outputs["longwave"])
    out["alpha2_new"] = 1.0
    out["steady"] = {**out["steady"], "h_new": 1.0}
    assert undocumented("longwave", out, docs) == {"alpha2_new", "steady.h_new"}


def test_longwave_json_alpha2_is_the_dispersion_relations(outputs):
    """``alpha2_re`` is Re α/k² of the eigenvalue at k = 1e-5 (at P1 12308.05 over N = 80 …
    200, tests/stability/test_robust.py), equal to that entry of ``eig_alpha2_re``; the Taylor
    value (12459 at N = 200, plain grid: 1.2 % away) is the separate diagnostic. Tolerance
    1e-5 relative, ~10× the spread over N."""
    out = outputs["longwave"]
    assert out["alpha2_k"] == 1e-5
    assert out["alpha2_re"] == out["eig_alpha2_re"][out["eig_k"].index(1e-5)]
    assert out["alpha2_re"] == pytest.approx(12308.05, rel=1e-5)
    assert out["alpha2_convergence"] < 1e-5
    assert abs(out["alpha2_taylor_re"] - out["alpha2_re"]) > 1e-3 * out["alpha2_re"]


@pytest.mark.parametrize("command", ["spatial", "absolute", "signalling"])
def test_the_spatial_key_lists_match_the_page(command):
    """``SPATIAL_KEYS``/``ABSOLUTE_KEYS``/``SIGNALLING_KEYS`` (what the commands print;
    tests/spatial/test_signalling.py runs ``signalling``) are the page's rows."""
    from chuteflow.cli.spatial import ABSOLUTE_KEYS, SIGNALLING_KEYS, SPATIAL_KEYS, SPECTRUM_KEYS

    keys = {
        "spatial": set(SPATIAL_KEYS),
        "absolute": set(ABSOLUTE_KEYS),
        "signalling": set(SIGNALLING_KEYS) | {f"spectrum[].{k}" for k in SPECTRUM_KEYS},
    }[command]
    docs = documented()
    assert keys - docs[COMMON] == docs[command]


@pytest.mark.slow
def test_absolute_json_keys_are_documented():
    """``absolute --json`` at P1 (about 5 s here, up to 20 s) prints exactly the page's keys."""
    from chuteflow.cli.spatial import ABSOLUTE_KEYS

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = runner.invoke(app, ["absolute", *P1, "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert not undocumented("absolute", out, documented())
    assert set(out) == set(ABSOLUTE_KEYS)
