"""User-facing steady solver with automatic resolution and a convergence estimate."""

from __future__ import annotations

import math
import weakref

import numpy as np

from ..closures import ChuteModel
from ..continuation import StepRules, Trial, continue_to
from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from .existence import steady_existence
from .result import SteadyFlow, cached_per_flow, derived_quantities, spectral_tail, steady_grid
from .solver import NewtonState, SteadyNewton, solve_state, validate_point

_KEYS = ("u_floor", "T_floor", "h", "nu_mean", "rho_bar", "Q", "y_max")


def state_of(flow: SteadyFlow) -> NewtonState:
    """The Newton unknowns of a converged flow (on its own grid)."""
    return NewtonState(
        flow.n, np.asarray(flow.log_nu), np.asarray(flow.u), np.asarray(flow.T), flow.y_max, flow.grid_map
    )


def _quantities(theta, st: NewtonState, model):
    g = steady_grid(st.n, st.L, st.grid_map)
    q = derived_quantities(theta, g, st.s, st.u, st.T, model)
    q.update(u_floor=float(st.u[0]), T_floor=float(st.T[0]), y_max=st.L)
    return g, q


def solve_steady(
    theta: float,
    nu0: float,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    n: int = 64,
    rtol: float = 1e-8,
    n_max: int = 384,
    guess: SteadyFlow | None = None,
    min_thickness: float = 1.0,
    continuation: bool = True,
    strict: bool = True,
) -> SteadyFlow:
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
        If the cold start and the shooting start both fail, follow the branch in θ from an
        anchor angle (see Notes). False: fail after the shooting start.
    strict : bool
        True (default): raise :class:`ConvergenceError` where no road reaches ``rtol``.
        False: where Newton converged at every resolution but the change between the last
        two stayed above ``rtol`` (at ``n_max``, or at Newton's round-off floor, e.g.
        nearly packed bands near the upper existence boundary), return the flow with the
        smallest such change instead, flagged: ``converged`` False and ``convergence`` the
        estimate (the guide's rule: a result that misses the precision comes with its
        estimate). Where no road gives a flow at all, the error is raised either way.

    Notes
    -----
    Without ``guess`` Newton starts from an isothermal estimate of the layer. Where that
    fails (e.g. the non-monotonic layers over a hot dilute cushion at large θ), a shooting
    scan in u0(0) (:func:`~chuteflow.steady.existence.steady_existence`) decides whether a
    flow exists — :class:`NoSteadyFlowError` then carries its verdict — and gives Newton a
    starting profile. Only if Newton fails from that profile too is the branch followed by
    continuation in θ at fixed ν0(0) from an angle where the cold start works; where that
    branch ends before θ, the flow the scan found is not resolved (:class:`ConvergenceError`,
    with the scan's estimate), which is not a verdict of no flow.

    Raises
    ------
    ParameterError
        An input is outside its range.
    NoSteadyFlowError
        No steady flow exists here: the angle is too small (the layer collapses below one
        diameter) or too large (the decay length diverges).
    ConvergenceError
        The solver failed to converge or (with ``strict``) to reach ``rtol``.
    """
    model = model or ChuteModel()
    theta, nu0 = validate_point(theta, nu0, model, nu_top)
    unresolved: list[SteadyFlow] = []  # flows of the roads that missed rtol (strict=False)

    def keep(exc: Exception) -> None:
        f = getattr(exc, "flow", None)
        if isinstance(exc, ResolutionError) and f is not None and f.h >= min_thickness:
            unresolved.append(f)

    def fail(exc: Exception) -> SteadyFlow:
        # every road failed: the flagged flow with the smallest change, or the error
        if not unresolved:
            raise exc
        best = min(unresolved, key=lambda f: f.convergence)
        if strict and getattr(exc, "flow", None) is best:
            raise exc  # its own message says it
        if strict:
            raise ConvergenceError(
                f"{exc}; closest: a flow (h = {best.h:.6g}) whose quantities change by "
                f"{best.convergence:.1e} between the last two resolutions (n = {best.n}), "
                "which strict=False returns flagged"
            ) from exc
        return best

    if guess is not None:
        start = state_of(guess)
        try:
            return solve_point(theta, nu0, model, nu_top, n, rtol, n_max, start, min_thickness)
        except ResolutionError as exc:
            keep(exc)
            return fail(exc)
    try:
        return solve_point(theta, nu0, model, nu_top, n, rtol, n_max, None, min_thickness)
    except ThinLayerError:
        raise
    except (NoSteadyFlowError, ConvergenceError) as exc:
        keep(exc)
        first = exc
    # --- existence by shooting (existence.py): a definitive verdict, or a Newton start ---
    verdict = steady_existence(theta, nu0, model, nu_top=nu_top, min_thickness=min_thickness)
    if not verdict.exists:
        raise NoSteadyFlowError(verdict.reason)
    # from here on a flow exists: a failure is a ConvergenceError naming the scan's verdict
    tried = (
        f"steady solver did not converge although shooting finds a solution — "
        f"{verdict.reason}; tried Newton from the isothermal cold start ({first})"
    )
    m, first = n, ConvergenceError(tried)
    while verdict.solution is not None and m <= (n_max if verdict.physical else n):
        # sharp dense bands need more nodes than n to be represented: double until it works
        # (a thin layer, rejected anyway, gets one try: it is kept only as ThinLayerError.flow)
        try:
            return solve_point(
                theta, nu0, model, nu_top, m, rtol, n_max, verdict.starting_state(m), min_thickness
            )
        except ThinLayerError:
            raise
        except (NoSteadyFlowError, ConvergenceError) as exc:
            keep(exc)
            first = ConvergenceError(f"{tried} and from the shooting profile at n = {n} … {m} ({exc})")
        m *= 2
    if not verdict.physical:
        raise NoSteadyFlowError(verdict.reason)
    if not continuation:
        return fail(first)
    # --- end of the shooting hook ---
    try:
        flow = _theta_continuation(theta, nu0, model, nu_top, n, rtol, n_max, first)
    except ConvergenceError as exc:
        return fail(exc)
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
            anchor = solve_point(th, nu0, model, nu_top, n, rtol, n_max, None, 0.0)
            break
        except (NoSteadyFlowError, ConvergenceError):
            continue
    if anchor is None:
        raise first_error
    cur, reached = follow_theta(anchor, theta, max_steps=_MAX_STEPS, n=n, rtol=rtol, n_max=n_max)
    if reached:
        return cur
    # the shooting scan found a flow here (solve_steady comes here only then): the branch
    # followed from the anchor is another one, which ends before theta — not a verdict
    raise ConvergenceError(
        f"{first_error}; the branch followed in theta from {anchor.theta:g} deg at the same "
        f"floor density ends near {cur.theta:.4g} deg (there h = {cur.h:.3g}, y_max = "
        f"{cur.y_max:.3g}, peak density {cur.nu_peak:.3g}) without reaching this flow"
    )


def follow_theta(flow: SteadyFlow, theta: float, **kw):
    """Follow the branch of ``flow`` at fixed ν0(0) in θ towards ``theta``; see
    :func:`follow`."""
    return follow(flow, theta=theta, **kw)


def follow(
    flow: SteadyFlow,
    theta: float | None = None,
    nu0: float | None = None,
    *,
    step: float = 0.5,
    min_step: float = 1.0 / 128,
    max_steps: int = 200,
    n: int = 64,
    rtol: float = 1e-8,
    n_max: int = 384,
):
    """Follow the branch of ``flow`` along the straight path to (``theta``, ``nu0``).

    Adaptive natural-parameter continuation (:func:`chuteflow.continuation.continue_to`,
    ``retry="halve"``) in the path parameter s ∈ [0, 1] (``step`` and
    ``min_step`` are in degrees when θ moves, else in units of ν0(0)/10): Euler predictor
    along the exact tangents dX/dθ, dX/dν0(0), Newton corrector (every point converged to
    ``rtol`` between two resolutions, as :func:`solve_steady`), step ×1.5 after a success,
    halved after a failure. Thin layers are kept.

    Returns
    -------
    (SteadyFlow, bool)
        The flow at the end of the path and True, or the last flow on the branch and False
        when the step fell below ``min_step`` (the branch ends there) or after ``max_steps``.
    """
    th0, nu00 = flow.theta, flow.nu0
    th1 = th0 if theta is None else float(theta)
    nu1 = nu00 if nu0 is None else float(nu0)
    # degrees per unit s along θ, else ten times the relative change of ν0(0)
    scale = abs(th1 - th0) if th1 != th0 else abs(nu1 - nu00) * 10.0 / max(nu00, 1e-12)
    if scale == 0:
        return flow, True
    model, nu_top = flow.model, flow.nu_top

    def solve(cur, s):
        th, nu = th0 + s * (th1 - th0), nu00 + s * (nu1 - nu00)
        dxb, dxt = tangent_vectors(cur, theta=True)
        X = state_of(cur).pack()
        pred = NewtonState.unpack(cur.n, X + (th - cur.theta) * dxt + (nu - cur.nu0) * dxb, cur.grid_map)
        if not (
            0.5 * cur.y_max < pred.L < 2 * cur.y_max
            and (pred.T > 0).all()
            and (pred.s < np.log(model.nu_max)).all()
        ):
            pred = NewtonState.unpack(cur.n, X, cur.grid_map)
        try:
            return Trial(
                True,
                solve_point(th, nu, model, nu_top, n, rtol, n_max, pred, 0.0, maxiter=15, lam_min=1.0 / 16),
            )
        except (NoSteadyFlowError, ConvergenceError, ParameterError) as exc:
            return Trial(False, str(exc))

    # steps in degrees (θ moves) or ν0(0)/10 per unit s; a failed step onto the end of the
    # path is retried there with the halved nominal step (clip=False)
    rules = StepRules(
        grow=1.5, shrink=0.5, max_step=2.0, min_step=min_step, max_attempts=max_steps, clip=False, scale=scale
    )
    res = continue_to(solve, flow, 0.0, 1.0, rules, h=step / scale)
    return res.state, res.reached


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
    nu_top,
    n,
    rtol,
    n_max,
    start,
    min_thickness,
    maxiter=60,
    lam_min=1e-6,
    noise_exit=False,
    keep: dict | None = None,
    chord: bool = False,
    inherit: dict | None = None,
    inherit_fine: bool = False,
):
    """solve_steady after validation; ``start`` is a :class:`NewtonState` (or None: cold start).

    Newton's last Jacobian at the finer of the two accepted resolutions also gives the
    family tangent dX/dβ (an extra right-hand side of its LU), which
    :func:`steady_tangent` then uses instead of a new factorisation when that Jacobian was
    taken within :data:`TANGENT_STEP` (relative) of the result. With ``keep`` (a dict),
    the states at the two accepted resolutions are stored there (``"coarse"``, ``"fine"``)
    with their :attr:`~chuteflow.steady.solver.NewtonState.tangents` (continuation
    predictors: :mod:`chuteflow.steady.family`). With ``chord``, Newton reuses an LU for
    chord steps while they contract fast (:attr:`~chuteflow.steady.solver.SteadyNewton.chord`),
    starting from ``inherit`` ({n: a neighbour's :attr:`~chuteflow.steady.solver.NewtonState.lu`})
    at the first rung and, with ``inherit_fine``, at the finer ones (otherwise a finer rung
    factorises, and its dX/dβ is exact); the accepted states' ``lu`` are then in ``keep``.

    With ``noise_exit`` the resolution ladder gives up (:class:`ResolutionError`) before
    n_max when the change between resolutions is at the solver's round-off floor, which
    grows with n (:meth:`~chuteflow.steady.solver.SteadyNewton.solve`) so that finer grids
    cannot bring it below rtol: from n ≥ :data:`_NOISE_N` on, when the change exceeds rtol,
    has grown since the previous pair (which exceeded rtol too), and the profile's spectral
    tail is below :data:`_NOISE_TAIL` × rtol (the truncation error is far below the change).
    """
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
    _, q = _quantities(theta, st, model)
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
        g2, q2 = _quantities(theta, st2, model)
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


#: Largest relative Newton step after the Jacobian whose LU gave a flow's dX/dβ for
#: :func:`steady_tangent` to use it (otherwise it factorises the Jacobian at the flow).
#: The tangent's error is of the order of that step (measured: tests/steady/test_solver.py).
TANGENT_STEP = 1e-10


class _PerObject:
    """Values by object identity while the object lives (a weak reference: never keeps it
    alive). Unlike a ``WeakKeyDictionary``, flows equal in value do not share an entry, so
    one flow dying does not take the entry of another equal one."""

    def __init__(self):
        self._items: dict[int, tuple] = {}

    def put(self, obj, value) -> None:
        key = id(obj)

        def drop(_ref, key=key, items=self._items):
            items.pop(key, None)

        self._items[key] = (weakref.ref(obj, drop), value)

    def get(self, obj):
        """The value stored for ``obj``, or None."""
        item = self._items.get(id(obj))
        return None if item is None or item[0]() is not obj else item[1]

    def take(self, obj):
        """The value stored for ``obj``, removed; None if there is none."""
        value = self.get(obj)
        if value is not None:
            self._items.pop(id(obj), None)
        return value


#: dX/dβ from Newton's last LU (solve_point), by flow object, while the flow lives.
_BETA_TANGENTS = _PerObject()


def newton_tangent(st: NewtonState) -> np.ndarray | None:
    """dX/dβ of a converged state from Newton's last LU (:attr:`NewtonState.tangents`) if
    that Jacobian was taken within :data:`TANGENT_STEP` of the state (accurate to about that
    step, as an output); None otherwise (factorise at the state instead)."""
    if st.tangents is not None and st.tangents[1] <= TANGENT_STEP:
        return st.tangents[0]
    return None


class ResolutionError(ConvergenceError):
    """Newton converged at every resolution up to ``n_max``, but the scalars still changed
    by more than ``rtol`` between the last two; ``.h`` is the thickness at the finest and
    ``.flow`` the flow there (``converged`` False, ``convergence`` the last change)."""

    def __init__(self, message, h=float("nan"), flow: SteadyFlow | None = None):
        super().__init__(message)
        self.h = h
        self.flow = flow


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
    O(1e-12)). The result is cached per flow while the flow lives; its arrays are
    read-only.

    Returns
    -------
    dict
        ``log_nu``, ``u``, ``T`` (nodal arrays), ``y_max`` (d/dβ at fixed ξ = y/y_max), and
        d/dβ of ``rho_bar``, ``Q``, ``T_mean``, ``h``, ``nu_mean``, ``u_floor``, ``T_floor``,
        plus ``dQ_drho`` = dQ0/dρ̄0 (eq. (B 6)).
    """
    return dict(_cached_tangent(flow))


@cached_per_flow
def _cached_tangent(flow: SteadyFlow) -> dict:
    """The tangent of one flow, computed once while the flow lives: several sweep metrics of
    the same point (``kinematic``, the 1D criterion, the long-wave theory) need it. Its
    arrays are made read-only so that no caller can alter the cached copy.

    Newton's dX/dβ is kept by flow object (:data:`_BETA_TANGENTS`), not by value as the
    cache is: two flows equal in value (a marked point on the grid, solved from the same
    cold start by two tasks in the threads of one Dask worker) each find their own, so the
    tangent does not depend on which of them dies or asks first (with one entry for both,
    the second factorised instead, and its dQ0/dρ̄0 differed by ~TANGENT_STEP: 2e-10 in
    tests/sweep/test_dask.py, in one run of three)."""
    dX = _BETA_TANGENTS.take(flow)
    out = tangent_from(flow, dX if dX is not None else tangent_vectors(flow, theta=False)[0])
    for v in out.values():
        if isinstance(v, np.ndarray):
            v.flags.writeable = False
    return out


def tangent_from(flow: SteadyFlow, dX: np.ndarray) -> dict:
    """steady_tangent's dict from the packed tangent dX/dβ."""
    st = state_of(flow)
    m = flow.n + 1
    out = {"log_nu": dX[:m], "u": dX[m : 2 * m], "T": dX[2 * m : 3 * m], "y_max": dX[-1]}
    X = st.pack()
    eps = 1e-6 * flow.nu0
    qp = _quantities(flow.theta, NewtonState.unpack(flow.n, X + eps * dX, flow.grid_map), flow.model)[1]
    qm = _quantities(flow.theta, NewtonState.unpack(flow.n, X - eps * dX, flow.grid_map), flow.model)[1]
    for k in ("rho_bar", "Q", "T_mean", "h", "nu_mean", "u_floor", "T_floor"):
        out["d" + k] = (qp[k] - qm[k]) / (2 * eps)
    out["dQ_drho"] = out["dQ"] / out["drho_bar"]
    return out


def tangent_vectors(flow: SteadyFlow, theta: bool = True):
    """Packed dX/dβ (β = ν0(0)) and, if ``theta``, dX/dθ (per degree), from one LU of the
    exact Jacobian. θ enters the residual only through sin θ and cos θ, linearly, so a
    central difference of R in θ (step 1e-3°) is exact up to round-off (~1e-12)."""
    st = state_of(flow)
    return state_tangent_vectors(flow.theta, flow.nu0, flow.model, flow.nu_top, st, theta=theta)


def state_tangent_vectors(theta_deg, nu0, model, nu_top, st: NewtonState, theta: bool = True):
    """:func:`tangent_vectors` at a solution given as a :class:`NewtonState` (any n)."""
    newton = SteadyNewton(st.n, theta_deg, nu0, model, nu_top, grid_map=st.grid_map)
    rhs = np.zeros((st.pack().size, 2 if theta else 1))
    rhs[0, 0] = -1.0 / nu0
    if theta:
        eps = 1e-3
        Rp = SteadyNewton(st.n, theta_deg + eps, nu0, model, nu_top, grid_map=st.grid_map).evaluate(
            st, jac=False
        )[0]
        Rm = SteadyNewton(st.n, theta_deg - eps, nu0, model, nu_top, grid_map=st.grid_map).evaluate(
            st, jac=False
        )[0]
        rhs[:, 1] = (Rp - Rm) / (2 * eps)
    # Newton's own solve: the exact Jacobian at st, with u0' eliminated where the equations
    # allow (SteadyNewton.step: a third of the dense LU's work)
    sol = -newton.step(st, rhs)
    return sol[:, 0], (sol[:, 1] if theta else None)
