"""Constitutive relations of Lun et al. (1984): paper §2.1, Table 1.

Dimensionless (σ, ρ_p σ³, √(σ/g)) transport functions of packing fraction ν and
granular temperature T:

    p = f1 T,   μ = f2 √T,   ζ = f3 √T,   κ = f4 √T,   Γ = (1 − e_p²) f5 T^{3/2}.

The heat-flux term κ_h ∇ν is neglected, as in the paper (§2.1). A transport closure is a
small frozen class that states f1 … f7 and the transport functions in sympy, given g0(ν)
from the radial distribution function; register a new one with :func:`register_transport`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .._codegen import lazy_module
from .registry import Registry

__all__ = [
    "TRANSPORTS",
    "LunClosure",
    "TransportClosure",
    "lun_functions",
    "register_transport",
]

sp = lazy_module("sympy")  # imported on first use (cached generated code needs none)


def lun_functions(nu, e, nu_max, g0):
    """Return f1 … f7 of Table 1 as sympy expressions (η = (1 + e_p)/2)."""
    eta = (1 + e) / 2
    sqpi = sp.sqrt(sp.pi)
    f1 = nu * (1 + 4 * eta * nu * g0)
    f2 = (
        5
        * sqpi
        / (96 * eta * (2 - eta))
        * (1 + sp.Rational(8, 5) * eta * nu * g0)
        * (1 / g0 + sp.Rational(8, 5) * eta * (3 * eta - 2) * nu)
        + 8 / (5 * sqpi) * eta * nu**2 * g0
    )
    f3 = 8 / (3 * sqpi) * eta * nu**2 * g0
    f4 = (
        25
        * sqpi
        / (16 * eta * (41 - 33 * eta))
        * (1 + sp.Rational(12, 5) * eta * nu * g0)
        * (1 / g0 + sp.Rational(12, 5) * eta**2 * (4 * eta - 3) * nu)
        + 4 / sqpi * eta * nu**2 * g0
    )
    f5 = 12 / sqpi * nu**2 * g0
    f6 = sp.sqrt(3) * sp.pi * nu * g0 / (2 * nu_max * f4)
    f7 = sp.pi * nu * g0 / (2 * sp.sqrt(3) * nu_max * f2)
    return {"f1": f1, "f2": f2, "f3": f3, "f4": f4, "f5": f5, "f6": f6, "f7": f7}


@dataclass(frozen=True)
class TransportClosure:
    """Base class of the kinetic-theory (transport) closures.

    ``functions(nu, e, nu_max, g0)`` gives the functions f1 … f7 of ν (Table 1: the wall
    conditions use them too) and ``transport(f, T, e)`` the transport functions p, μ, ζ, κ,
    Γ from them, all as sympy expressions.
    """

    name: ClassVar[str] = "base"

    def functions(self, nu, e, nu_max, g0) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError

    def transport(self, f, T, e) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError


#: The transport closures, by name (the ``transport`` field of ChuteModel).
TRANSPORTS: Registry[TransportClosure] = Registry("transport", TransportClosure)
register_transport = TRANSPORTS.register


@register_transport
@dataclass(frozen=True)
class LunClosure(TransportClosure):
    """Lun et al. (1984) kinetic theory (paper §2.1, Table 1)."""

    name: ClassVar[str] = "lun"

    def functions(self, nu, e, nu_max, g0):
        """f1 … f7 (Table 1) as sympy expressions in ν, given g0(ν)."""
        return lun_functions(nu, e, nu_max, g0)

    def transport(self, f, T, e):
        """Transport functions p, μ, ζ, κ, Γ (paper §2.1) from f1 … f7 (sympy)."""
        sqT = sp.sqrt(T)
        return {
            "p": f["f1"] * T,
            "mu": f["f2"] * sqT,
            "zeta": f["f3"] * sqT,
            "kappa": f["f4"] * sqT,
            "Gamma": (1 - e**2) * f["f5"] * T * sqT,
        }
