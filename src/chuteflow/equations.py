"""The governing equations, stated once, and their exact linearisation.

The hydrodynamic equations eq:rho, eq:u, eq:temp with the constitutive relations of
eq:pmuetc and the floor conditions eq:bc1, eq:bc2 are written here a single time, in
*jet space*: every field f ∈ (ν, u, v, w, T) and each of its partial derivatives
∂_t^a ∂_x^b ∂_y^c ∂_z^d f is an independent symbol, and the total derivative D_x, D_y, …
is the chain rule over those symbols. Transport functions p(ν, T), μ, ζ, κ, Γ and the floor
terms η*, Γ* are *undefined* functions: their partial derivatives are supplied numerically
by :class:`chuteflow.closures.ChuteModel`, so the derivation below is closure independent.

From this one statement sympy derives

* the residual of each equation at a state uniform along the slope (``v = w = 0``, fields
  depending on ``y`` only): the steady equations of §3 (eq:steady1–3);
* the coefficient of every perturbation jet, ∂R/∂J at such a state: the linear operator
  of Appendix A (eq:leqnu … eq:leqT, eq:bc0u, eq:bc0T), for a normal mode
  exp(αt + i k_x x + i k_z z) where a jet (a, b, c, d) of a field becomes
  α^a (i k_x)^b (i k_z)^d d^c/dy^c. The same coefficients at an arbitrary y-dependent state
  are the exact Jacobian used by the steady Newton solver.

Residual sign convention: every equation is written as ``N(X) − B ∂_t X = 0`` so that the
coefficient of α is −B with B = diag(1, ν, ν, ν, 3ν/2) positive.
"""
from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import _codegen
from .closures.model import FUNCTIONS, ORDERS

FIELDS = ("nu", "u", "v", "w", "T")
AXES = ("t", "x", "y", "z")
#: Base-state (y-dependent) quantities the coefficients depend on.
BASE = ("nu", "nu_y", "nu_yy", "u", "u_y", "u_yy", "T", "T_y", "T_yy")
BULK = ("mass", "xmom", "ymom", "zmom", "energy")
FLOOR = ("floor_v", "floor_x", "floor_z", "floor_energy")

#: sympy, imported on first use: a process whose generated code is cached never needs it.
sp = _codegen.lazy_module("sympy")


def _gravity_symbols():
    """Symbols sin θ and cos θ of the gravity vector (sympy caches equal symbols)."""
    return sp.symbols("sin_theta cos_theta", real=True)


def jet(field: str, t: int = 0, x: int = 0, y: int = 0, z: int = 0) -> sp.Symbol:
    """Symbol for ∂_t^t ∂_x^x ∂_y^y ∂_z^z of ``field``."""
    return sp.Symbol(f"{field}_{t}{x}{y}{z}", real=True)


def _parse(sym: sp.Symbol):
    name, idx = sym.name.rsplit("_", 1)
    return name, tuple(int(ch) for ch in idx)


def _is_jet(sym) -> bool:
    if not isinstance(sym, sp.Symbol):
        return False
    parts = sym.name.rsplit("_", 1)
    return len(parts) == 2 and parts[0] in FIELDS and len(parts[1]) == 4 and parts[1].isdigit()


def D(expr: sp.Expr, axis: str) -> sp.Expr:
    """Total derivative of a jet-space expression along ``axis`` (chain rule over jets)."""
    k = AXES.index(axis)
    out = sp.S.Zero
    for s in expr.free_symbols:
        if _is_jet(s):
            f, idx = _parse(s)
            nxt = list(idx)
            nxt[k] += 1
            out += sp.diff(expr, s) * jet(f, *nxt)
    return out


