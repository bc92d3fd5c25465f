"""Generated code cached on disk (chuteflow._codegen): cold and warm runs agree bitwise, the
key follows what the expressions depend on, and a damaged or unusable cache falls back."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from chuteflow import _codegen
from chuteflow._codegen import cache_dir, cache_key, cached_lambdify
from chuteflow.closures import CarnahanStarling, ChuteModel
from chuteflow.closures import model as model_module
from chuteflow.equations import _derive_compiled, compiled_equations

SRC = Path(__file__).resolve().parents[1] / "src"
X, Y = sp.symbols("x y", positive=True)


def _exprs():
    return {
        "f": (
            (X, Y),
            [sp.sqrt(sp.pi) * X**Y + sp.exp(X) / (1 + Y), sp.S.Zero, sp.diff(sp.log(1 + X * Y) ** 3, X, 2)],
        ),
        "g": ((X,), [sp.Rational(5, 2) * X ** sp.Rational(-3, 2)], False),
    }, ("a", 1)


def _never():
    raise AssertionError("build_exprs called on a warm cache")


def _bits(values):
    return [np.asarray(v, dtype=float).tobytes() for v in values]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("CHUTEFLOW_CACHE_DIR", str(folder))
    return folder


def test_cold_then_warm_is_bitwise_identical_to_lambdify(cache):
    x = np.linspace(0.01, 3.0, 101)
    y = np.linspace(0.2, 2.0, 101)
    calls = []

    def build():
        calls.append(1)
        return _exprs()

    cold = cached_lambdify("test", "k1", build, sources=(__name__,))
    assert calls == [1]
    assert cold.path is not None
    assert cold.path.is_file()
    assert cold.path.parent == cache / "codegen"
    assert cold.data == ("a", 1)
    warm = cached_lambdify("test", "k1", _never, sources=(__name__,))
    assert warm.path == cold.path
    assert warm.data == ("a", 1)
    spec, _ = _exprs()
    direct = sp.lambdify(spec["f"][0], spec["f"][1], modules="numpy", cse=True)
    assert _bits(cold["f"](x, y)) == _bits(warm["f"](x, y)) == _bits(direct(x, y))
    np.testing.assert_allclose(warm["g"](x)[0], 2.5 * x**-1.5, rtol=1e-15)


def test_key_changes_with_what_the_expressions_depend_on(cache, tmp_path, monkeypatch):
    base = cache_key("test", "k1", (__name__,))
    assert base == cache_key("test", "k1", (__name__,))
    assert base[1] != cache_key("test", "k2", (__name__,))[1]
    assert base[1] != cache_key("other", "k1", (__name__,))[1]
    # a closure with another g0: another key
    a, b = ChuteModel().closures, ChuteModel(radial=CarnahanStarling()).closures
    ka = cache_key("closure", repr(a), a)
    kb = cache_key("closure", repr(b), b)
    assert ka[1] != kb[1]
    assert "chuteflow.closures.radial" in json.loads(ka[0])["sources"]
    assert "chuteflow.closures.walls" in json.loads(ka[0])["sources"]
    # an edited source file: another key
    mod = tmp_path / "cf_codegen_probe.py"
    mod.write_text("def g0(nu):\n    return nu\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    k1 = cache_key("test", "k1", ("cf_codegen_probe",))
    mod.write_text("def g0(nu):\n    return 2 * nu\n")
    assert k1[1] != cache_key("test", "k1", ("cf_codegen_probe",))[1]
    # the sympy and chuteflow versions are part of the key
    monkeypatch.setattr(_codegen, "__version__", "0.0.0-test")
    assert base[1] != cache_key("test", "k1", (__name__,))[1]


def test_objects_without_a_stable_repr_are_not_cached_on_disk(cache):
    class Opaque:
        pass

    assert cache_key("test", repr(Opaque()), ()) is None
    code = cached_lambdify("test", repr(Opaque()), _exprs)
    assert code.path is None
    assert not (cache / "codegen").exists()
    assert code["g"](np.array([1.0]))[0][0] == 2.5


def test_corrupt_cache_file_is_rederived_and_repaired(cache):
    first = cached_lambdify("test", "k1", _exprs)
    for damage in ("def f(:\n", "KEY = 'other'\nDATA = None\nFUNCTIONS = {}\n", ""):
        first.path.write_text(damage)
        calls: list[int] = []

        def build(calls=calls):
            calls.append(1)
            return _exprs()

        again = cached_lambdify("test", "k1", build)
        assert calls == [1]
        assert again.path == first.path
        assert again["g"](np.array([4.0]))[0][0] == 2.5 / 8.0
        assert cached_lambdify("test", "k1", _never).path == first.path  # repaired


def test_unwritable_or_disabled_cache_falls_back_to_memory(tmp_path, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("CHUTEFLOW_CACHE_DIR", str(blocker / "cache"))
    code = cached_lambdify("test", "k1", _exprs)
    assert code.path is None
    assert code["g"](np.array([1.0]))[0][0] == 2.5
    for off in ("", "off", "none"):
        monkeypatch.setenv("CHUTEFLOW_CACHE_DIR", off)
        assert cache_dir() is None
        assert cached_lambdify("test", "k1", _exprs).path is None


def test_cache_dir_follows_xdg(monkeypatch, tmp_path):
    monkeypatch.delenv("CHUTEFLOW_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert cache_dir() == tmp_path / "chuteflow"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/path")  # ignored, as the spec says
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_dir() == tmp_path / "home" / ".cache" / "chuteflow"


def test_model_code_is_bitwise_identical_to_lambdify(cache):
    """The cached code of the built-in closure and equations computes exactly what
    sympy.lambdify of the same derivation computes (nothing changes numerically)."""
    model_module._compiled.cache_clear()
    compiled_equations.cache_clear()
    try:
        m = ChuteModel()
        rng = np.random.default_rng(7)
        nu, T = rng.uniform(0.001, 0.55, 50), rng.uniform(0.1, 5.0, 50)
        spec, _ = model_module._derive(*m.closures)
        args, exprs = spec["partials"]
        direct = sp.lambdify(args, exprs, modules="numpy", cse=True)
        partials = model_module._compiled(*m.closures)[0]
        p = (m.restitution, m.nu_max, m.roughness, m.wall_loss)
        assert _bits(partials(nu, T, *p)) == _bits(direct(nu, T, *p))
        eqs = compiled_equations()
        espec, terms = _derive_compiled()
        vals = [rng.uniform(0.1, 1.0, 20) for _ in espec["mass"][0]]
        for name, ts in terms:
            fun = sp.lambdify(espec[name][0], espec[name][1], modules="numpy", cse=True)
            assert _bits(eqs[name]._fun(*vals)) == _bits(fun(*vals)), name
            assert tuple((t.field, t.a, t.b, t.c, t.d, t.index, t.k) for t in eqs[name].terms) == ts
    finally:
        model_module._compiled.cache_clear()
        compiled_equations.cache_clear()


_RUN = textwrap.dedent("""
    import json, sys
    import numpy as np
    from chuteflow.closures import ChuteModel
    from chuteflow.steady import solve_steady
    m = ChuteModel()
    nu = np.linspace(0.01, 0.5, 9)
    ev = m.evaluate(nu, np.linspace(0.3, 3.0, 9))
    flow = solve_steady(16.0, 0.05, m)
    out = {"evaluate": [ev[k][o].tobytes().hex() for k in sorted(ev) for o in sorted(ev[k])],
           "f": [v.tobytes().hex() for k, t in sorted(m.f(nu).items()) for v in t],
           "steady": [flow.u.tobytes().hex(), flow.T.tobytes().hex(), repr(flow.h)],
           "sympy": "sympy" in sys.modules}
    print(json.dumps(out))
