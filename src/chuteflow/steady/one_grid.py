"""A steady solve at one resolution (paper §3): the start (cold, or a given state), its grid
map, Newton, and an error that says why it failed.
"""

from __future__ import annotations

import math
from typing import Any

from .cold_start import _cold_start
from .grid import layer_grid_map
from .newton import SteadyNewton, _diagnose, _NewtonFailure
from .state import resample


def solve_state(
    theta,
    nu0,
    model,
    nu_top,
    n,
    guess=None,
    tol=1e-11,
    maxiter=60,
    lam_min=1e-6,
    min_iter=0,
    grid_map: Any = "auto",
    tangents: bool = False,
    chord: bool = False,
    inherit: Any = None,
):
    """Solve the steady problem; returns (state, iterations, residual). Raises on failure.

    Without ``guess`` the cold start runs Newton on a coarse grid first (n = 32: its iterations
    are a third of the cost) and refines; the result does not depend on it. The grid is
    ``grid_map`` ((ξ_c, ξ_w) or None: plain Chebyshev nodes); by default (``"auto"``) the map of
    :func:`~chuteflow.steady.grid.layer_grid_map` for the starting state (cold start or
    ``guess``). ``tangents`` sets the state's
    :attr:`~chuteflow.steady.state.NewtonState.tangents` (dX/dβ from Newton's last Jacobian).
    ``chord``: Newton reuses its last LU while that contracts fast
    (:attr:`~chuteflow.steady.newton.SteadyNewton.chord`; imports scipy.linalg), from the start
    with ``inherit`` (:attr:`~chuteflow.steady.newton.SteadyNewton.inherit`: a neighbour's LU at
    n) if given.
    """
    it0 = 0
    if guess is None:
        guess, it0 = _cold_start(theta, nu0, model, nu_top, n)
    gm = layer_grid_map(guess, theta) if isinstance(grid_map, str) else grid_map
    guess = resample(guess, n, gm)
    guess.s = guess.s + (math.log(nu0) - guess.s[0])  # exact floor value, same shape
    newton = SteadyNewton(n, theta, nu0, model, nu_top, grid_map=gm)
    newton.tangents = tangents
    newton.chord = chord
    newton.inherit = inherit
    try:
        st, it, res, _ = newton.solve(guess, tol=tol, maxiter=maxiter, lam_min=lam_min, min_iter=min_iter)
    except _NewtonFailure as fail:
        raise _diagnose(theta, nu0, model, fail) from None
    return st, it0 + it, res
