"""Constitutive relations of Lun et al. (1984): paper §2.1, Table 1.

Dimensionless (σ, ρ_p σ³, √(σ/g)) transport functions of packing fraction ν and
granular temperature T:

    p = f1 T,   μ = f2 √T,   ζ = f3 √T,   κ = f4 √T,   Γ = (1 − e_p²) f5 T^{3/2},
    κ_h = fh T^{3/2}  (heat flux q = −κ∇T − κ_h∇ν),
    Γ_U  (energy sink Γ + Γ_U ∇·u; zero for Lun et al.'s closures here).

``lun`` is the paper's closure: the heat-flux term κ_h ∇ν is dropped (κ_h = 0; the paper's
footnote to eq. 2.7). ``lun_full`` keeps it; ``lun_mfix`` is MFiX's ``KT_TYPE = LUN_1984``
(its viscosity carries the factor (2 + α)/3). Garzó & Dufty (1999) is in
:mod:`chuteflow.closures.garzo_dufty`. A transport closure is a small frozen class that
states f1 … f7 (and optionally fh) and the transport functions in sympy, given g0(ν) from
the radial distribution function; register a new one with :func:`register_transport`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .._codegen import lazy_module
from .registry import Registry

__all__ = [
    "TRANSPORTS",
    "LunClosure",
    "LunFullClosure",
    "MfixLunClosure",
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
    Γ and, optionally, κ_h (``"kappa_h"``, the coefficient of ∇ν in the heat flux; zero if
    absent) and Γ_U (``"Gamma_U"``, the coefficient of ∇·u in the energy sink Γ + Γ_U ∇·u;
    zero if absent) from them, all as sympy expressions.
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


@register_transport
@dataclass(frozen=True)
class LunFullClosure(LunClosure):
    """Lun et al. (1984) with their density-gradient heat flux q = −κ∇T − κ_h∇ν (the paper's
    footnote to eq. 2.7, which drops κ_h as Forterre & Pouliquen 2002 do).

    f1 … f7 are Table 1's; κ_h = fh T^{3/2} with (η = (1 + e_p)/2)

        fh = 25√π / (16 (41 − 33η)) (1 + 12/5 η ν g0) · 12/5 (η − 1)(2η − 1) · (ν² g0)'/(ν g0),

    proportional to 1 − e_p as the footnote says, and negative for 1/2 < η < 1 (heat flows
    up the density gradient). Source: Lun et al. (1984)'s coefficient as two codes transcribe
    it, in the same sign convention (q = −κ∇T − κ_h∇ν): MFiX's ``GT_PDE_LUN``
    (CurtinIDS/mfix ``model/calc_mu_s.f``, ``Kphi_s``, written out there and commented out:
    MFiX runs with 0) and sedFoam's ``LunConductivityAlpha.C``
    (SedFoam/sedfoam ``solver/kineticTheoryModels/conductivityModelAlpha/Lun``), which agree
    with each other algebraically. The text of Lun et al. (1984) was not at hand. An earlier
    transcription here had 12/5 η(1 − η)(2η − 1): the opposite sign and a factor η.
    """

    name: ClassVar[str] = "lun_full"

    def functions(self, nu, e, nu_max, g0):
        """f1 … f7 (Table 1) and fh as sympy expressions in ν, given g0(ν)."""
        f = lun_functions(nu, e, nu_max, g0)
        eta = (1 + e) / 2
        sqpi = sp.sqrt(sp.pi)
        f["fh"] = (
            25
            * sqpi
            / (16 * (41 - 33 * eta))
            * (1 + sp.Rational(12, 5) * eta * nu * g0)
            * sp.Rational(12, 5)
            * (eta - 1)
            * (2 * eta - 1)
            * sp.diff(nu**2 * g0, nu)
            / (nu * g0)
        )
        return f

    def transport(self, f, T, e):
        """p, μ, ζ, κ, Γ of :class:`LunClosure` and κ_h = fh T^{3/2}."""
        out = super().transport(f, T, e)
        out["kappa_h"] = f["fh"] * T * sp.sqrt(T)
        return out


@register_transport
@dataclass(frozen=True)
class MfixLunClosure(LunClosure):
    """MFiX's ``KT_TYPE = LUN_1984`` (MFiX theory guide, Lun et al. 1984): Table 1's closures
    with the shear viscosity multiplied by (2 + α)/3, α = ``alpha`` (MFiX's ``ALPHA``,
    1.6, the value MFiX uses; α = 1 gives the paper's f2). Every other function
    (p, ζ, κ, Γ; no κ_h) is the paper's. The floor conditions see the same f2 through η*.
    Checked against MFiX's ``GT_PDE_LUN`` (CurtinIDS/mfix ``model/calc_mu_s.f``): the
    factor multiplies the whole shear viscosity, kinetic and collisional, ``Kphi_s = 0``;
    ``ALPHA = 1.6d0`` is a Fortran PARAMETER in ``model/constant_mod.f`` there (changed by
    editing the source, not an input keyword) — tests/closures/test_garzo_dufty_mfix.py.

    Parameters
    ----------
    alpha : float
        MFiX's ``ALPHA`` in the viscosity factor (2 + α)/3, in [0, 10].
    """

    name: ClassVar[str] = "lun_mfix"
    alpha: float = 1.6

    def __post_init__(self):
        from ..errors import ParameterError

        a = self.alpha
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not (0.0 <= float(a) <= 10.0):
            raise ParameterError(
                f"transport lun_mfix: alpha = {a!r} is outside the allowed range [0, 10]: "
                "MFiX's ALPHA of the viscosity factor (2 + α)/3 (its default 1.6; 1 is the paper's)"
            )
        object.__setattr__(self, "alpha", float(a))

    def functions(self, nu, e, nu_max, g0):
        """Table 1's f1 … f7 with f2 (and f7 ∝ 1/f2) for MFiX's viscosity (2 + α)/3 f2."""
        f = lun_functions(nu, e, nu_max, g0)
        factor = (2 + sp.nsimplify(self.alpha)) / 3
        f["f2"] = factor * f["f2"]
        f["f7"] = f["f7"] / factor
        return f
