"""The statements next to the governing equations: first integral and far-field conditions.

Symbolic checks (sympy, no numerics): the integrated x-momentum of
:func:`chuteflow.equations.first_integrals` is a first integral of the governing x- and
y-momentum balances at a state uniform along the slope, and reduces to the paper's §3,
eq. (3.7) μ u0' = tan θ p; the far-field conditions of
:func:`chuteflow.equations.far_field_conditions` are those of §4.1, eq. (4.5) with
|k| = √(k_x² + k_z²), and are compiled with one term per power of |k|.
"""

from __future__ import annotations

import sympy as sp

from chuteflow.equations import (
    FIELDS,
    K_ABS,
    TOP_OF,
    D,
    base_value,
    compiled_equations,
    far_field_conditions,
    first_integrals,
    governing_equations,
    jet,
)


def _uniform(expr):
    """Restrict a jet-space expression to a state uniform along the slope: v = w = 0 and
    no t, x, z dependence (every such jet set to zero)."""
    zero = {}
    for s in expr.free_symbols:
        if not isinstance(s, sp.Symbol) or "_" not in s.name:
            continue
        name, idx = s.name.rsplit("_", 1)
        if name in FIELDS and len(idx) == 4 and idx.isdigit():
            t, x, _, z = (int(ch) for ch in idx)
            if name in ("v", "w") or t or x or z:
                zero[s] = 0
    return expr.xreplace(zero)


def test_integrated_xmom_is_a_first_integral():
    """d/dy of the integrated form equals xmom − (g_x/g_y) ymom = xmom + tan θ ymom at a
    uniform state, so integrating the two momentum balances from y to ∞ (stress-free
    there, eq. (2.15)) gives it exactly."""
    eqs = governing_equations()
    R = first_integrals()["xmom_integrated"]
    sin, cos = sp.symbols("sin_theta cos_theta", real=True)
    lhs = _uniform(D(R, "y"))
    rhs = _uniform(eqs["xmom"] + sin / cos * eqs["ymom"])
    assert sp.simplify(sp.expand(lhs - rhs)) == 0


def test_integrated_xmom_is_eq_3_7():
    """At a uniform state: Σ_xy = −μ u0', Σ_yy = p, so the residual is μ u0' − tan θ p
    (the steady solver's form of eq. (3.7), hand-written there before)."""
    R = _uniform(first_integrals()["xmom_integrated"])
    nu, T = jet("nu"), jet("T")
    mu, p = sp.Function("mu")(nu, T), sp.Function("p")(nu, T)
    sin, cos = sp.symbols("sin_theta cos_theta", real=True)
    assert sp.simplify(R - (mu * jet("u", y=1) - sin / cos * p)) == 0


def test_far_field_conditions_are_section_4_1():
    """û' = −|k| û, v̂' = −|k| v̂, ŵ' = −|k| ŵ, T̂' = −|k| T̂ and ν̂' = −(cos θ/T0) ν̂, the
    last with the base state's T0 (not linearised)."""
    far = far_field_conditions()
    cos = sp.Symbol("cos_theta", real=True)
    assert set(far) == set(TOP_OF.values())
    for f in ("u", "v", "w", "T"):
        assert sp.expand(far[TOP_OF[f]] - (jet(f, y=1) + K_ABS * jet(f))) == 0
    assert sp.expand(far[TOP_OF["nu"]] - (jet("nu", y=1) + cos / base_value("T") * jet("nu"))) == 0
    assert jet("T") not in far[TOP_OF["nu"]].free_symbols


def test_compiled_far_field_terms():
    """One term per power of |k| (Term.k), residual evaluated at |k| = 0; the governing
    equations have no |k| terms."""
    ce = compiled_equations()
    for f in ("u", "v", "w", "T"):
        terms = {(t.field, t.c, t.k) for t in ce[TOP_OF[f]].terms}
        assert terms == {(f, 1, 0), (f, 0, 1)}
    assert {(t.field, t.c, t.k) for t in ce[TOP_OF["nu"]].terms} == {("nu", 1, 0), ("nu", 0, 0)}
    for name in governing_equations():
        assert all(t.k == 0 for t in ce[name].terms), name
