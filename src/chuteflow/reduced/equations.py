"""The depth-averaged equations of the 1D model (§5.1.2), stated once, and what follows from them.

The 1D model for the one-dimensional density ρ̄(x, t) and the mean velocity ū(x, t) is a
balance law in the conserved variables (ρ̄, m = ρ̄ū)::

    ∂t ρ̄ + ∂x f_ρ = 0,                 f_ρ = ρ̄ ū,
    ∂t m + ∂x f_m = S,                 f_m = ρ̄ ū² + ρ̄ T̄(ρ̄) − μ̄(ρ̄) ∂x ū,
                                       S   = ρ̄ sin θ − a(ρ̄) ū,

which is the pair of equations of §5.1.2 (continuity and the momentum balance with the floor
drag a(ρ̄)[U(ρ̄) − ū], U = ρ̄ sin θ / a). The closures T̄(ρ̄), a(ρ̄), μ̄(ρ̄) are *undefined*
functions here: their values and slopes at a state are supplied numerically (exact at one
steady flow, or interpolated over the steady family), so the derivation below does not depend
on how they are obtained. The viscosity closure is stated separately,
μ̄ = (4/3) f2(0) H(T̄) √T̄ with H = T̄ / cos θ (§5.1.2, approximation iii).

From this one statement (:data:`MASS_FLUX`, :data:`MOMENTUM_FLUX`, :data:`SOURCE`,
:data:`VISCOSITY`) sympy derives, once per process and on first use,

* the uniform state: U(ρ̄) solves S(ρ̄, U) = 0; the pressure P = ρ̄T̄ is the part of f_m
  independent of ū; the flux q0 = f_ρ(ρ̄, U); and their ρ̄-derivatives
  (:func:`uniform_state`);
* f_m and S and their pointwise partial derivatives, from which the finite-volume scheme, its
  exact Jacobian and its Fourier symbol are assembled (:func:`momentum_flux`, :func:`source`,
  :func:`flux_partials`, :func:`source_partials`);
* the linearisation about a uniform state for a normal mode exp(αt + ikx) in (ρ̂, û): the
  2×2 matrix M(k) (:func:`linear_matrix`) and the coefficients b, c of its characteristic
  polynomial in λ = α + ikU, λ² + bλ + c = 0 (:func:`dispersion_coefficients`).

Every numeric function takes the closure values as an object with attributes ``Tbar``,
``dTbar``, ``a``, ``da``, ``mu_bar``, ``dmu_bar`` (e.g. :class:`ClosureValues` or a
:class:`~chuteflow.reduced.LocalCoefficients`); an attribute an expression does not use may
be ``None``.
"""

from __future__ import annotations

import functools
import math
from typing import Any, NamedTuple

import numpy as np
import sympy as sp

__all__ = [
    "ClosureValues",
    "derivation",
    "MASS_FLUX",
    "MOMENTUM_FLUX",
    "SOURCE",
    "VISCOSITY",
    "momentum_flux",
    "source",
    "flux_partials",
    "source_partials",
    "uniform_state",
    "viscosity",
    "linear_matrix",
    "dispersion_coefficients",
]

# -- the statement ------------------------------------------------------------------------
RHO, U, UX = sp.symbols("rho u u_x", real=True)
SIN_THETA, COS_THETA, F2_0, K = sp.symbols("sin_theta cos_theta f2_0 k", real=True)
_T, _A, _MU = sp.Function("Tbar"), sp.Function("a"), sp.Function("mu_bar")

#: Mass flux f_ρ(ρ̄, ū) of the continuity equation.
MASS_FLUX = RHO * U
#: Momentum flux f_m(ρ̄, ū, ∂x ū): advection, depth-integrated pressure ρ̄T̄, viscous stress.
MOMENTUM_FLUX = RHO * U**2 + RHO * _T(RHO) - _MU(RHO) * UX
#: Momentum source S(ρ̄, ū): gravity along the slope and floor drag.
SOURCE = RHO * SIN_THETA - _A(RHO) * U
#: Viscosity closure μ̄(T̄) = (4/3) f2(0) H √T̄, H = T̄ / cos θ (as an expression in T̄).
_TB = sp.Symbol("Tbar", positive=True)
VISCOSITY = sp.Rational(4, 3) * F2_0 * (_TB / COS_THETA) * sp.sqrt(_TB)

