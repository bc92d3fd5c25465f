"""The steady grid (paper §3): Chebyshev nodes of ξ = y/y_max ∈ [0, 1], clustered at the
edge of the dense layer by the sinh map shared with the stability grid
(:func:`chuteflow.spectral.layer_edge_map`).
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING

import numpy as np

from ..spectral import ChebyshevGrid, coefficients, layer_edge_map
from .result import fine_sampling, steady_grid

if TYPE_CHECKING:
    from .state import NewtonState


@functools.lru_cache(maxsize=8)
def reference_grid(n: int, grid_map: tuple[float, float] | None = None) -> ChebyshevGrid:
    """The steady grid on ξ = y/y_max ∈ [0, 1] (:func:`~chuteflow.steady.result.steady_grid`
    with y_max = 1); cached, its arrays are shared. The map differs from flow to flow, so
    only the last few are kept (a Newton solve asks for its grid at every iteration; 64
    grids with their D and D2 held 42 MiB after one row of a 60 × 60 diagram, 8 hold
    ~5 MiB and miss 4 % more often)."""
    return steady_grid(n, 1.0, grid_map)


def layer_grid_map(st: NewtonState, theta_deg: float) -> tuple[float, float] | None:
    """The sinh map (ξ_c, ξ_w) that clusters nodes at the edge of the layer of ``st``.

    Above the dense layer the density falls with the scale height T0/cos θ of an
    isothermal atmosphere (y-momentum balance p' = −ν cos θ with p ≈ νT): at the edge of a
    dense band under a cold top (the upper existence boundary, T0 ~ 0.1 there) ln ν0 bends
    from the band's profile to that slope within a few scale heights, which a plain Chebyshev
    grid on [0, y_max] resolves only with n ≈ 500 (its nodes crowd the floor and the top
    instead). The map of :class:`~chuteflow.spectral.MappedChebyshevGrid` centred at the
    thickness h (ν0 at 1 % of its maximum, to the spacing of 8n + 1 samples equidistant in
    the grid's variable x) with width ε = :data:`~chuteflow.spectral.LAYER_MAP_WIDTH` T0(h)/cos θ
    (:func:`~chuteflow.spectral.layer_edge_map`, the map of the stability grid too) puts a
    fixed number of nodes across that bend; the converged flow does not depend on it (the
    ladder of :func:`~chuteflow.steady.ladder.solve_point` checks the resolution).

    Returns None (plain grid) where the profile has no edge (a state far from converged) or
    by the fallback rule of :func:`~chuteflow.spectral.layer_edge_map` (the width exceeds
    half the domain, or is not a positive number).
    """
    try:
        ref = st.ref
        # sampled at 8n + 1 points equidistant in the grid's own variable x (the series'
        # variable: one matrix product, :func:`~chuteflow.steady.result.fine_sampling`)
        xf, V = fine_sampling(st.n)
        s = V @ coefficients(st.s)
        k = int(np.argmax(s))
        below = np.nonzero(s[k:] <= s[k] + math.log(0.01))[0]
        if not len(below):
            return None
        xc = float(ref.from_computational(xf[k + below[0]]))
        T_h = float(ref.interpolate(st.T, np.array([xc]))[0])
        # the shared map in units of y (centre xc y_max); the steady grid keeps it as the
        # fractions (ξ_c, ξ_w) of y_max, with ξ_c as sampled
        edge_map = layer_edge_map(xc * st.L, T_h, theta_deg, st.L)
        if edge_map is None:
            return None
        xw = edge_map[1] / st.L
    except (ValueError, ArithmeticError, IndexError):
        return None
    return (xc, xw)