""")


def test_fresh_processes_cold_and_warm_agree_and_warm_needs_no_sympy(cache):
    env = dict(
        os.environ,
        CHUTEFLOW_CACHE_DIR=str(cache),
        PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
    )

    def run():
        res = subprocess.run(
            [sys.executable, "-c", _RUN], env=env, capture_output=True, text=True, timeout=600, check=True
        )
        return json.loads(res.stdout.strip().splitlines()[-1])

    cold = run()
    # the closures (numpy and scalar: the steady flow's dilute tail, derived_quantities)
    # and the equations
    assert len(list((cache / "codegen").glob("*.py"))) == 3
    warm = run()
    assert cold.pop("sympy") is True
    assert warm.pop("sympy") is False
    assert cold == warm


def test_old_generated_modules_are_pruned(cache, monkeypatch):
    paths = [cached_lambdify("test", f"k{i}", _exprs).path for i in range(6)]
    for i, p in enumerate(paths):
        os.utime(p, (1000.0 + i, 1000.0 + i))  # distinct ages, oldest first
    monkeypatch.setattr(_codegen, "KEEP", 3)
    newest = cached_lambdify("test", "k6", _exprs).path
    left = set((cache / "codegen").glob("test-*.py"))
    assert newest in left
    assert len(left) == 3
    assert paths[0] not in left


_CLI = textwrap.dedent("""
    import io, json, sys, contextlib
    from chuteflow.cli import main
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(sys.argv[1:])
    heavy = sorted(m for m in ("sympy", "matplotlib", "xarray", "dask", "pandas", "h5py")
                   if m in sys.modules)
    print(json.dumps({"rc": rc, "heavy": heavy}))
