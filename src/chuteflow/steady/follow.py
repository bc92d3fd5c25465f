"""Following a branch of steady flows in θ or ν0(0) by natural-parameter continuation
(paper §3.2).
"""

from __future__ import annotations

import numpy as np

from ..continuation import StepRules, Trial, continue_to
from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from .ladder import solve_point
from .options import Options
from .result import SteadyFlow
from .state import NewtonState, state_of
from .tangent import tangent_vectors


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
    ``retry="halve"``) in the path parameter s ∈ [0, 1] (``step`` and ``min_step`` are in
    degrees when θ moves, else in units of ν0(0)/10): Euler predictor along the exact tangents
    dX/dθ, dX/dν0(0), Newton corrector (every point converged to ``rtol`` between two
    resolutions, as :func:`~chuteflow.steady.solve.solve_steady`), step ×1.5 after a success,
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
    # each step's ladder fails fast (a step onto the wrong side of a fold), thin layers kept
    opts = Options(
        nu_top=nu_top,
        n=n,
        rtol=rtol,
        n_max=n_max,
        min_thickness=0.0,
        maxiter=15,
        lam_min=1.0 / 16,
        noise_exit=False,
    )

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
                solve_point(th, nu, model, pred, opts),
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
