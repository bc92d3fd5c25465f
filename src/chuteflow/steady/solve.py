"""User-facing steady solver (paper §3): the roads tried in turn (cold start, shooting,
θ-continuation), each with the resolution ladder and its convergence estimate.
"""

from __future__ import annotations

import dataclasses

from ..closures import ChuteModel
from ..errors import ConvergenceError, NoSteadyFlowError, ResolutionError, ThinLayerError
from .follow import follow_theta
from .inputs import validate_point
from .ladder import _thin_message, solve_point
from .options import Options
from .result import SteadyFlow
from .shooting import steady_existence
from .state import state_of


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
    strict: bool = False,
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
        False (default, the package's convention, :mod:`chuteflow.results`): where Newton
        converged at every resolution but the change between the last
        two stayed above ``rtol`` (at ``n_max``, or at Newton's round-off floor, e.g.
        nearly packed bands near the upper existence boundary), return the flow with the
        smallest such change instead, flagged: ``converged`` False and ``convergence`` the
        estimate (the guide's rule: a result that misses the precision comes with its
        estimate). True: raise :class:`ConvergenceError` where no road reaches ``rtol``.
        Where no road gives a flow at all, the error is raised either way.

    Notes
    -----
    Without ``guess`` Newton starts from an isothermal estimate of the layer. Where that
    fails (e.g. the non-monotonic layers over a hot dilute cushion at large θ), a shooting
    scan in u0(0) (:func:`~chuteflow.steady.shooting.steady_existence`) decides whether a
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
    opts = Options(
        nu_top=nu_top, n=n, rtol=rtol, n_max=n_max, min_thickness=min_thickness, noise_exit=False
    ).isolated()
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
            return solve_point(theta, nu0, model, start, opts)
        except ResolutionError as exc:
            keep(exc)
            return fail(exc)
    try:
        return solve_point(theta, nu0, model, None, opts)
    except ThinLayerError:
        raise
    except (NoSteadyFlowError, ConvergenceError) as exc:
        keep(exc)
        first = exc
    # --- existence by shooting (shooting/verdict.py): a definitive verdict, or a Newton start ---
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
            return solve_point(theta, nu0, model, verdict.starting_state(m), dataclasses.replace(opts, n=m))
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
        flow = _theta_continuation(theta, nu0, model, opts, first)
    except ConvergenceError as exc:
        return fail(exc)
    if flow.h < min_thickness:
        raise ThinLayerError(_thin_message(theta, nu0, model, flow.h, min_thickness), flow)
    return flow


#: Angles tried as starting points of the θ-continuation fallback (cold start reliable).
_ANCHORS = (12.0, 13.0, 15.0, 17.0, 19.0, 21.0)


_MAX_ANCHORS = 3


_MAX_STEPS = 24


def _theta_continuation(theta, nu0, model, opts: Options, first_error):
    """Follow the branch at fixed ν0 from an anchor angle to ``theta``; raises the
    appropriate error if no anchor converges or the branch ends on the way."""
    anchor = None
    for th in sorted(_ANCHORS, key=lambda a: abs(a - theta))[:_MAX_ANCHORS]:
        if abs(th - theta) < 1e-9:
            continue
        try:
            anchor = solve_point(th, nu0, model, None, dataclasses.replace(opts, min_thickness=0.0))
            break
        except (NoSteadyFlowError, ConvergenceError):
            continue
    if anchor is None:
        raise first_error
    cur, reached = follow_theta(
        anchor, theta, max_steps=_MAX_STEPS, n=opts.n, rtol=opts.rtol, n_max=opts.n_max
    )
    if reached:
        return cur
    # the shooting scan found a flow here (solve_steady comes here only then): the branch
    # followed from the anchor is another one, which ends before theta — not a verdict
    raise ConvergenceError(
        f"{first_error}; the branch followed in theta from {anchor.theta:g} deg at the same "
        f"floor density ends near {cur.theta:.4g} deg (there h = {cur.h:.3g}, y_max = "
        f"{cur.y_max:.3g}, peak density {cur.nu_peak:.3g}) without reaching this flow"
    )
