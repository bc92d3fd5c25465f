"""A periodic x coordinate that concentrates the grid at a front: the tan map.

The unknowns of a mapped simulation are Fourier coefficients in a computational coordinate s
(uniform grid, period L); the physical position is

    x = g(s) = x0 + (L/π) arctan(β tan(π (s − x0) / L)),        0 < β ≤ 1,

(Boyd, *Chebyshev and Fourier Spectral Methods*, 2nd ed., 2001, §17.6, the periodic "tan"
map), with g(s + L) = g(s) + L, g(x0) = x0, g'(x0) = β and g'(x0 ± L/2) = 1/β: the uniform
s grid has 1/β times the uniform density of points at the front x0 and β times it half a
period away. β = 1 is the identity. x-derivatives follow from the chain rule,
∂_x = a ∂_s and ∂_xx = a² ∂_ss − (g''/g'³) ∂_s with a = 1/g'; an x-average is the s-average
weighted by g'.

Why: a bore like P5's (θ 17°, ν0(0) 0.1, L = 2000) is a front of ≈ 100 particle diameters in
a smooth wave; its state at t = 14616 needs M = 96 uniform modes for the resolution
criterion (tail ≤ 1e-4) and M = 32 with β = 0.25 … 0.35 (docs/dns.md, *A grid that follows
the front*; ``benchmarks/probes/mapped_x.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["TanMap"]


@dataclass(frozen=True)
class TanMap:
    """The periodic tan map x = g(s) of period ``length`` centred at ``centre`` (the front),
    with ``beta`` = g'(centre) ∈ (0, 1] (1: the identity)."""

    centre: float
    beta: float
    length: float

    def __post_init__(self):
        if not (math.isfinite(self.length) and self.length > 0):
            raise ParameterError(f"length = {self.length!r}: the period must be finite and > 0")
        if not (math.isfinite(self.beta) and 0.0 < self.beta <= 1.0):
            raise ParameterError(
                f"beta = {self.beta!r}: the map's g'(x0) must lie in (0, 1] "
                "(1/β times the uniform density of points at the front; 1 is the uniform grid)"
            )
        if not math.isfinite(self.centre):
            raise ParameterError(f"centre = {self.centre!r}: the front's position must be finite")

    def _phase(self, s: np.ndarray) -> np.ndarray:
        """π (s − x0)/L wrapped into [−π/2, π/2)."""
        L = self.length
        w = np.mod(np.asarray(s, dtype=float) - self.centre + 0.5 * L, L) - 0.5 * L
        return math.pi * w / L

    def x(self, s: np.ndarray) -> np.ndarray:
        """Physical position g(s) (in [x0 − L/2, x0 + L/2) for s there; periodic continuation
        g(s + L) = g(s) + L elsewhere)."""
        s = np.asarray(s, dtype=float)
        L = self.length
        p = self._phase(s)
        shift = s - self.centre - p * L / math.pi  # the multiple of L
        return self.centre + shift + (L / math.pi) * np.arctan(self.beta * np.tan(p))

    def s(self, x: np.ndarray) -> np.ndarray:
        """The inverse s = g⁻¹(x) (the same map with 1/β)."""
        x = np.asarray(x, dtype=float)
        L = self.length
        p = self._phase(x)
        shift = x - self.centre - p * L / math.pi
        return self.centre + shift + (L / math.pi) * np.arctan(np.tan(p) / self.beta)

    def dx_ds(self, s: np.ndarray) -> np.ndarray:
        """g'(s) = β / (cos²φ + β² sin²φ), φ = π (s − x0)/L."""
        p = self._phase(s)
        c, sn = np.cos(p), np.sin(p)
        return self.beta / (c * c + self.beta**2 * sn * sn)

    def d2x_ds2(self, s: np.ndarray) -> np.ndarray:
        """g''(s) = β (1 − β²) sin 2φ (π/L) / (cos²φ + β² sin²φ)²."""
        p = self._phase(s)
        c, sn = np.cos(p), np.sin(p)
        den = c * c + self.beta**2 * sn * sn
        return self.beta * (1.0 - self.beta**2) * np.sin(2.0 * p) * (math.pi / self.length) / den**2
