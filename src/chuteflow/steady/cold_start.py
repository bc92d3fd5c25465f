"""The cold start of the steady solver (paper §3): an isothermal estimate of the layer
(closed form in T), polished by Newton on a coarse grid.
"""

from __future__ import annotations

import math

import numpy as np

from ..spectral import ChebyshevGrid
from .newton import SteadyNewton, _diagnose, _NewtonFailure
from .state import NewtonState


def isothermal_guess(theta_deg, nu0, model, nu_top, grid):
    """Cold start: isothermal layer with T fixed by the depth-integrated energy balance.

    With T constant, ν(y) depends on y/T only, every floor term scales as T^{3/2} and every
    bulk integral as T^{5/2}; the energy balance η* u_f² − Γ* = ∫(Γ − μ u'²) dy then fixes T
    in closed form.

    This approximate model (u' = tan θ p/μ, u_f = tan θ p/η*, hydrostatic isothermal ν) is
    only a starting point for Newton, which then solves the equations derived in
    :mod:`chuteflow.equations`; the converged flow does not depend on it.
    """
    th = math.radians(theta_deg)
    s, c = math.sin(th), math.cos(th)
    # ν as a function of ỹ = y c / T on a log-spaced ν grid
    lnnu = np.linspace(math.log(nu0), math.log(nu_top), 400)
    nus = np.exp(lnnu)
    f1p = model.f(nus)["f1"][1]
    ytil = np.concatenate([[0.0], np.cumsum(0.5 * (f1p[1:] + f1p[:-1]) * -np.diff(lnnu))])
    ev = model.evaluate(nus, 1.0)
    tan = s / c
    bulk_integrand = ev["Gamma"][(0, 0)] - tan**2 * ev["p"][(0, 0)] ** 2 / ev["mu"][(0, 0)]
    b = np.trapezoid(bulk_integrand, ytil) / c  # ∫ … dy = (T/c) ∫ … dỹ, per T^{5/2}
    e0 = model.evaluate(nu0, 1.0)
    uf1 = tan * e0["p"][(0, 0)] / e0["eta_star"][(0, 0)]  # u_f per √T
    a = float(e0["eta_star"][(0, 0)] * uf1**2 - e0["Gamma_star"][(0, 0)])
    T = a / b if (a > 0 and b > 0) else 1.0
    L = T * ytil[-1] / c
    y = grid.y * L
    nu = np.exp(np.interp(y * c / T, ytil, lnnu))
    ev = model.evaluate(nu, T)
    uprime = tan * ev["p"][(0, 0)] / ev["mu"][(0, 0)]
    g = ChebyshevGrid(grid.n, 0.0, L)
    u = uf1 * math.sqrt(T) + g.cumulative(uprime)
    return NewtonState(grid.n, np.log(nu), u, np.full_like(nu, T), L)


_COARSE = 32


def _cold_start(theta, nu0, model, nu_top, n, maxiter=30):
    """Isothermal guess polished by Newton (second-order x-momentum form, see
    :meth:`~chuteflow.steady.newton.SteadyNewton.evaluate`) on the coarse grid; (state,
    iterations). If the coarse Newton got close (residual < 1e-3) but not below tolerance, the
    layer may be under-resolved and the n grid is tried too. A cold start that converges needs
    at most ~15 iterations: failing after ``maxiter`` (and backtracking at most 10 halvings)
    keeps the cost of a point without a steady flow bounded."""
    levels = (_COARSE, n) if n > _COARSE else (n,)
    first = None
    for m in levels:
        newton = SteadyNewton(m, theta, nu0, model, nu_top, integrated=False)
        try:
            st, it, _, _ = newton.solve(
                isothermal_guess(theta, nu0, model, nu_top, newton.ref),
                tol=1e-9,
                maxiter=maxiter,
                lam_min=2.0**-10,
            )
            return st, it
        except _NewtonFailure as fail:
            # (without its traceback: kept in this frame, it would be a reference cycle
            # holding the callers' frames, a whole map row's flows, until the cyclic GC)
            first = first or fail.with_traceback(None)
            if not (min(fail.history) < 1e-3):
                break
    raise _diagnose(theta, nu0, model, first)
