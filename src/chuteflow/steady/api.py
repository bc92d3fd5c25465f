"""User-facing steady solver with automatic resolution and a convergence estimate."""
from __future__ import annotations

import math

import numpy as np

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
                 guess: SteadyFlow | None = None, min_thickness: float = 1.0,
                 continuation: bool = True) -> SteadyFlow:
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
    continuation : bool
        If the cold start fails, follow the branch in θ from an anchor angle (see Notes).
        False: fail at once (faster where no flow exists, but a flow the cold start
        cannot find is then reported as missing).

    Notes
    -----
    Without ``guess`` Newton starts from an isothermal estimate of the layer. Where that
    fails (e.g. the non-monotonic layers over a hot dilute cushion at large θ), the branch
    is followed instead by continuation in θ at fixed ν0(0) from an angle where the cold
    start works (15°, 13° or 12°), with adaptive steps; :class:`NoSteadyFlowError` then
    means that this branch ends before ``theta``.

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
    if guess is not None:
        start = _State(guess.n, np.asarray(guess.log_nu), np.asarray(guess.u),
                       np.asarray(guess.T), guess.y_max)
        return _solve(theta, nu0, model, nu_top, n, rtol, n_max, start, min_thickness)
    try:
        return _solve(theta, nu0, model, nu_top, n, rtol, n_max, None, min_thickness)
    except ThinLayerError:
        raise
    except (NoSteadyFlowError, ConvergenceError) as exc:
        if not continuation:
            raise
        first = exc
    flow = _theta_continuation(theta, nu0, model, nu_top, n, rtol, n_max, first)
    if flow.h < min_thickness:
        raise ThinLayerError(_thin_message(theta, nu0, model, flow.h, min_thickness), flow)
    return flow


#: Angles tried as starting points of the θ-continuation fallback (cold start reliable).
_ANCHORS = (12.0, 13.0, 15.0, 17.0, 19.0, 21.0)
_MAX_ANCHORS = 3
_MAX_STEPS = 24


def _theta_continuation(theta, nu0, model, nu_top, n, rtol, n_max, first_error):
    """Follow the branch at fixed ν0 from an anchor angle to ``theta``; raises the
    appropriate error if no anchor converges or the branch ends on the way."""
    anchor = None
    for th in sorted(_ANCHORS, key=lambda a: abs(a - theta))[:_MAX_ANCHORS]:
        if abs(th - theta) < 1e-9:
            continue
        try:
            anchor = _solve(th, nu0, model, nu_top, n, rtol, n_max, None, 0.0)
            break
        except (NoSteadyFlowError, ConvergenceError):
            continue
    if anchor is None:
        raise first_error
    cur, step, steps = anchor, 0.5, 0
    direction = 1.0 if theta > anchor.theta else -1.0
    while steps < _MAX_STEPS:
        steps += 1
        nxt = cur.theta + direction * min(step, abs(theta - cur.theta))
        dxb, dxt = _tangent_vectors(cur, theta=True)
        X = _State(cur.n, np.asarray(cur.log_nu), np.asarray(cur.u), np.asarray(cur.T),
                   cur.y_max).pack()
        pred = _State.unpack(cur.n, X + (nxt - cur.theta) * dxt)
        if not (0.5 * cur.y_max < pred.L < 2 * cur.y_max and (pred.T > 0).all()):
            pred = _State.unpack(cur.n, X)
        try:
            cur = _solve(nxt, nu0, model, nu_top, n, rtol, n_max, pred, 0.0,
                         maxiter=15, lam_min=1.0 / 16)
            if abs(cur.theta - theta) < 1e-12:
                return cur
            step = min(2.0, step * 1.5)
        except (NoSteadyFlowError, ConvergenceError):
            step *= 0.5
            if step < 1.0 / 128:
                break
    too = "large" if direction > 0 else "small"
    raise NoSteadyFlowError(
        f"no steady flow found at theta = {theta:g} deg, nu0 = {nu0:g}, roughness = "
        f"{model.roughness:g}, wall_loss = {model.wall_loss:g}: the cold start failed and "
        f"the branch followed in theta from {anchor.theta:g} deg ends near "
        f"{cur.theta:.4g} deg (there h = {cur.h:.3g}, y_max = {cur.y_max:.3g}, peak "
        f"density {cur.nu_peak:.3g}) — the angle is too {too} for this floor density")


