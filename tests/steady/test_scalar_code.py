"""Scalar generated code of the shooting scan (issue 9 item 4): ``math``-module code from the
same derivations as the numpy code, cached on disk like it, giving the same numbers.

Sources: :func:`chuteflow._codegen.cached_lambdify` (``modules="math"``),
:meth:`ChuteModel.scalar_evaluator`, :mod:`chuteflow.steady._scalar_ode`; the right-hand side
of the steady ODE is also compared with an independent transcription of the paper's
equations in tests/steady/test_existence.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from chuteflow._codegen import cached_lambdify
from chuteflow.closures import ChuteModel
from chuteflow.closures.model import FUNCTIONS, SCALAR_ORDERS
from chuteflow.equations import BASE, arguments, compiled_equations
from chuteflow.errors import ParameterError
from chuteflow.steady import _scalar_ode
from chuteflow.steady.shooting.ode import SteadyODE, _term_index

X, Y = sp.symbols("x y", positive=True)


def _exprs():
    return {
        "f": (
            (X, Y),
            [sp.sqrt(X) * sp.exp(Y) + X ** sp.Rational(1, 3) / (1 - Y) ** sp.Rational(5, 2), sp.S.Zero],
        )
    }


def test_math_code_cold_then_warm_equals_lambdify(tmp_path, monkeypatch):
    """The cached math-module code computes exactly what sympy.lambdify(modules="math")
    computes, cold and warm, under a key of its own (not the numpy code's)."""
    monkeypatch.setenv("CHUTEFLOW_CACHE_DIR", str(tmp_path))
    cold = cached_lambdify("t", "k", _exprs, modules="math")
    warm = cached_lambdify("t", "k", lambda: pytest.fail("derived again"), modules="math")
    numpy_code = cached_lambdify("t", "k", _exprs)
    assert warm.path == cold.path
    assert numpy_code.path != cold.path
    direct = sp.lambdify((X, Y), _exprs()["f"][1], modules="math", cse=True)
    for x, y in ((0.3, 0.2), (2.0, 0.9), (1e-6, -3.0)):
        out = cold["f"](x, y)
        assert out == warm["f"](x, y) == direct(x, y)
        assert all(type(v) in (float, int) for v in out)
        np.testing.assert_allclose(out, numpy_code["f"](np.float64(x), np.float64(y)), rtol=1e-15)
    with pytest.raises(ValueError, match="math domain error"):
        cold["f"](-1.0, 0.2)  # math.sqrt of a negative number: an error, not NaN
    with pytest.raises(ValueError, match="modules"):
        cached_lambdify("t", "k", _exprs, modules="mpmath")


@pytest.mark.parametrize("phi", [0.05, 0.10])
def test_scalar_evaluator_equals_evaluate(phi):
    """ChuteModel.scalar_evaluator gives the partials of ChuteModel.evaluate to round-off."""
    m = ChuteModel(roughness=phi)
    f = m.scalar_evaluator()
    rng = np.random.default_rng(3)
    for nu, T in zip(rng.uniform(1e-9, 0.59, 30), rng.uniform(1e-3, 50.0, 30)):
        ref = m.evaluate(nu, T)
        want = [float(ref[k][o]) for k in FUNCTIONS for o in SCALAR_ORDERS]
        np.testing.assert_allclose(f(float(nu), float(T)), want, rtol=2e-14, atol=0)
    g = m.scalar_evaluator(((2, 0),))
    ref = m.evaluate(0.3, 2.0)
    np.testing.assert_allclose(g(0.3, 2.0), [float(ref[k][(2, 0)]) for k in FUNCTIONS], rtol=2e-14)
    with pytest.raises(ParameterError, match="orders"):
        m.scalar_evaluator(((3, 0),))


def _numpy_rhs(theta, model, z):
    """ν0'/ν0, u0', T0'' from the numpy code of the closures and compiled equations (the
    scan's right-hand side before the scalar code)."""
    th = math.radians(theta)
    sin, cos = math.sin(th), math.cos(th)
    eqs = compiled_equations()
    s, u, T, T_y = z
    nu = math.exp(s)
    part = model.evaluate(nu, T)
    base = dict.fromkeys(BASE, 0.0)
    base.update(
        nu=nu, u=u, T=T, T_y=T_y, u_y=sin / cos * float(part["p"][(0, 0)]) / float(part["mu"][(0, 0)])
    )
    r, c = eqs["ymom"].evaluate_arguments(arguments(base, part, sin, cos))
    base["nu_y"] = -float(r) / float(c[_term_index(eqs["ymom"], "nu", 1)])
    r, c = eqs["energy"].evaluate_arguments(arguments(base, part, sin, cos))
    return [base["nu_y"] / nu, base["u_y"], -float(r) / float(c[_term_index(eqs["energy"], "T", 2)])]


@pytest.mark.parametrize("phi", [0.05, 0.10])
def test_scalar_rhs_equals_numpy_code(phi):
    """The fused scalar right-hand side equals the one assembled from the numpy code of the
    closures and equations to round-off, and gives NaN outside the closures' domain."""
    m = ChuteModel(roughness=phi)
    rng = np.random.default_rng(5)
    for _ in range(20):
        theta = rng.uniform(8.0, 27.0)
        z = [
            math.log(rng.uniform(1e-9, 0.59)),
            rng.uniform(0.1, 50.0),
            rng.uniform(1e-3, 20.0),
            rng.uniform(-2, 2),
        ]
        mine = SteadyODE(theta, m).rhs(0.0, z)
        assert mine[2] == z[3]
        np.testing.assert_allclose([mine[0], mine[1], mine[3]], _numpy_rhs(theta, m, z), rtol=1e-12)
    ode = SteadyODE(16.0, m)
    assert all(math.isnan(v) for v in ode.rhs(0.0, [math.log(0.5), 1.0, -1.0, 0.0]))  # T < 0
    assert all(math.isnan(v) for v in ode.rhs(0.0, [math.log(0.7), 1.0, 1.0, 0.0]))  # ν > ν_m


def test_scalar_rhs_code_is_cached_and_reproducible(tmp_path, monkeypatch):
    """A fresh derivation into an empty cache gives the same function values as the cached
    code (the generated source is a pure function of the derivation)."""
    m = ChuteModel()
    cached = _scalar_ode.scalar_rhs(*m.closures)
    monkeypatch.setenv("CHUTEFLOW_CACHE_DIR", str(tmp_path))
    _scalar_ode.scalar_rhs.cache_clear()
    try:
        fresh = _scalar_ode.scalar_rhs(*m.closures)
        assert list((tmp_path / "codegen").glob("steady_ode-*.py"))
        args = (0.05, 10.0, 3.0, -0.2, *m._params, math.sin(0.3), math.cos(0.3))
        assert fresh(*args) == cached(*args)
    finally:
        _scalar_ode.scalar_rhs.cache_clear()
