"""The resolution ladder of a steady point (paper §3): Newton at n, then at n + n/2, … until
the scalar results change by less than rtol between two resolutions.
"""

from __future__ import annotations

import math

from ..errors import ResolutionError, ThinLayerError
from .one_grid import solve_state
from .options import Options
from .result import SteadyFlow, spectral_tail
from .state import NewtonState, quantities
from .tangent import _BETA_TANGENTS, newton_tangent

_KEYS = ("u_floor", "T_floor", "h", "nu_mean", "rho_bar", "Q", "y_max")


def _thin_message(theta, nu0, model, h, min_thickness):
    return (
        f"no steady flow at theta = {theta:g} deg, nu0 = {nu0:g}, roughness = "
        f"{model.roughness:g}: the only solution has thickness h = {h:.3g}, below "
        f"{min_thickness:g} particle diameter, which the hydrodynamics cannot describe — the "
        "angle is too small for this roughness (or the floor density too low)"
    )


#: The ladder of :func:`solve_point` with ``noise_exit`` stops at n ≥ this when the change
#: between resolutions has grown twice above rtol on a resolved profile (round-off floor).
_NOISE_N = 216


#: Spectral tail (:func:`~chuteflow.steady.result.spectral_tail`) below which a profile
#: counts as resolved for ``noise_exit``, relative to rtol.
_NOISE_TAIL = 1e-3


def solve_point(
    theta,
    nu0,
    model,
    start: NewtonState | None,
    opts: Options,
    *,
    keep: dict | None = None,
    chord: bool = False,
    inherit: dict | None = None,
    inherit_fine: bool = False,
):
    """solve_steady after validation; ``start`` is a :class:`~chuteflow.steady.state.NewtonState`
    (or None: cold start).

    ``opts`` (:class:`~chuteflow.steady.options.Options`) gives ``nu_top``, the first rung
    ``n``, ``rtol``, ``n_max``, ``min_thickness``, Newton's ``maxiter`` and ``lam_min``, and
    ``noise_exit``.

    Newton's last Jacobian at the finer of the two accepted resolutions also gives the family
    tangent dX/dβ (an extra right-hand side of its LU), which
    :func:`~chuteflow.steady.tangent.steady_tangent` then uses instead of a new factorisation
    when that Jacobian was taken within :data:`~chuteflow.steady.tangent.TANGENT_STEP`
    (relative) of the result. With ``keep`` (a dict), the states at the two accepted resolutions
    are stored there (``"coarse"``, ``"fine"``) with their
    :attr:`~chuteflow.steady.state.NewtonState.tangents` (continuation predictors:
    :mod:`chuteflow.steady.continuation_step`). With ``chord``, Newton reuses an LU for chord
    steps while they contract fast (:attr:`~chuteflow.steady.newton.SteadyNewton.chord`),
    starting from ``inherit`` ({n: a neighbour's
    :attr:`~chuteflow.steady.state.NewtonState.lu`}) at the first rung and, with
    ``inherit_fine``, at the finer ones (otherwise a finer rung factorises, and its dX/dβ is
    exact); the accepted states' ``lu`` are then in ``keep``.

    With ``noise_exit`` the resolution ladder gives up (:class:`ResolutionError`) before
    n_max when the change between resolutions is at the solver's round-off floor, which
    grows with n (:meth:`~chuteflow.steady.newton.SteadyNewton.solve`) so that finer grids
    cannot bring it below rtol: from n ≥ :data:`_NOISE_N` on, when the change exceeds rtol,
    has grown since the previous pair (which exceeded rtol too), and the profile's spectral
    tail is below :data:`_NOISE_TAIL` × rtol (the truncation error is far below the change).
    """
    nu_top, n, rtol, n_max, min_thickness = opts.nu_top, opts.n, opts.rtol, opts.n_max, opts.min_thickness
    maxiter, lam_min, noise_exit = opts.maxiter, opts.lam_min, opts.noise_exit
    st, it, res = solve_state(
        theta,
        nu0,
        model,
        nu_top,
        n,
        guess=start,
        maxiter=maxiter,
        lam_min=lam_min,
        tangents=True,
        chord=chord,
        inherit=inherit.get(n) if inherit else None,
    )
    _, q = quantities(theta, st, model)
    change = prev = math.inf
    while True:
        n2 = n + max(n // 2, 8)
        if n < n_max:  # the last rung is n_max itself (not up to 1.5 n_max)
            n2 = min(n2, n_max)
        # at least one Newton correction on the finer grid, so that the change measures
        # the discretisation even when the interpolated coarse solution already passes tol
        # on the same grid map as n: the change then measures the resolution of one grid
        st2, it2, res2 = solve_state(
            theta,
            nu0,
            model,
            nu_top,
            n2,
            guess=st,
            maxiter=maxiter,
            lam_min=lam_min,
            min_iter=1,
            grid_map=st.grid_map,
            tangents=True,
            chord=chord,
            inherit=inherit.get(n2) if inherit and inherit_fine else None,
        )
        it += it2
        g2, q2 = quantities(theta, st2, model)
        change = max(abs(q2[k] - q[k]) / max(abs(q2[k]), 1e-300) for k in _KEYS)
        if change <= rtol or n2 >= n_max:
            break
        if (
            noise_exit
            and n2 >= _NOISE_N
            and rtol < prev < change
            and spectral_tail(st2.s, st2.u, st2.T) < _NOISE_TAIL * rtol
        ):
            break
        n, st, q, prev = n2, st2, q2, change
    flow = SteadyFlow(
        theta=theta,
        nu0=nu0,
        model=model,
        nu_top=nu_top,
        n=n2,
        y=g2.y,
        log_nu=st2.s,
        u=st2.u,
        T=st2.T,
        residual=float(res2),
        iterations=it,
        convergence=float(change),
        spectral_tail=spectral_tail(st2.s, st2.u, st2.T),
        grid_map=st2.grid_map,
        converged=bool(change <= rtol),
        **q2,
    )
    if change > rtol:
        raise ResolutionError(
            f"steady flow at theta = {theta:g}, nu0 = {nu0:g} did not converge to rtol = "
            f"{rtol:g}: relative change {change:.2e} between n = {n} and n = {n2} "
            f"(n_max = {n_max}{', round-off floor' if n2 < n_max else ''})",
            h=float(q2["h"]),
            flow=flow,
        )
    dX = newton_tangent(st2)
    if dX is not None:
        _BETA_TANGENTS.put(flow, dX)
    if keep is not None:
        keep["coarse"], keep["fine"] = st, st2
    if q2["h"] < min_thickness:
        raise ThinLayerError(_thin_message(theta, nu0, model, q2["h"], min_thickness), flow)
    return flow
