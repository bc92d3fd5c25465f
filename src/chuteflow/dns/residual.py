"""The nonlinear residual of the governing equations at an arbitrary (x, y)-dependent state.

Nothing of the physics is retyped here: the residuals of eqs (2.1)–(2.3) and of the floor
conditions (2.9), (2.10) are those of :func:`chuteflow.equations.governing_equations`, in
jet space. sympy compiles each one, with w ≡ 0 and no z dependence, into a numeric function
of all its jets — every field f ∈ (ν, u, v, T) with ∂_t f and its x, y derivatives up to
second order — and of the closures' values and partial derivatives (supplied numerically
by :meth:`chuteflow.closures.ChuteModel.evaluate`). The generated code is cached on disk
(:func:`chuteflow._codegen.cached_lambdify`, keyed by the source of :mod:`chuteflow.equations`,
of the closure model and of this module).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from .. import _codegen
from .. import equations as eqs
from ..closures import ChuteModel
from ..closures.model import FUNCTIONS, ORDERS

__all__ = [
    "DNS_FIELDS",
    "DNS_EQUATIONS",
    "JETS",
    "CompiledResidual",
    "compiled_residuals",
    "evaluate_residuals",
]

#: Fields of the two-dimensional simulation (w ≡ 0).
DNS_FIELDS = ("nu", "u", "v", "T")
#: Equations compiled for the simulation: the bulk balances and the floor conditions.
DNS_EQUATIONS = ("mass", "xmom", "ymom", "energy", "floor_v", "floor_x", "floor_energy")
#: Derivative orders (t, x, y) of the jets a residual may contain.
JETS = ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 2, 0), (0, 1, 1), (0, 0, 2))

sp = _codegen.lazy_module("sympy")


def _is_jet(sym) -> bool:
    parts = getattr(sym, "name", "").rsplit("_", 1)
    return len(parts) == 2 and parts[0] in eqs.FIELDS and len(parts[1]) == 4 and parts[1].isdigit()


def jet_name(field: str, order: tuple[int, int, int]) -> str:
    """Key of a jet in the state dictionaries: ``"u_x"``, ``"T_yy"``, ``"nu_t"``, ``"v"``."""
    t, x, y = order
    suffix = "t" * t + "x" * x + "y" * y
    return f"{field}_{suffix}" if suffix else field


@dataclass(frozen=True)
class CompiledResidual:
    """One equation's residual as a numeric function of the jets and the closures.

    Attributes
    ----------
    name : str
        Equation name (a key of :func:`chuteflow.equations.governing_equations`).
    jets : tuple of str
        The jets (:func:`jet_name`) the residual depends on, in argument order.
    """

    name: str
    jets: tuple[str, ...]
    _fun: Callable

    def __call__(
        self, state: Mapping[str, np.ndarray], partials: Mapping, sin_theta: float, cos_theta: float
    ):
        """Residual at every point of ``state`` (jet name → array)."""
        args = [state[j] for j in self.jets]
        for name in FUNCTIONS:
            args.extend(partials[name][o] for o in ORDERS)
        out = self._fun(*args, sin_theta, cos_theta)[0]
        return np.broadcast_to(out, np.shape(state["nu"]))


def _derive():
    gov = eqs.governing_equations()
    nu, T = eqs.jet("nu"), eqs.jet("T")
    psyms = {(n, o): sp.Symbol(f"{n}__{o[0]}{o[1]}", real=True) for n in FUNCTIONS for o in ORDERS}

    def deriv(d):
        counts = dict(d.variable_count)
        return psyms[(d.expr.func.__name__, (int(counts.get(nu, 0)), int(counts.get(T, 0))))]

    def replace(expr):
        expr = expr.replace(lambda e: isinstance(e, sp.Derivative), deriv)
        return expr.replace(
            lambda e: isinstance(e, sp.core.function.AppliedUndef), lambda e: psyms[(e.func.__name__, (0, 0))]
        )

    keep = {eqs.jet(f, t, x, y): jet_name(f, (t, x, y)) for f in DNS_FIELDS for (t, x, y) in JETS}
    spec, data = {}, []
    for name in DNS_EQUATIONS:
        R = replace(gov[name])
        zero = {s: sp.S.Zero for s in R.free_symbols if _is_jet(s) and s not in keep}
        R = sp.expand(R.xreplace(zero))
        used = sorted((s for s in R.free_symbols if s in keep), key=lambda s: keep[s])
        extra = [s for s in R.free_symbols if _is_jet(s) and s not in keep]
        if extra:  # pragma: no cover - the governing equations are second order
            raise AssertionError(f"{name}: jets beyond second order {extra}")
        sin_theta, cos_theta = sp.symbols("sin_theta cos_theta", real=True)
        args = used + [psyms[(n, o)] for n in FUNCTIONS for o in ORDERS] + [sin_theta, cos_theta]
        spec[name] = (args, [R])
        data.append((name, tuple(keep[s] for s in used)))
    return spec, tuple(data)


@functools.cache
def compiled_residuals() -> dict[str, CompiledResidual]:
    """Every equation of :data:`DNS_EQUATIONS` as a :class:`CompiledResidual` (once per process)."""
    code = _codegen.cached_lambdify(
        "dns_residual",
        "dns_residual",
        _derive,
        sources=(__name__, "chuteflow.equations", "chuteflow.closures.model"),
    )
    return {name: CompiledResidual(name, tuple(jets), code[name]) for name, jets in code.data}


def evaluate_residuals(
    state: Mapping[str, np.ndarray], model: ChuteModel, theta: float, names=DNS_EQUATIONS
) -> tuple[dict[str, np.ndarray], dict]:
    """Residuals of ``names`` at ``state`` and the closures' partials there.

    Parameters
    ----------
    state : mapping
        Jet name (:func:`jet_name`) → array, for every jet of :data:`JETS` of every field of
        :data:`DNS_FIELDS` (all of the same shape).
    model : ChuteModel
        Closures and parameters.
    theta : float
        Inclination in degrees.

    Returns
    -------
    (dict, dict)
        Equation name → residual array (sign convention of :mod:`chuteflow.equations`:
        N(X) − B ∂_t X), and the partials of :meth:`ChuteModel.evaluate`.
    """
    th = math.radians(theta)
    part = model.evaluate(state["nu"], state["T"], compiled=True)
    comp = compiled_residuals()
    return {n: comp[n](state, part, math.sin(th), math.cos(th)) for n in names}, part