@functools.lru_cache(maxsize=None)
def governing_equations() -> dict[str, sp.Expr]:
    """Residuals of eq:rho, eq:u (x, y, z), eq:temp and the floor conditions, in jet space.

    Dimensionless (σ, ρ_p σ³, √(σ/g)); gravity g = (sin θ, −cos θ, 0); Σ = (p − ζ∇·u)I − 2μS,
    q = −κ∇T (eq:pmuetc). Floor normal n = e_y.
    """
    nu, T = jet("nu"), jet("T")
    vel = [jet("u"), jet("v"), jet("w")]
    F = {name: sp.Function(name)(nu, T) for name in FUNCTIONS}
    sp_axes = ("x", "y", "z")
    grad = [[D(vel[i], sp_axes[j]) for j in range(3)] for i in range(3)]  # ∂_j u_i
    div = grad[0][0] + grad[1][1] + grad[2][2]
    S = [[(grad[i][j] + grad[j][i]) / 2 - (sp.Rational(1, 3) * div if i == j else 0)
          for j in range(3)] for i in range(3)]
    Sigma = [[(F["p"] - F["zeta"] * div if i == j else 0) - 2 * F["mu"] * S[i][j]
              for j in range(3)] for i in range(3)]
    q = [-F["kappa"] * D(T, a) for a in sp_axes]
    sin_theta, cos_theta = _gravity_symbols()
    g = (sin_theta, -cos_theta, sp.S.Zero)

    def material(fld):  # ∂_t f + u·∇f
        return D(fld, "t") + sum(vel[j] * D(fld, sp_axes[j]) for j in range(3))

    eqs = {"mass": -D(nu, "t") - sum(D(nu * vel[j], sp_axes[j]) for j in range(3))}
    for i, name in enumerate(("xmom", "ymom", "zmom")):
        eqs[name] = (nu * g[i] - sum(D(Sigma[j][i], sp_axes[j]) for j in range(3))
                     - nu * material(vel[i]))
    eqs["energy"] = (-sum(D(q[j], sp_axes[j]) for j in range(3))
                     - sum(Sigma[i][j] * grad[j][i] for i in range(3) for j in range(3))
                     - F["Gamma"] - sp.Rational(3, 2) * nu * material(T))
    # floor y = 0, n = e_y: impermeable; eq:bc1 (tangential momentum); eq:bc2 (energy)
    eqs["floor_v"] = vel[1]
    eqs["floor_x"] = -Sigma[1][0] - F["eta_star"] * vel[0]
    eqs["floor_z"] = -Sigma[1][2] - F["eta_star"] * vel[2]
    eqs["floor_energy"] = -(q[1] + vel[0] * Sigma[0][1] + vel[2] * Sigma[2][1] + F["Gamma_star"])
    return {k: sp.expand(v) for k, v in eqs.items()}


def _base_substitution():
    """Map jets to the y-dependent base state: v = w = 0, no t, x, z dependence."""
    nu, u, T = jet("nu"), jet("u"), jet("T")
    sub = {}
    base_syms = {b: sp.Symbol(f"base_{b}", real=True) for b in BASE}
    for f in ("nu", "u", "T"):
        for c, suffix in enumerate(("", "_y", "_yy")):
            sub[jet(f, y=c)] = base_syms[f + suffix]
    return sub, base_syms


def _partial_symbols():
    """Symbols standing for numeric partials, and a function replacing the sympy objects."""
    nu, T = jet("nu"), jet("T")
    syms = {(name, o): sp.Symbol(f"{name}__{o[0]}{o[1]}", real=True)
            for name in FUNCTIONS for o in ORDERS}

    def replace(expr):
        def deriv(d):
            counts = dict(d.variable_count)
            o = (int(counts.get(nu, 0)), int(counts.get(T, 0)))
            return syms[(d.expr.func.__name__, o)]
        expr = expr.replace(lambda e: isinstance(e, sp.Derivative), deriv)
        return expr.replace(lambda e: isinstance(e, sp.core.function.AppliedUndef),
                            lambda e: syms[(e.func.__name__, (0, 0))])
    return syms, replace


