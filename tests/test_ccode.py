"""Compiled kernels (:mod:`chuteflow._ccode`): generated C, cached on disk, with a Python road
that gives the same numbers to round-off wherever no compiler is available.

Sources: the generated Python code of the same sympy expressions
(:func:`chuteflow._codegen.cached_lambdify`, itself checked against sympy.lambdify in
tests/test_codegen.py) and scipy's ``dopri5`` (Hairer's DOPRI5) for the compiled
Dormand–Prince loop.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from chuteflow import _ccode
from chuteflow.closures import ChuteModel
from chuteflow.closures import model as closure_model
from chuteflow.steady.shooting import SteadyODE, shoot, steady_existence

pytestmark = pytest.mark.skipif(_ccode.compiler() is None, reason="no C compiler on this machine")

X, Y, P = sp.symbols("x y p", positive=True)


def _exprs():
    return (X, Y, P), [
        sp.sqrt(X) * sp.exp(Y) + X ** sp.Rational(1, 3) / (1 - Y) ** sp.Rational(5, 2),
        P * X,
        sp.S(2),
    ]


def test_pointwise_kernel_matches_lambdify_and_is_cached(tmp_path, monkeypatch):
    """A pointwise kernel computes what sympy.lambdify computes (to 2 ulp: libm against
    numpy's own exp/pow loops), broadcasts its array arguments, and a second request loads
    the cached library instead of deriving again."""
    monkeypatch.setenv("CHUTEFLOW_CACHE_DIR", str(tmp_path))
    kern = _ccode.cached_pointwise("t_pointwise", "k", _exprs, 2)
    assert kern is not None
    assert len(list((tmp_path / "ccode").glob("t_pointwise-*.so"))) == 1
    again = _ccode.cached_pointwise("t_pointwise", "k", lambda: pytest.fail("derived again"), 2)
    assert again is not None
    x = np.linspace(0.01, 3.0, 7)
    y = np.array([[0.1], [0.5]])
    out = kern(x, y, 1.5)
    assert out.shape == (3, 2, 7)
    ref = sp.lambdify((X, Y, P), _exprs()[1], modules="numpy")(x, y, 1.5)
    np.testing.assert_allclose(out[0], ref[0], rtol=4e-16 * 2)
    np.testing.assert_array_equal(out[1], np.broadcast_to(1.5 * x, (2, 7)))
    assert (out[2] == 2.0).all()
    # outside the domain: NaN as numpy gives, no exception
    with np.errstate(all="ignore"):
        assert np.isnan(kern(np.array([-1.0]), np.array([0.2]), 1.0)[0, 0])


def test_disabled_or_no_compiler_gives_none(tmp_path, monkeypatch):
    """CHUTEFLOW_CCODE=off, or a compiler that does not exist, leaves the Python road."""
    monkeypatch.setenv("CHUTEFLOW_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("CHUTEFLOW_CCODE", "off")
    assert _ccode.cached_pointwise("t_off", "k", _exprs, 2) is None
    monkeypatch.delenv("CHUTEFLOW_CCODE")
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    _ccode.compiler.cache_clear()
    try:
        assert _ccode.cached_pointwise("t_nocc", "k", _exprs, 2) is None
    finally:
        monkeypatch.delenv("CC")
        _ccode.compiler.cache_clear()
    # a source that does not compile: None as well, and nothing left in the cache
    assert _ccode.cached_library("t_broken", "k", lambda: "this is not C;") is None
    assert not list(tmp_path.glob("**/t_broken-*"))


@pytest.mark.parametrize("phi", [0.05, 0.10])
def test_compiled_partials_equal_generated_python(phi):
    """ChuteModel.evaluate's compiled partials equal the generated numpy code's (the same
    expressions) to round-off at random states, also outside the usual ranges."""
    model = ChuteModel(roughness=phi)
    kern = closure_model._compiled_c(*model.closures)
    assert kern is not None
    python = closure_model._compiled(*model.closures)[0]
    rng = np.random.default_rng(11)
    nu = rng.uniform(1e-9, 0.99 * model.nu_max, 200)
    T = np.exp(rng.uniform(-8, 4, 200))
    c = kern(nu, T, *model._params)
    py = python(nu, T, *model._params)
    worst = 0.0
    for row, ref in zip(c, py):
        ref = np.broadcast_to(np.asarray(ref, dtype=float), nu.shape)
        scale = np.maximum(np.abs(ref), 1e-300)
        worst = max(worst, float(np.max(np.abs(row - ref) / scale)))
    # measured 4.7e-15 (numpy's SIMD exp/pow against libm, and cancellations in the
    # second partials near nu_max)
    assert worst < 1e-12
    out = model.evaluate(nu, T, compiled=True)
    assert set(out) == set(closure_model.FUNCTIONS)
    assert out["p"][(1, 0)].shape == nu.shape


def test_compiled_shots_equal_scipy_dopri5():
    """The compiled Dormand–Prince loop takes the steps of scipy's dopri5 (Hairer's DOPRI5
    at scipy's settings) on the steady ODE: the same number of accepted steps and the same
    outcome for every trial of a scan, the end height and the miss equal to round-off."""
    model = ChuteModel()
    fast = SteadyODE(16.0, model)
    assert fast.kernel is not None
    slow = SteadyODE(16.0, model)
    slow.kernel = None
    worst = 0.0
    for nu0 in (0.02, 0.08, 0.3):
        for u in np.geomspace(1e-2, 1e3, 11):
            for rtol in (1e-4, 1e-6):
                a = shoot(fast, nu0, float(u), rtol=rtol, dense=True)
                b = shoot(slow, nu0, float(u), rtol=rtol, dense=True)
                assert (a.kind, a.sign, len(a.solution.t)) == (b.kind, b.sign, len(b.solution.t))
                worst = max(worst, abs(a.y_end - b.y_end) / max(1.0, b.y_end))
                if a.kind == "top":
                    assert a.dT_top == pytest.approx(b.dT_top, rel=1e-6, abs=1e-12)
                    y = np.linspace(0.0, a.y_end, 9)
                    np.testing.assert_allclose(a.solution.sol(y), b.solution.sol(y), rtol=1e-9, atol=1e-12)
    assert worst < 1e-12  # measured 5.5e-15


@pytest.mark.parametrize(
    ("theta", "nu0"), [(16.0, 0.05), (14.0, 0.02), (18.0, 0.2), (12.0, 0.3), (20.0, 0.03)]
)
def test_compiled_verdicts_equal_python_verdicts(theta, nu0, monkeypatch):
    """steady_existence gives the same verdict, floor velocity and shot count with the
    compiled integrator as with scipy's dopri5 and the generated Python right-hand side."""
    fast = steady_existence(theta, nu0)
    real = SteadyODE.__init__

    def python_only(self, *a, **kw):
        real(self, *a, **kw)
        self.kernel = None

    monkeypatch.setattr(SteadyODE, "__init__", python_only)
    slow = steady_existence(theta, nu0)
    assert (fast.kind, fast.shots) == (slow.kind, slow.shots)
    if math.isfinite(slow.u_floor):
        assert fast.u_floor == pytest.approx(slow.u_floor, rel=1e-9)
        assert fast.h == pytest.approx(slow.h, rel=1e-9)
