"""User-facing steady solver with automatic resolution and a convergence estimate."""
from __future__ import annotations

import math

from ..closures import ChuteModel
from ..errors import ConvergenceError, NoSteadyFlowError
from ..spectral import ChebyshevGrid
from .result import SteadyFlow, derived_quantities, spectral_tail
from .solver import _State, _validate, solve_state

_KEYS = ("u_floor", "T_floor", "h", "nu_mean", "rho_bar", "Q", "y_max")


def _quantities(theta, st: _State, model):
    g = ChebyshevGrid(st.n, 0.0, st.L)
    q = derived_quantities(theta, g, st.s, st.u, st.T, model)
    q.update(u_floor=float(st.u[0]), T_floor=float(st.T[0]), y_max=st.L)
    return g, q


def solve_steady(theta: float, nu0: float, model: ChuteModel | None = None, *,
                 nu_top: float = 1e-9, n: int = 64, rtol: float = 1e-8, n_max: int = 384,
                 guess: SteadyFlow | None = None, min_thickness: float = 1.0) -> SteadyFlow:
    """Steady flow at inclination ``theta`` (degrees) and floor density ``nu0`` (paper §3).

    Parameters
    ----------
    theta : float
        Inclination θ in degrees.
    nu0 : float
        Floor packing fraction ν0(0).
    model : ChuteModel, optional
        Closure parameters; the paper's defaults (φ = 0.05, Φ = 0.39, e_p = 0.7, ν_m = 0.6).
    nu_top : float
        Density ν0(y_max) at the top of the domain (paper: 1e-9).
    n : int
        Starting number of Chebyshev intervals; raised until converged.
    rtol : float
        Target relative change of the scalar results between resolutions n and 3n/2.
    guess : SteadyFlow, optional
        A nearby solution to start Newton from (continuation along a family).
    min_thickness : float
        Flows whose thickness h falls below this (diameters) are rejected as unphysical
        (paper §3.2: decay length below one particle diameter). Set 0 to accept them.

    Raises
    ------
    ParameterError
        An input is outside its range.
    NoSteadyFlowError
        No steady flow exists here: the angle is too small (the layer collapses below one
        diameter) or too large (the decay length diverges).
    ConvergenceError
        The solver failed to converge or to reach ``rtol``.
    """
    model = model or ChuteModel()
    theta, nu0 = _validate(theta, nu0, model, nu_top)
    start = None
    if guess is not None:
        start = _State(guess.n, guess.log_nu, guess.u, guess.T, guess.y_max)
    st, it, res = solve_state(theta, nu0, model, nu_top, n, guess=start)
    _, q = _quantities(theta, st, model)
    change = math.inf
    while True:
        n2 = n + max(n // 2, 8)
        st2, it2, res2 = solve_state(theta, nu0, model, nu_top, n2, guess=st)
        g2, q2 = _quantities(theta, st2, model)
        change = max(abs(q2[k] - q[k]) / max(abs(q2[k]), 1e-300) for k in _KEYS)
        if change <= rtol or n2 >= n_max:
            break
        n, st, q = n2, st2, q2
    if change > rtol:
        raise ConvergenceError(
            f"steady flow at theta = {theta:g}, nu0 = {nu0:g} did not converge to rtol = "
            f"{rtol:g}: relative change {change:.2e} between n = {n} and n = {n2}")
    if q2["h"] < min_thickness:
        raise NoSteadyFlowError(
            f"no physical steady flow at theta = {theta:g} deg, nu0 = {nu0:g}, roughness = "
            f"{model.roughness:g}: thickness h = {q2['h']:.3g} is below {min_thickness:g} "
            "particle diameter — the angle is too small for this roughness (or the floor "
            "density too low)")
    return SteadyFlow(theta=theta, nu0=nu0, model=model, nu_top=nu_top, n=n2, y=g2.y,
                      log_nu=st2.s, u=st2.u, T=st2.T, residual=float(res2), iterations=it + it2,
                      convergence=float(change), spectral_tail=spectral_tail(st2.s, st2.u, st2.T),
                      **q2)


def steady_tangent(flow: SteadyFlow) -> dict:
    """Derivative of a steady flow along its family at fixed θ, with respect to β = ν0(0).

    Differentiating the discrete steady equations R(X; β) = 0 gives J dX/dβ = −∂R/∂β with the
    same exact Jacobian J that Newton used; β enters only through ln ν0(0) = ln β. This is the
    k = 0 null vector ∂X0/∂β of Appendix B. Scalar quantities are differentiated along that
    tangent (central difference on the exact tangent direction, step 1e-6 relative: error
    O(1e-12)).

    Returns
    -------
    dict
        ``log_nu``, ``u``, ``T`` (nodal arrays), ``y_max`` (d/dβ at fixed ξ = y/y_max), and
        d/dβ of ``rho_bar``, ``Q``, ``T_mean``, ``h``, ``nu_mean``, ``u_floor``, ``T_floor``,
        plus ``dQ_drho`` = dQ0/dρ̄0 (label eq:dqdh).
    """
    import numpy as np
    import scipy.linalg as sla
    from .solver import _Newton

    newton = _Newton(flow.n, flow.theta, flow.nu0, flow.model, flow.nu_top)
    st = _State(flow.n, np.asarray(flow.log_nu), np.asarray(flow.u), np.asarray(flow.T),
                flow.y_max)
    _, J = newton.evaluate(st)
    dR = np.zeros(J.shape[0])
    dR[0] = -1.0 / flow.nu0
    dX = -sla.solve(J, dR)
    m = flow.n + 1
    out = {"log_nu": dX[:m], "u": dX[m:2 * m], "T": dX[2 * m:3 * m], "y_max": dX[-1]}
    X = st.pack()
    eps = 1e-6 * flow.nu0
    qp = _quantities(flow.theta, _State.unpack(flow.n, X + eps * dX), flow.model)[1]
    qm = _quantities(flow.theta, _State.unpack(flow.n, X - eps * dX), flow.model)[1]
    for k in ("rho_bar", "Q", "T_mean", "h", "nu_mean", "u_floor", "T_floor"):
        out["d" + k] = (qp[k] - qm[k]) / (2 * eps)
    out["dQ_drho"] = out["dQ"] / out["drho_bar"]
    return out
