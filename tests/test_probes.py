"""Smoke test of the probes in benchmarks/probes/: scripts that monkeypatch private code of the
package, which no other test runs. A refactor that moves or renames what they use fails here.

- every probe imports, and has a ``main``;
- every ``chuteflow`` import in it resolves, the ones inside functions included (most probes
  import the package in ``main``), and so does every attribute chain on what it imports from
  the package (``newton.SteadyNewton.step``, ``spectral.LAYER_MAP_WIDTH``): the targets of its
  monkeypatches and the functions it calls;
- (slow) the probes that take a size or a list of points run on a tiny case.
"""

from __future__ import annotations

import ast
import contextlib
import importlib
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROBES = sorted((ROOT / "benchmarks" / "probes").glob("*.py"))


def _load(path: Path):
    spec = importlib.util.spec_from_file_location(f"_probe_{path.stem}", path)
    assert spec is not None
    assert spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _resolve(module: str, name: str):
    mod = importlib.import_module(module)
    if hasattr(mod, name):
        return getattr(mod, name)
    return importlib.import_module(f"{module}.{name}")  # a submodule not imported by its package


def _package_names(tree: ast.AST) -> dict[str, object]:
    """Names bound anywhere in the probe to objects of the package (modules, classes, functions)."""
    bound: dict[str, object] = {}
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.ImportFrom)
            and node.level == 0
            and (node.module or "").startswith("chuteflow")
        ):
            assert node.module is not None
            for alias in node.names:
                bound[alias.asname or alias.name] = _resolve(node.module, alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] != "chuteflow":
                    continue
                mod = importlib.import_module(alias.name)
                if alias.asname:
                    bound[alias.asname] = mod
                else:
                    bound["chuteflow"] = importlib.import_module("chuteflow")
    return bound


def _chain(node: ast.Attribute) -> tuple[str, list[str]] | None:
    attrs = []
    cur: ast.expr = node
    while isinstance(cur, ast.Attribute):
        attrs.append(cur.attr)
        cur = cur.value
    return (cur.id, attrs[::-1]) if isinstance(cur, ast.Name) else None


@pytest.mark.parametrize("path", PROBES, ids=[p.stem for p in PROBES])
def test_probe_imports(path):
    mod = _load(path)
    assert callable(getattr(mod, "main", None)), f"{path.name}: no main()"


@pytest.mark.parametrize("path", PROBES, ids=[p.stem for p in PROBES])
def test_probe_uses_what_the_package_has(path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    bound = _package_names(tree)  # raises where an import no longer resolves
    missing = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        chain = _chain(node)
        if chain is None or chain[0] not in bound:
            continue
        obj = bound[chain[0]]
        for i, attr in enumerate(chain[1]):
            if isinstance(obj, type(sys)) and not hasattr(obj, attr):
                with contextlib.suppress(ImportError):  # a submodule not imported by its package
                    importlib.import_module(f"{obj.__name__}.{attr}")
            if not hasattr(obj, attr):
                missing.append(f"line {node.lineno}: {chain[0]}.{'.'.join(chain[1][: i + 1])}")
                break
            obj = getattr(obj, attr)
    assert not missing, f"{path.name} uses what the package no longer has: {missing}"


#: probe, arguments of a run of a few seconds (the others need a checkpoint or minutes)
QUICK = [
    ("chord_contraction", ["0.05", "4"]),
    ("longwave_start", ["3", "--size=8"]),
    ("map_schedule", ["0.05", "6"]),
    ("map_width", ["P1", "0.5", "plain,2"]),
    ("metric_work", ["growth", "3", "--size=6"]),
    ("metric_work", ["longwave", "3", "--size=6"]),
    ("n_table", ["P1", "0.5"]),
    ("relaxed_branch", ["P1", "0.5", "48"]),
    ("steady_work", ["map", "4"]),
    ("steady_work", ["families", "4"]),
    ("task_memory", ["0", "--size=4"]),
]


@pytest.mark.slow
@pytest.mark.parametrize(("probe", "args"), QUICK, ids=[f"{p}-{a[0]}" for p, a in QUICK])
def test_probe_runs_on_a_tiny_case(probe, args, tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    env.setdefault("MPLBACKEND", "Agg")
    script = ROOT / "benchmarks" / "probes" / f"{probe}.py"
    res = subprocess.run(
        [sys.executable, str(script), *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=300,
        check=False,
    )
    assert res.returncode == 0, f"{probe} {' '.join(args)}:\n{res.stdout[-2000:]}\n{res.stderr[-4000:]}"


@pytest.mark.slow
def test_mapped_x_probe_runs_on_a_tiny_checkpoint(tmp_path):
    """benchmarks/probes/mapped_x.py needs a run's state: a tiny P1 run's (L = 1000, 9 × 24),
    then the spectra in s and two steps on a mapped grid from it."""
    from chuteflow.closures import ChuteModel
    from chuteflow.dns import DnsSimulation
    from chuteflow.steady import solve_steady

    flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
    sim = DnsSimulation(flow, 1000.0, time=40.0, dt=4.0, n=24, modes=4, init="mode", amplitude=0.01)
    state = sim.run()
    state.save(tmp_path / "state.npz", sim.key())
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    script = str(ROOT / "benchmarks" / "probes" / "mapped_x.py")
    base = [sys.executable, script, "--state", str(tmp_path / "state.npz"), "--length", "1000"]
    runs = [
        [*base, "--modes", "2,3,4", "--json"],
        [*base, "--theta", "16", "--nu0", "0.05", "--ny", "24", "--dt", "4", "--step", "2"]
        + ["--mapped-nx", "9", "--betas", "0.5", "--preconditioners", "columns"],
    ]
    for cmd in runs:
        res = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300, check=False)
        assert res.returncode == 0, f"{res.stdout[-2000:]}\n{res.stderr[-4000:]}"
    rows = [json.loads(line) for line in res.stdout.splitlines() if line.startswith("{")]
    assert [r["grid"] for r in rows] == ["uniform", "nx 9, β 0.5"]
    # the same flow on a 9-point mapped grid: u within 1e-2 (measured 1.0e-3)
    assert rows[1]["max_diff_s_u_v_T"][1] < 1e-2