def _thin_message(theta, nu0, model, h, min_thickness):
    return (f"no physical steady flow at theta = {theta:g} deg, nu0 = {nu0:g}, roughness = "
            f"{model.roughness:g}: thickness h = {h:.3g} is below {min_thickness:g} "
            "particle diameter — the angle is too small for this roughness (or the floor "
            "density too low)")


def _solve(theta, nu0, model, nu_top, n, rtol, n_max, start, min_thickness, maxiter=60,
           lam_min=1e-6):
    """solve_steady after validation; ``start`` is a :class:`_State` (or None: cold start)."""
    st, it, res = solve_state(theta, nu0, model, nu_top, n, guess=start, maxiter=maxiter,
                              lam_min=lam_min)
    _, q = _quantities(theta, st, model)
    change = math.inf
    while True:
        n2 = n + max(n // 2, 8)
        # at least one Newton correction on the finer grid, so that the change measures
        # the discretisation even when the interpolated coarse solution already passes tol
        st2, it2, res2 = solve_state(theta, nu0, model, nu_top, n2, guess=st, maxiter=maxiter,
                                     lam_min=lam_min, min_iter=1)
        it += it2
        g2, q2 = _quantities(theta, st2, model)
        change = max(abs(q2[k] - q[k]) / max(abs(q2[k]), 1e-300) for k in _KEYS)
        if change <= rtol or n2 >= n_max:
            break
        n, st, q = n2, st2, q2
    if change > rtol:
        raise ConvergenceError(
            f"steady flow at theta = {theta:g}, nu0 = {nu0:g} did not converge to rtol = "
            f"{rtol:g}: relative change {change:.2e} between n = {n} and n = {n2} "
            f"(n_max = {n_max})")
    flow = SteadyFlow(theta=theta, nu0=nu0, model=model, nu_top=nu_top, n=n2, y=g2.y,
                      log_nu=st2.s, u=st2.u, T=st2.T, residual=float(res2), iterations=it,
                      convergence=float(change),
                      spectral_tail=spectral_tail(st2.s, st2.u, st2.T), **q2)
    if q2["h"] < min_thickness:
        raise ThinLayerError(_thin_message(theta, nu0, model, q2["h"], min_thickness), flow)
    return flow


class ThinLayerError(NoSteadyFlowError):
    """A converged solution thinner than ``min_thickness``; ``.flow`` keeps it (e.g. as a
    continuation guess)."""

    def __init__(self, message, flow):
        super().__init__(message)
        self.flow = flow


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
    return _tangent_from(flow, _tangent_vectors(flow, theta=False)[0])


def _tangent_from(flow: SteadyFlow, dX: np.ndarray) -> dict:
    """steady_tangent's dict from the packed tangent dX/dβ."""
    st = _State(flow.n, np.asarray(flow.log_nu), np.asarray(flow.u), np.asarray(flow.T),
                flow.y_max)
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


def _tangent_vectors(flow: SteadyFlow, theta: bool = True):
    """Packed dX/dβ (β = ν0(0)) and, if ``theta``, dX/dθ (per degree), from one LU of the
    exact Jacobian. θ enters the residual only through sin θ and cos θ, linearly, so a
    central difference of R in θ (step 1e-3°) is exact up to round-off (~1e-12)."""
    import scipy.linalg as sla
    from .solver import _Newton

    newton = _Newton(flow.n, flow.theta, flow.nu0, flow.model, flow.nu_top)
    st = _State(flow.n, np.asarray(flow.log_nu), np.asarray(flow.u), np.asarray(flow.T),
                flow.y_max)
    _, J = newton.evaluate(st)
    rhs = np.zeros((J.shape[0], 2 if theta else 1))
    rhs[0, 0] = -1.0 / flow.nu0
    if theta:
        eps = 1e-3
        Rp = _Newton(flow.n, flow.theta + eps, flow.nu0, flow.model, flow.nu_top).evaluate(
            st, jac=False)[0]
        Rm = _Newton(flow.n, flow.theta - eps, flow.nu0, flow.model, flow.nu_top).evaluate(
            st, jac=False)[0]
        rhs[:, 1] = (Rp - Rm) / (2 * eps)
    sol = -sla.lu_solve(sla.lu_factor(J, check_finite=False), rhs, check_finite=False)
    return sol[:, 0], (sol[:, 1] if theta else None)
