"""Floor (wall) conditions: Johnson–Jackson momentum and energy balances.

A wall condition supplies the slip-drag coefficient η*(ν, T) (label etastar) and the
collisional energy loss Γ*(ν, T) (label gammastar) as sympy expressions; the floor
conditions eq:bc1 and eq:bc2 themselves are stated once in :mod:`chuteflow.equations`.
"""
from __future__ import annotations

from dataclasses import dataclass

from .._codegen import lazy_module

sp = lazy_module("sympy")  # imported on first use (cached generated code needs none)


@dataclass(frozen=True)
class JohnsonJackson:
    """Johnson & Jackson (1987) with the collision rate Ω = √(3T) ν g0/ν_m of FP02.

    η* = φ f7 f2 √T  (etastar),   Γ* = ½ Φ f6 f4 T^{3/2}  (gammastar).
    """

    name: str = "johnson_jackson"

    def terms(self, f, T, roughness, wall_loss):
        sqT = sp.sqrt(T)
        return {
            "eta_star": roughness * f["f7"] * f["f2"] * sqT,
            "Gamma_star": wall_loss * f["f6"] * f["f4"] * T * sqT / 2,
        }
