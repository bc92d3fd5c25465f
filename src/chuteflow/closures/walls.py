"""Floor (wall) conditions: Johnson–Jackson momentum and energy balances.

A wall condition supplies the slip-drag coefficient η*(ν, T) and the collisional energy
loss Γ*(ν, T) (paper §2.2, "Boundary conditions", where η* and Γ* are defined) as sympy
expressions; the floor conditions themselves are stated once in :mod:`chuteflow.equations`.
Register a new one with :func:`register_wall`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .._codegen import lazy_module
from .registry import Registry

sp = lazy_module("sympy")  # imported on first use (cached generated code needs none)

__all__ = ["WALLS", "JohnsonJackson", "WallCondition", "register_wall"]


@dataclass(frozen=True)
class WallCondition:
    """Base class: ``terms(f, T, roughness, wall_loss)`` gives η* and Γ* (sympy).

    ``f`` holds the transport closure's f1 … f7 (Table 1) as sympy expressions in ν.
    """

    name: ClassVar[str] = "base"

    def terms(self, f, T, roughness, wall_loss) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError


#: The wall conditions, by name (the ``wall`` field of ChuteModel).
WALLS: Registry[WallCondition] = Registry("wall", WallCondition)
register_wall = WALLS.register


@register_wall
@dataclass(frozen=True)
class JohnsonJackson(WallCondition):
    """Johnson & Jackson (1987) with the collision rate Ω = √(3T) ν g0/ν_m of FP02.

    η* = φ f7 f2 √T,   Γ* = ½ Φ f6 f4 T^{3/2}.
    """

    name: ClassVar[str] = "johnson_jackson"

    def terms(self, f, T, roughness, wall_loss):
        sqT = sp.sqrt(T)
        return {
            "eta_star": roughness * f["f7"] * f["f2"] * sqT,
            "Gamma_star": wall_loss * f["f6"] * f["f4"] * T * sqT / 2,
        }
