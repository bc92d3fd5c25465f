"""Radial distribution functions g0(ν) at contact.

A radial distribution function is a small frozen class that returns a sympy expression in
ν and the maximum packing ``nu_max``; everything numeric (values, derivatives) is
derived from that one expression. Register a new one with :func:`register_radial`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from .._codegen import lazy_module
from .registry import Registry

if TYPE_CHECKING:  # the annotations name sympy's classes; at run time sympy stays lazy
    import sympy as sp
else:
    sp = lazy_module("sympy")  # imported on first use (cached generated code needs none)

__all__ = [
    "RADIALS",
    "CarnahanStarling",
    "LunSavage",
    "MaAhmadi",
    "RadialDistribution",
    "register_radial",
]


@dataclass(frozen=True)
class RadialDistribution:
    """Base class: ``expr(nu, nu_max)`` gives g0 as a sympy expression."""

    name: ClassVar[str] = "base"

    def expr(self, nu: sp.Expr, nu_max: sp.Expr) -> sp.Expr:  # pragma: no cover - abstract
        raise NotImplementedError


#: The radial distribution functions, by name (the ``radial`` field of ChuteModel).
RADIALS: Registry[RadialDistribution] = Registry("radial", RadialDistribution)
register_radial = RADIALS.register


@register_radial
@dataclass(frozen=True)
class LunSavage(RadialDistribution):
    """Lun & Savage (1986): g0(ν) = (1 − ν/ν_m)^(−2.5 ν_m) (paper §2.1)."""

    name: ClassVar[str] = "lun_savage"

    def expr(self, nu, nu_max):
        return (1 - nu / nu_max) ** (-sp.Rational(5, 2) * nu_max)


@register_radial
@dataclass(frozen=True)
class CarnahanStarling(RadialDistribution):
    """Carnahan–Starling: g0(ν) = (2 − ν) / (2 (1 − ν)³); ``nu_max`` unused.

    Offered as an alternative closure (beyond the paper); it does not diverge at ν_m.
    """

    name: ClassVar[str] = "carnahan_starling"

    def expr(self, nu, nu_max):
        return (2 - nu) / (2 * (1 - nu) ** 3)


@register_radial
@dataclass(frozen=True)
class MaAhmadi(RadialDistribution):
    """Ma & Ahmadi (1986): g0(ν) = (1 + 2.5ν + 4.5904ν² + 4.515439ν³) / (1 − (ν/ν_m)³)^0.67802.

    (Not an MFiX option: the MFiX source checked, CurtinIDS/mfix ``model/rdf_mod.f`` and
    ``check_data/check_solids_continuum.f``, has no ``RDF_TYPE = MA_AHMADI`` and allows only
    Carnahan–Starling for one solids phase.) Ma & Ahmadi fitted it with ν_m = 0.64356; here
    ν_m is the model's ``nu_max``. It diverges at
    ν_m like the paper's Lun–Savage g0 and tends to Carnahan–Starling's 1 + 5ν/2 + … as
    ν → 0.
    """

    name: ClassVar[str] = "ma_ahmadi"

    def expr(self, nu, nu_max):
        num = (
            1
            + sp.Rational(5, 2) * nu
            + sp.Rational(45904, 10000) * nu**2
            + sp.Rational(4515439, 1000000) * nu**3
        )
        return num / (1 - (nu / nu_max) ** 3) ** sp.Rational(67802, 100000)