""")


@pytest.fixture(scope="module")
def shared_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("cache")


@pytest.mark.parametrize(
    "argv",
    [
        ["steady", "--theta", "16", "--nu0", "0.05", "--json"],
        ["eig", "--theta", "16", "--nu0", "0.05", "--k", "0.002", "--json"],
    ],
)
def test_warm_cli_imports_no_heavy_modules(argv, shared_cache):
    """A fresh ``chuteflow steady`` / ``eig`` with a warm cache loads neither sympy nor the
    plotting and data-set libraries (start-up in a fraction of a second)."""
    env = dict(
        os.environ,
        CHUTEFLOW_CACHE_DIR=str(shared_cache),
        PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
    )
    for _ in range(2):  # the first run fills the cache if it is cold
        res = subprocess.run(
            [sys.executable, "-c", _CLI, *argv],
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
            check=True,
        )
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out == {"rc": 0, "heavy": []}


_STEADY_LIGHT = textwrap.dedent("""
    import io, json, sys, contextlib
    from chuteflow.cli import main
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(sys.argv[1:])
    names = ("sympy", "matplotlib", "xarray", "typer", "rich", "pydantic", "scipy", "numpy.f2py")
    print(json.dumps({"rc": rc, "heavy": sorted(m for m in names if m in sys.modules),
                      "theta": json.loads(buf.getvalue())["theta"]}))
""")


def test_warm_steady_skips_typer_and_scipy(shared_cache):
    """``chuteflow steady --json`` with a warm cache is answered by the plain parser of
    cli/_fast.py: neither typer, rich and pydantic (0.3 s) nor any part of scipy (0.3 s)
    nor numpy.f2py (``from numpy import *``) is imported (issue 9, item 5)."""
    env = dict(
        os.environ,
        CHUTEFLOW_CACHE_DIR=str(shared_cache),
        PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
    )
    argv = ["steady", "--theta", "16", "--nu0", "0.05", "--roughness", "0.05", "--json"]
    for _ in range(2):  # the first run fills the cache if it is cold
        res = subprocess.run(
            [sys.executable, "-c", _STEADY_LIGHT, *argv],
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
            check=True,
        )
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out == {"rc": 0, "heavy": [], "theta": 16.0}
