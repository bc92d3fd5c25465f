"""The governing equations, stated once, and their exact linearisation.

The hydrodynamic equations (2.1), (2.2), (2.3) with the constitutive relations of
eq. (2.7) and the floor conditions eqs (2.9), (2.10) are written here a single time, in
*jet space*: every field f ∈ (ν, u, v, w, T) and each of its partial derivatives
∂_t^a ∂_x^b ∂_y^c ∂_z^d f is an independent symbol, and the total derivative D_x, D_y, …
is the chain rule over those symbols. Transport functions p(ν, T), μ, ζ, κ, Γ and the floor
terms η*, Γ* are *undefined* functions: their partial derivatives are supplied numerically
by :class:`chuteflow.closures.ChuteModel`, so the derivation below is closure independent.

From this one statement sympy derives

* the residual of each equation at a state uniform along the slope (``v = w = 0``, fields
  depending on ``y`` only): the steady equations of §3 (eqs 3.4–3.6);
* the coefficient of every perturbation jet, ∂R/∂J at such a state: the linear operator
  of Appendix A (eqs A 1 … A 4, A 5, A 6), for a normal mode
  exp(αt + i k_x x + i k_z z) where a jet (a, b, c, d) of a field becomes
  α^a (i k_x)^b (i k_z)^d d^c/dy^c. The same coefficients at an arbitrary y-dependent state
  are the exact Jacobian used by the steady Newton solver.

Two further statements sit next to the governing equations and go through the same
derivation (:func:`compiled_equations` compiles all three sets):

* :func:`first_integrals` — the x-momentum balance of a flow uniform along the slope,
  integrated from the top with the stress vanishing there (§3, eq. (3.7)): built from the
  stress tensor Σ and the gravity vector of the governing equations, not retyped;
* :func:`far_field_conditions` — the top (y → ∞) conditions on a normal-mode perturbation
  (§4.1, eq. (4.5) and the density decay condition stated after it), with
  |k| = √(k_x² + k_z²) the symbol :data:`K_ABS`, so the three-dimensional case is covered.

Residual sign convention: every equation is written as ``N(X) − B ∂_t X = 0`` so that the
coefficient of α is −B with B = diag(1, ν, ν, ν, 3ν/2) positive.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from . import _codegen
from .closures.model import FUNCTIONS, ORDERS

FIELDS = ("nu", "u", "v", "w", "T")
AXES = ("t", "x", "y", "z")
#: Base-state (y-dependent) quantities the coefficients depend on.
BASE = ("nu", "nu_y", "nu_yy", "u", "u_y", "u_yy", "T", "T_y", "T_yy")
BULK = ("mass", "xmom", "ymom", "zmom", "energy")
FLOOR = ("floor_v", "floor_x", "floor_z", "floor_energy")
#: First integrals of the uniform steady state (:func:`first_integrals`).
INTEGRATED = ("xmom_integrated",)
#: Far-field (top) condition of each field's perturbation (:func:`far_field_conditions`).
TOP_OF = {"nu": "top_nu", "u": "top_u", "v": "top_v", "w": "top_w", "T": "top_T"}
#: The wavenumber magnitude |k| = √(k_x² + k_z²) of a normal mode exp(αt + i k_x x + i k_z z).
#: It is not a polynomial in the jets (∂_x ↦ ik_x, ∂_z ↦ ik_z), so it is a symbol of its own;
#: a compiled term records its power in :attr:`Term.k`. ``K_ABS`` is created on first use
#: (module ``__getattr__``), so that importing this module does not import sympy.

#: sympy, imported on first use: a process whose generated code is cached never needs it.
if TYPE_CHECKING:  # the annotations name sympy's classes; at run time sympy stays lazy
    import sympy as sp
else:
    sp = _codegen.lazy_module("sympy")


def _gravity_symbols():
    """Symbols sin θ and cos θ of the gravity vector (sympy caches equal symbols)."""
    return sp.symbols("sin_theta cos_theta", real=True)


def _k_abs():
    """The symbol |k| = √(k_x² + k_z²) (:data:`K_ABS`)."""
    return sp.Symbol("k_abs", nonnegative=True)


def __getattr__(name: str):
    if name == "K_ABS":
        return _k_abs()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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


def base_value(name: str) -> sp.Symbol:
    """Symbol for a base-state quantity (a key of :data:`BASE`) that is *not* linearised.

    :func:`compiled_equations` maps the jets ν, ν_y, …, T_yy of a state uniform along the
    slope to these symbols; a condition may also use one directly, as a coefficient that
    belongs to the base flow (the density decay rate cos θ/T0 of
    :func:`far_field_conditions`).
    """
    if name not in BASE:
        raise ValueError(f"{name!r} is not a base-state quantity; choose one of {BASE}")
    return sp.Symbol(f"base_{name}", real=True)


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


@dataclass(frozen=True)
class _Continuum:
    """Constitutive statement shared by every equation below (eq. 2.7)."""

    F: dict  # p, mu, zeta, kappa, Gamma, eta_star, Gamma_star as functions of (ν, T)
    vel: tuple  # (u, v, w) jets
    grad: tuple  # grad[i][j] = ∂_j u_i
    Sigma: tuple  # stress tensor Σ_ij
    q: tuple  # heat flux
    g: tuple  # gravity (sin θ, −cos θ, 0)
    div: sp.Expr  # ∇·u


@functools.cache
def _continuum() -> _Continuum:
    """Σ = (p − ζ∇·u)I − 2μS, q = −κ∇T − κ_h∇ν (eq. 2.7 with the paper's footnoted
    density-gradient term) and gravity, in jet space."""
    nu, T = jet("nu"), jet("T")
    vel = [jet("u"), jet("v"), jet("w")]
    F = {name: sp.Function(name)(nu, T) for name in FUNCTIONS}
    sp_axes = ("x", "y", "z")
    grad = [[D(vel[i], sp_axes[j]) for j in range(3)] for i in range(3)]  # ∂_j u_i
    div = grad[0][0] + grad[1][1] + grad[2][2]
    S = [
        [(grad[i][j] + grad[j][i]) / 2 - (sp.Rational(1, 3) * div if i == j else 0) for j in range(3)]
        for i in range(3)
    ]
    Sigma = [
        [(F["p"] - F["zeta"] * div if i == j else 0) - 2 * F["mu"] * S[i][j] for j in range(3)]
        for i in range(3)
    ]
    # q = −κ∇T − κ_h∇ν: Lun et al. (1984) and Garzó & Dufty (1999) both have the
    # density-gradient term; the paper (footnote to eq. 2.7) drops it (κ_h = 0 for the
    # ``lun`` closure, which leaves every equation as the paper states it)
    q = [-F["kappa"] * D(T, a) - F["kappa_h"] * D(nu, a) for a in sp_axes]
    sin_theta, cos_theta = _gravity_symbols()
    g = (sin_theta, -cos_theta, sp.S.Zero)
    return _Continuum(F, tuple(vel), tuple(map(tuple, grad)), tuple(map(tuple, Sigma)), tuple(q), g, div)


@functools.cache
def governing_equations() -> dict[str, sp.Expr]:
    """Residuals of eqs (2.1), (2.2) (x, y, z), eq. (2.3) and the floor conditions, in jet space.

    Dimensionless (σ, ρ_p σ³, √(σ/g)); gravity g = (sin θ, −cos θ, 0); Σ = (p − ζ∇·u)I − 2μS,
    q = −κ∇T − κ_h∇ν (eq. 2.7; the paper's footnote to it: Lun et al.'s κ_h term, which the
    paper drops — the ``lun`` closure has κ_h = 0). Floor normal n = e_y.

    The collisional energy sink is Γ + Γ_U ∇·u: Γ = (3/2) ν T ζ^(0) of eq. (2.3) and the
    first-order cooling rate of Garzó & Dufty (1999), (3/2) ν T ζ_U ∇·u (Γ_U = 0 for the
    paper's ``lun`` and for ``lun_full``, which leaves eq. (2.3) as the paper states it). It
    vanishes in the steady flows (∇·u = 0) but not in their perturbations.

    The floor energy condition (2.10) is the paper's, q·n + u·Σ·n + Γ* = 0 (sign as below),
    with q the whole heat flux: the energy the flow loses through the floor is the normal
    flux whatever its constitutive form, so a closure with κ_h ≠ 0 has −κ_h ν_y in it too.
    """
    c = _continuum()
    nu, T = jet("nu"), jet("T")
    F, vel, grad, Sigma, q, g = c.F, c.vel, c.grad, c.Sigma, c.q, c.g
    sp_axes = ("x", "y", "z")

    def material(fld):  # ∂_t f + u·∇f
        return D(fld, "t") + sum(vel[j] * D(fld, sp_axes[j]) for j in range(3))

    eqs = {"mass": -D(nu, "t") - sum(D(nu * vel[j], sp_axes[j]) for j in range(3))}
    for i, name in enumerate(("xmom", "ymom", "zmom")):
        eqs[name] = nu * g[i] - sum(D(Sigma[j][i], sp_axes[j]) for j in range(3)) - nu * material(vel[i])
    eqs["energy"] = (
        -sum(D(q[j], sp_axes[j]) for j in range(3))
        - sum(Sigma[i][j] * grad[j][i] for i in range(3) for j in range(3))
        - F["Gamma"]
        - F["Gamma_U"] * c.div
        - sp.Rational(3, 2) * nu * material(T)
    )
    # floor y = 0, n = e_y: impermeable; eq. (2.9) (tangential momentum); eq. (2.10) (energy)
    eqs["floor_v"] = vel[1]
    eqs["floor_x"] = -Sigma[1][0] - F["eta_star"] * vel[0]
    eqs["floor_z"] = -Sigma[1][2] - F["eta_star"] * vel[2]
    eqs["floor_energy"] = -(q[1] + vel[0] * Sigma[0][1] + vel[2] * Sigma[2][1] + F["Gamma_star"])
    return {k: sp.expand(v) for k, v in eqs.items()}


@functools.cache
def first_integrals() -> dict[str, sp.Expr]:
    """The x-momentum balance of a uniform steady flow, integrated from the top (§3).

    For a state uniform along the slope (v = w = 0, fields of y only) the x- and y-momentum
    residuals of :func:`governing_equations` are ν g_x − dΣ_yx/dy and ν g_y − dΣ_yy/dy.
    Integrated from y to ∞ with the stress vanishing there (eq. (2.15)), both give the
    weight W(y) = ∫_y^∞ ν dy' of the layer above y: Σ_yx = −g_x W and Σ_yy = −g_y W.
    Eliminating W gives eq. (3.7), Σ_xy = −tan θ Σ_yy, stated here as the residual

        xmom_integrated = −(Σ_yx − (g_x/g_y) Σ_yy)  (= μ u0' − tan θ p at the steady state),

    whose y-derivative is xmom − (g_x/g_y) ymom at a uniform state (checked in the tests).
    Unlike the x-momentum balance it keeps the weight of the layer above any finite
    y_max, and it is first order in u. It holds only at states uniform along the slope; its
    coefficients (∂R/∂J) are the exact Jacobian of the steady solver's x-momentum rows.
    """
    c = _continuum()
    gx, gy = c.g[0], c.g[1]
    return {"xmom_integrated": sp.expand(-(c.Sigma[1][0] - gx / gy * c.Sigma[1][1]))}


@functools.cache
def far_field_conditions() -> dict[str, sp.Expr]:
    """Top (y → ∞) conditions on a normal-mode perturbation (§4.1), keyed by :data:`TOP_OF`.

    Far above the dense layer, where ν0 is negligible, the velocity and temperature
    perturbations decay like exp(−|k| y) (eq. (4.5), with |k| = √(k_x² + k_z²) :data:`K_ABS`
    for an oblique wavevector), and the density perturbation follows the base density,
    ν̂ ∝ ν0 ∝ exp(−y cos θ/T0) (the isothermal atmosphere; §4.1, second extra condition):

        f_y + |k| f = 0   (f = u, v, w, T),        ν_y + (cos θ/T0) ν = 0.

    These are linear in the perturbation, so the coefficients ∂R/∂J that
    :func:`compiled_equations` derives are the top rows of the stability operator; T0 in
    the density condition is the base state's (:func:`base_value`), not linearised. At
    |k| = 0 and at the base state the velocity and temperature conditions are the steady
    top conditions u0' = 0 and T0' = 0 (eq. (3.13)), which is how the steady solver uses
    them (the compiled residual is evaluated with |k| = 0).
    """
    out = {TOP_OF["nu"]: D(jet("nu"), "y") + _gravity_symbols()[1] / base_value("T") * jet("nu")}
    for f in ("u", "v", "w", "T"):
        out[TOP_OF[f]] = D(jet(f), "y") + _k_abs() * jet(f)
    return {k: sp.expand(v) for k, v in out.items()}


def _base_substitution():
    """Map jets to the y-dependent base state: v = w = 0, no t, x, z dependence."""
    sub = {}
    base_syms = {b: base_value(b) for b in BASE}
    for f in ("nu", "u", "T"):
        for c, suffix in enumerate(("", "_y", "_yy")):
            sub[jet(f, y=c)] = base_syms[f + suffix]
    return sub, base_syms


def _partial_symbols():
    """Symbols standing for numeric partials, and a function replacing the sympy objects."""
    nu, T = jet("nu"), jet("T")
    syms = {(name, o): sp.Symbol(f"{name}__{o[0]}{o[1]}", real=True) for name in FUNCTIONS for o in ORDERS}

    def replace(expr):
        def deriv(d):
            counts = dict(d.variable_count)
            o = (int(counts.get(nu, 0)), int(counts.get(T, 0)))
            return syms[(d.expr.func.__name__, o)]

        expr = expr.replace(lambda e: isinstance(e, sp.Derivative), deriv)
        return expr.replace(
            lambda e: isinstance(e, sp.core.function.AppliedUndef), lambda e: syms[(e.func.__name__, (0, 0))]
        )

    return syms, replace


@dataclass(frozen=True)
class Term:
    """One term of the linear operator: coefficient × α^a (i k_x)^b (i k_z)^d |k|^k d^c/dy^c.

    ``k`` is the power of |k| = √(k_x² + k_z²) (:data:`K_ABS`); only the far-field
    conditions have terms with k > 0.
    """

    field: str
    a: int
    b: int
    c: int
    d: int
    index: int  # position of the coefficient in the equation's compiled output
    k: int = 0


@dataclass(frozen=True)
class CompiledEquation:
    """Residual and operator coefficients of one equation at a y-dependent base state."""

    name: str
    terms: tuple[Term, ...]
    _fun: Callable

    def evaluate(self, base: dict, partials: dict, sin_theta: float, cos_theta: float):
        """Return (residual, [coefficient arrays in the order of ``terms``])."""
        return self.evaluate_arguments(arguments(base, partials, sin_theta, cos_theta))

    def evaluate_arguments(self, args: list):
        """:meth:`evaluate` from the argument list of :func:`arguments` (built once for
        several equations at the same state)."""
        out = self._fun(*args)
        return out[0], out[1:]


def arguments(base: dict, partials: dict, sin_theta: float, cos_theta: float) -> list:
    """The argument list every compiled equation takes: the base-state jets (:data:`BASE`),
    the closures' partials (:data:`FUNCTIONS` × :data:`ORDERS`), sin θ and cos θ."""
    args = [base[b] for b in BASE]
    for name in FUNCTIONS:
        args.extend(partials[name][o] for o in ORDERS)
    return args + [sin_theta, cos_theta]


@functools.cache
def compiled_equations() -> dict[str, CompiledEquation]:
    """Every equation's residual and coefficients as numeric functions (once per process).

    Covers :func:`governing_equations`, :func:`first_integrals` and
    :func:`far_field_conditions`. A coefficient that depends on |k| (:data:`K_ABS`) is split
    into one term per power of |k| (:attr:`Term.k`); the residual is evaluated at |k| = 0.
    Derived by :func:`_derive_compiled`; the generated code is cached on disk
    (:func:`chuteflow._codegen.cached_lambdify`, keyed by this module's and the closure
    model's source), so a fresh process loads it instead of deriving again.
    """
    code = _codegen.cached_lambdify(
        "equations", "compiled_equations", _derive_compiled, sources=(__name__, "chuteflow.closures.model")
    )
    return {
        name: CompiledEquation(name, tuple(Term(*t) for t in terms), code[name]) for name, terms in code.data
    }


def warm_up(model=None) -> None:
    """Build the generated code once in this process, so that processes forked from it
    inherit it instead of each building it again: :func:`compiled_equations` and, for a
    :class:`~chuteflow.closures.ChuteModel`, its closures' partial derivatives (the generated
    numpy code and, where a compiler is available, the compiled kernel that the steady
    solver uses) and the pair ``f``. Used by :func:`chuteflow.steady.steady_map` and the
    sweep's process pool before they fork."""
    compiled_equations()
    if model is not None:
        nu, T = np.array([0.1]), np.array([1.0])
        model.evaluate(nu, T)
        model.evaluate(nu, T, compiled=True)
        model.f(nu)


def _derive_compiled():
    """Residual and nonzero coefficients of each equation at a y-dependent base state.

    Returns ``({equation: (args, [residual, coefficients ...])}, ((equation, terms), ...))``
    with each term as the fields of :class:`Term`.
    """
    eqs = {**governing_equations(), **first_integrals(), **far_field_conditions()}
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
        exprs = [R.subs(_k_abs(), 0) if _k_abs() in R.free_symbols else R]
        found: list[Term] = []
        for s in jets:
            f, (a, b, c, d) = _parse(s)
            coef = sp.diff(R, s)
            for e, part in _powers_of_k(coef):
                exprs.append(part)
                found.append(Term(f, a, b, c, d, len(found), e))
        at_base = []
        for e in exprs:
            e = repl(sp.sympify(e)).xreplace(zero_jets).xreplace(sub)
            at_base.append(e)
        keep = [i for i, e in enumerate(at_base[1:]) if e != 0]
        terms = tuple(Term(t.field, t.a, t.b, t.c, t.d, j, t.k) for j, t in enumerate(found[i] for i in keep))
        spec[name] = (args, [at_base[0]] + [at_base[1 + i] for i in keep])
        data.append((name, tuple((t.field, t.a, t.b, t.c, t.d, t.index, t.k) for t in terms)))
    return spec, tuple(data)


def _powers_of_k(coef: sp.Expr) -> list[tuple[int, sp.Expr]]:
    """[(e, c_e)] with coef = Σ c_e |k|^e; a coefficient free of |k| is left untouched."""
    if _k_abs() not in coef.free_symbols:
        return [(0, coef)]
    poly = sp.Poly(sp.expand(coef), _k_abs())
    return sorted((int(e), c) for (e,), c in poly.terms())


def base_state(nu, u, T, D1, D2) -> dict[str, np.ndarray]:
    """Jets of a y-dependent state from nodal values and differentiation matrices."""
    return {
        "nu": nu,
        "nu_y": D1 @ nu,
        "nu_yy": D2 @ nu,
        "u": u,
        "u_y": D1 @ u,
        "u_yy": D2 @ u,
        "T": T,
        "T_y": D1 @ T,
        "T_yy": D2 @ T,
    }