@dataclass(frozen=True)
class Term:
    """One term of the linear operator: coefficient × α^a (i k_x)^b (i k_z)^d d^c/dy^c."""

    field: str
    a: int
    b: int
    c: int
    d: int
    index: int  # position of the coefficient in the equation's compiled output


@dataclass(frozen=True)
class CompiledEquation:
    """Residual and operator coefficients of one equation at a y-dependent base state."""

    name: str
    terms: tuple[Term, ...]
    _fun: Callable

    def evaluate(self, base: dict, partials: dict, sin_theta: float, cos_theta: float):
        """Return (residual, [coefficient arrays in the order of ``terms``])."""
        out = self._fun(*_args(base, partials, sin_theta, cos_theta))
        return out[0], out[1:]


def _args(base, partials, s, c):
    args = [base[b] for b in BASE]
    for name in FUNCTIONS:
        for o in ORDERS:
            args.append(partials[name][o])
    return args + [s, c]


@functools.lru_cache(maxsize=None)
def compiled_equations() -> dict[str, CompiledEquation]:
    """Every equation's residual and coefficients as numeric functions (once per process).

    Derived from :func:`governing_equations` by :func:`_derive_compiled`; the generated code
    is cached on disk (:func:`chuteflow._codegen.cached_lambdify`, keyed by this module's and
    the closure model's source), so a fresh process loads it instead of deriving again.
    """
    code = _codegen.cached_lambdify("equations", "compiled_equations", _derive_compiled,
                                    sources=(__name__, "chuteflow.closures.model"))
    return {name: CompiledEquation(name, tuple(Term(*t) for t in terms), code[name])
            for name, terms in code.data}


def _derive_compiled():
    """Residual and nonzero coefficients of each equation at a y-dependent base state.

    Returns ``({equation: (args, [residual, coefficients ...])}, ((equation, terms), ...))``
    with each term as the fields of :class:`Term`.
    """
    eqs = governing_equations()
    sub, base_syms = _base_substitution()
    psyms, repl = _partial_symbols()
    zero_jets = {}
    for f in FIELDS:
        for idx in itertools.product(range(3), repeat=4):
            if sum(idx) > 3:
                continue
            s = jet(f, *idx)
            if s in sub:
                continue
            zero_jets[s] = sp.S.Zero
    args = [base_syms[b] for b in BASE] + [psyms[(n, o)] for n in FUNCTIONS for o in ORDERS]
    args += list(_gravity_symbols())
    spec, data = {}, []
    for name, R in eqs.items():
        jets = sorted((s for s in R.free_symbols if _is_jet(s)), key=lambda s: s.name)
        exprs = [R]
        terms = []
        for s in jets:
            f, (a, b, c, d) = _parse(s)
            coef = sp.diff(R, s)
            exprs.append(coef)
            terms.append(Term(f, a, b, c, d, len(terms)))
        at_base = []
        for e in exprs:
            e = repl(sp.sympify(e)).xreplace(zero_jets).xreplace(sub)
            at_base.append(e)
        keep = [i for i, e in enumerate(at_base[1:]) if e != 0]
        terms = tuple(Term(t.field, t.a, t.b, t.c, t.d, j) for j, t in
                      enumerate(terms[i] for i in keep))
        spec[name] = (args, [at_base[0]] + [at_base[1 + i] for i in keep])
        data.append((name, tuple((t.field, t.a, t.b, t.c, t.d, t.index) for t in terms)))
    return spec, tuple(data)


def base_state(nu, u, T, D1, D2) -> dict[str, np.ndarray]:
    """Jets of a y-dependent state from nodal values and differentiation matrices."""
    return {"nu": nu, "nu_y": D1 @ nu, "nu_yy": D2 @ nu, "u": u, "u_y": D1 @ u,
            "u_yy": D2 @ u, "T": T, "T_y": D1 @ T, "T_yy": D2 @ T}