# -- numeric closure values ---------------------------------------------------------------
_CLOSURE = ("Tbar", "dTbar", "a", "da", "mu_bar", "dmu_bar")
_CSYM = sp.symbols(" ".join(_CLOSURE), real=True)


class ClosureValues(NamedTuple):
    """Values and ρ̄-slopes of the closures T̄, a, μ̄ at the points where the model is evaluated
    (scalars or arrays; ``None`` for what an expression does not need)."""

    Tbar: Any = None
    dTbar: Any = None
    a: Any = None
    da: Any = None
    mu_bar: Any = None
    dmu_bar: Any = None


def _numeric(expr):
    """Replace the undefined closures and their first derivatives by value symbols."""
    subs = {}
    for f, (_v, d) in ((_T, _CSYM[0:2]), (_A, _CSYM[2:4]), (_MU, _CSYM[4:6])):
        subs[sp.Derivative(f(RHO), RHO)] = d
    expr = sp.sympify(expr).subs(subs)
    return expr.subs({_T(RHO): _CSYM[0], _A(RHO): _CSYM[2], _MU(RHO): _CSYM[4]})


_ARGS = (RHO, U, UX, SIN_THETA) + _CSYM


def _lambdify(exprs, extra=()):
    return sp.lambdify(extra + _ARGS, [_numeric(e) for e in exprs], modules="numpy", cse=True)


#: Symbol of the uniform velocity U0 in :func:`derivation` (``matrix``, ``quadratic``).
U0 = sp.Symbol("U_0", real=True)


@functools.cache
def derivation() -> dict:
    """Everything derived from the statement, as sympy expressions (closures undefined).

    Keys: ``flux``, ``source`` ([f_m], [S]); ``flux_partials``, ``source_partials``;
    ``uniform`` ([U, U', P, P', q0, q0']); ``matrix`` (the four entries of M(k), row by row,
    in :data:`K` and :data:`U0`); ``quadratic`` ([b, c]).
    """
    fm, s = MOMENTUM_FLUX, SOURCE
    out = {}
    out["flux"] = [fm]
    out["source"] = [s]
    out["flux_partials"] = [sp.diff(fm, RHO), sp.diff(fm, U), sp.diff(fm, UX)]
    out["source_partials"] = [sp.diff(s, RHO), sp.diff(s, U)]
    # uniform state: S(ρ̄, U) = 0, ∂x = 0
    (u0,) = sp.solve(sp.Eq(s, 0), U)
    pressure = fm.subs({U: 0, UX: 0})
    q0 = MASS_FLUX.subs(U, u0)
    out["uniform"] = [u0, sp.diff(u0, RHO), pressure, sp.diff(pressure, RHO), q0, sp.diff(q0, RHO)]
    # linearisation about (ρ0, U0, ∂x ū = 0) for exp(αt + ikx) in (ρ̂, û)
    rh, uh = sp.symbols("rho_hat u_hat")

    def lin(f):
        d = sp.diff(f, RHO) * rh + sp.diff(f, U) * uh + sp.diff(f, UX) * sp.I * K * uh
        return d.subs({U: U0, UX: 0})

    rho_t = -sp.I * K * lin(MASS_FLUX)
    m_t = -sp.I * K * lin(fm) + lin(s)
    u_t = sp.expand((m_t - U0 * rho_t) / RHO)  # m = ρ̄ū: ∂t m = ρ0 ∂t û + U0 ∂t ρ̂
    rho_t = sp.expand(rho_t)
    M = sp.Matrix([[rho_t.coeff(rh), rho_t.coeff(uh)], [u_t.coeff(rh), u_t.coeff(uh)]])
    out["matrix"] = list(M)
    # characteristic polynomial in λ = α + ikU0: λ² + bλ + c
    shifted = M + sp.I * K * U0 * sp.eye(2)
    out["quadratic"] = [sp.simplify(-shifted.trace()), sp.expand(shifted.det())]
    return out


@functools.cache
def _derived():
    """Lambdify (once per process) everything :func:`derivation` gives."""
    d = derivation()
    out = {
        name: _lambdify(d[name]) for name in ("flux", "source", "flux_partials", "source_partials", "uniform")
    }
    for name in ("matrix", "quadratic"):
        out[name] = _lambdify(d[name], extra=(K, U0))
    out["viscosity"] = sp.lambdify(
        (_TB, COS_THETA, F2_0), [VISCOSITY, sp.diff(VISCOSITY, _TB)], modules="numpy"
    )
    return out


def _call(name, rho, u, ux, sin_theta, c: ClosureValues, *extra):
    vals = [getattr(c, n) for n in _CLOSURE]
    return _derived()[name](*extra, rho, u, ux, sin_theta, *vals)


def momentum_flux(rho, u, ux, closure) -> np.ndarray:
    """f_m = ρ̄ū² + ρ̄T̄ − μ̄ ∂xū (needs ``Tbar``, ``mu_bar``)."""
    return _call("flux", rho, u, ux, 0.0, closure)[0]


def source(rho, u, sin_theta: float, closure) -> np.ndarray:
    """S = ρ̄ sin θ − a ū (needs ``a``)."""
    return _call("source", rho, u, 0.0, sin_theta, closure)[0]


class FluxPartials(NamedTuple):
    """∂f_m/∂ρ̄ (closure slopes included), ∂f_m/∂ū and ∂f_m/∂(∂xū)."""

    rho: Any
    u: Any
    ux: Any


class SourcePartials(NamedTuple):
    """∂S/∂ρ̄ (closure slope included) and ∂S/∂ū."""

    rho: Any
    u: Any


def flux_partials(rho, u, ux, closure) -> FluxPartials:
    """Partial derivatives of the momentum flux f_m (needs ``Tbar``, ``dTbar``, ``mu_bar``,
    ``dmu_bar``)."""
    return FluxPartials(*_call("flux_partials", rho, u, ux, 0.0, closure))


def source_partials(rho, u, sin_theta: float, closure) -> SourcePartials:
    """Partial derivatives of the source S (needs ``a``, ``da``)."""
    return SourcePartials(*_call("source_partials", rho, u, 0.0, sin_theta, closure))


class UniformState(NamedTuple):
    """The uniform flow at ρ̄ and the ρ̄-derivatives along the family (primes: d/dρ̄)."""

    U: Any
    dU: Any
    P: Any
    dP: Any
    q0: Any
    dq0: Any


def uniform_state(rho, sin_theta: float, closure) -> UniformState:
    """U(ρ̄) (root of S(ρ̄, U) = 0), P = ρ̄T̄, q0 = ρ̄U and their ρ̄-derivatives."""
    return UniformState(*_call("uniform", rho, 0.0, 0.0, sin_theta, closure))


def viscosity(Tbar, dTbar, theta: float, f2_0: float) -> tuple:
    """μ̄ = (4/3) f2(0) H(T̄) √T̄ (H = T̄/cos θ, θ in degrees) and μ̄' = (dμ̄/dT̄) T̄'."""
    mu, dmu_dT = _derived()["viscosity"](Tbar, math.cos(math.radians(theta)), f2_0)
    return mu, dmu_dT * dTbar


def linear_matrix(k, rho0: float, U0: float, sin_theta: float, closure) -> np.ndarray:
    """M(k) of α (ρ̂, û) = M(k) (ρ̂, û) about the uniform state (ρ0, U0); shape
    ``k.shape + (2, 2)``."""
    k = np.asarray(k, dtype=float)
    entries = _call("matrix", rho0, U0, 0.0, sin_theta, closure, k, U0)
    M = np.empty(k.shape + (2, 2), dtype=complex)
    for idx, e in zip(((0, 0), (0, 1), (1, 0), (1, 1)), entries):
        M[(...,) + idx] = e
    return M


def dispersion_coefficients(k, rho0: float, U0: float, sin_theta: float, closure) -> tuple:
    """(b, c) of λ² + bλ + c = 0, λ = α + ikU0, for the eigenvalues α of :func:`linear_matrix`."""
    k = np.asarray(k, dtype=float)
    b, c = _call("quadratic", rho0, U0, 0.0, sin_theta, closure, k, U0)
    return np.asarray(b + 0.0 * k), np.asarray(c + 0j * k)
