"""One point of a family or map (paper §3.2): a solve from a converged neighbour advanced
along its exact tangents (Euler predictor, Newton corrector with chord steps), or a cold
start, with the tangent vectors the next step needs.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..continuation import StepRules, Trial, continue_to
from ..errors import ConvergenceError, NoSteadyFlowError, ResolutionError, ThinLayerError
from ..spectral import coefficients
from .ladder import solve_point
from .options import Options
from .result import SteadyFlow
from .state import NewtonState, resample, state_of
from .tangent import newton_tangent, state_tangent_vectors, tangent_from, tangent_vectors


@dataclass
class _Point:
    """Outcome at one (θ, ν0): a flow (possibly thin) or an error, and the ν0-tangent."""

    status: str
    flow: SteadyFlow | None = None
    error: str = ""
    tangent: dict | None = None
    vectors: tuple | None = None  # packed dX/dν0(0), dX/dθ
    tried: frozenset = frozenset()  # sources tried for this point (see continue_row)

    @property
    def usable(self) -> bool:
        """A converged solution (physical or thin) that can seed a neighbour."""
        return self.flow is not None


_UNREACHED = "unreached"


def _attempt(
    theta,
    nu0,
    model,
    opts: Options,
    start: NewtonState | None,
    n: int,
    cold: bool = False,
    inherit: dict | None = None,
    lu_out: dict | None = None,
) -> _Point:
    """Solve at (θ, ν0) from ``start`` (None: cold start) with the ladder from n. Except
    for a cold start, Newton takes chord steps (:attr:`~chuteflow.steady.newton.SteadyNewton.chord`),
    from the start with ``inherit`` ({n: LU} of a neighbour's solve); ``lu_out`` (a dict)
    receives those of this solve, {n: LU} at its two accepted resolutions, if it gives a flow."""
    ladder = dataclasses.replace(opts.isolated() if cold else opts, n=n)
    kw: dict[str, Any] = (
        {} if cold else {"chord": True, "inherit": inherit, "inherit_fine": not opts.beta_tangents}
    )
    keep: dict = {}
    try:
        flow = solve_point(theta, nu0, model, start, ladder, keep=keep, **kw)
        point = _Point("ok", flow)
    except ThinLayerError as exc:
        point = _Point("thin", exc.flow, str(exc))
    except NoSteadyFlowError as exc:
        return _Point("no_steady_flow", None, str(exc))
    except ResolutionError as exc:
        # a solution found at every resolution: with h ≥ min_thickness, a flow that exists
        # but that n_max does not resolve to rtol
        if exc.h >= opts.min_thickness:
            return _Point(
                "not_converged",
                None,
                f"a steady flow exists here (Newton converges at every resolution, h = {exc.h:.4g}) "
                f"but is not resolved: {exc}",
            )
        return _Point("not_converged", None, str(exc))
    except ConvergenceError as exc:
        return _Point("not_converged", None, str(exc))
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        return _Point("not_converged", None, f"{type(exc).__name__}: {exc}")
    if lu_out is not None:
        lu_out.update({st.n: st.lu for st in keep.values() if st.lu is not None})
    return _newton_vectors(point, keep, opts)


def _newton_vectors(point: _Point, keep: dict, opts: Options) -> _Point:
    """dX/dβ for :attr:`_Point.vectors` from Newton's last LU
    (:func:`~chuteflow.steady.ladder.solve_point` with ``keep``), dX/dθ left for
    :func:`_predict` to add if a step in θ needs it: for a predictor, dX/dβ of the coarser
    accepted resolution; with ``opts.tangent`` (an output), that of the finer one if Newton's
    last step after that LU was small enough (:func:`~chuteflow.steady.ladder.newton_tangent`;
    else :func:`_with_tangent` factorises)."""
    f = point.flow
    coarse, fine = keep.get("coarse"), keep.get("fine")
    if f is None or coarse is None or fine is None:
        return point
    if opts.tangent and point.status == "ok":
        dX = newton_tangent(fine)
        if dX is not None:
            point.vectors = (dX, None)
            point.tangent = tangent_from(f, dX)
    elif coarse.tangents is not None and coarse.n == _start_n(f, opts):
        point.vectors = (coarse.tangents[0], None)
    return point


def _start_n(flow: SteadyFlow, opts: Options) -> int:
    """The coarser of the two resolutions the neighbour was accepted at."""
    return max(opts.n, int(round(flow.n * 2 / 3)))


#: A neighbour's Chebyshev coefficients (of ln ν0, u0, T0, relative to the largest) beyond
#: the resolution a ladder starts at are below this: far below the change rtol = 1e-8 that
#: the ladder then checks between two resolutions.
_RESOLVED = 1e-11


def _resolved_n(flow: SteadyFlow, opts: Options) -> int:
    """Resolution to start a continuation step's ladder at.

    The neighbour's accepted n only grows along a row or a map (each step starts at 2/3 of
    the neighbour's n, and the ladder only goes up), although most flows are resolved by far
    fewer nodes (θ = 16°, ν0(0) = 0.05: n = 96 from a cold start, 216 deep in a map). The
    start is therefore the first resolution n of the ladder n → n + n/2 from ``opts.n`` whose
    Chebyshev coefficients of the neighbour (interpolated to n) are resolved: every
    coefficient of index ≥ 2n/3 below :data:`_RESOLVED` relative to the largest (spectral
    convergence: the truncation error at n is then ≪ rtol). Never above
    :func:`_start_n`."""
    top = _start_n(flow, opts)
    k = 0
    for f in (flow.log_nu, flow.u, flow.T):
        c = np.abs(coefficients(np.asarray(f)))
        big = np.nonzero(c > _RESOLVED * c.max())[0]
        k = max(k, int(big[-1]) + 1 if len(big) else 0)
    n = opts.n
    while n < top and 2 * n < 3 * k:
        n += max(n // 2, 8)
    return min(n, top)


def _predict(point: _Point, theta: float, nu0: float) -> NewtonState:
    """Neighbour advanced along its exact tangents dX/dν0(0), dX/dθ (Euler predictor), on
    the grid the tangents were computed on (:func:`_with_tangent`)."""
    f = point.flow
    assert f is not None, "a predictor needs a converged neighbour"
    st0 = state_of(f)
    if point.vectors is not None:
        st0 = resample(st0, len(point.vectors[0]) // 3 - 1)
    X = st0.pack()
    if point.vectors is not None and point.vectors[1] is None and theta != f.theta:
        # dX/dθ on the vectors' grid, once per point, where a step in θ needs it
        try:
            d_theta = state_tangent_vectors(f.theta, f.nu0, f.model, f.nu_top, st0)[1]
            point.vectors = (point.vectors[0], d_theta)
        except (ValueError, np.linalg.LinAlgError, ArithmeticError):
            point.vectors = None
    if point.vectors is not None:
        Xp = X + (nu0 - f.nu0) * point.vectors[0]
        if theta != f.theta:
            Xp = Xp + (theta - f.theta) * point.vectors[1]
        st = NewtonState.unpack(st0.n, Xp, st0.grid_map)
        # near a fold a full Euler step can overshoot; keep it only where it is sane
        if (
            0.5 * f.y_max < st.L < 2.0 * f.y_max
            and (st.T > 0).all()
            and (st.s < np.log(f.model.nu_max)).all()
        ):
            return st
    return NewtonState.unpack(st0.n, X, st0.grid_map)


def _with_tangent(point: _Point, opts: Options) -> _Point:
    """Tangent vectors of a converged point: for the predictor of its neighbours and, with
    ``opts.tangent``, the derivatives along the family
    (:func:`~chuteflow.steady.tangent.tangent_from`). Those are outputs and use the exact
    Jacobian at the accepted resolution; a predictor needs no such accuracy, so without
    ``opts.tangent`` the vectors come from the coarser of the two resolutions the flow was
    checked at (a third of the cost of the LU factorisation)."""
    if point.flow is not None and point.vectors is None:
        f = point.flow
        try:
            if opts.tangent and point.status == "ok":
                point.vectors = tangent_vectors(f, theta=True)
                point.tangent = tangent_from(f, point.vectors[0])
            else:
                st = state_of(f)
                st = resample(st, _start_n(f, opts))
                point.vectors = state_tangent_vectors(f.theta, f.nu0, f.model, f.nu_top, st)
        except (ValueError, np.linalg.LinAlgError, ArithmeticError):
            point.vectors = None
    return point


#: Key of ``memo`` (:func:`_continue`) for the LUs of the row's last successful solve:
#: (its point, {n: LU}). One slot, so that a row keeps O(1) factorisations alive; a walk
#: along ν0 continues from the point it solved last.
_LU_SLOT = "lu"


def _continue(nb: _Point, theta: float, nu0: float, model, opts: Options, memo: dict | None = None) -> _Point:
    """Solve at (θ, ν0) from the converged neighbour ``nb``; on failure retry through
    2, then 4, … (up to 2**``opts.substeps``) equal steps on the straight path from the
    neighbour (:func:`~chuteflow.continuation.continue_to`, ``retry="subdivide"``).

    ``memo`` (a dict shared by the calls of one row, :func:`~chuteflow.steady.rows.continue_row`) keeps every
    step's outcome by (start point, target, settings): a retry with more substeps repeats
    the whole step and the half steps of the first try exactly, and gets them from there
    (the solver is deterministic, so the outcome is the same, at no cost)."""
    assert nb.flow is not None, "continuation needs a converged neighbour"
    th0, nu00 = nb.flow.theta, nb.flow.nu0
    okey = dataclasses.replace(opts, substeps=0)

    def solve(cur: _Point, s: float) -> Trial:
        if s == 1.0:
            th, nu = theta, nu0
        else:
            th, nu = th0 + (theta - th0) * s, nu00 + (nu0 - nu00) * s
        if memo is None:
            return step(cur, th, nu, s)
        key = (id(cur), th, nu, s == 1.0, okey)
        hit = memo.get(key)
        if hit is None or hit[0] is not cur:
            # the start point is kept with the outcome, so that its id is not reused
            hit = memo[key] = (cur, step(cur, th, nu, s))
        return hit[1]

    def step(cur: _Point, th: float, nu: float, s: float) -> Trial:
        assert cur.flow is not None  # continue_to steps only from accepted (usable) points
        pred = _predict(cur, th, nu)
        n_low, n_old = _resolved_n(cur.flow, opts), _start_n(cur.flow, opts)
        # the LUs of the last solve (memo's one slot), if it was this start point's: Newton's
        # chord steps start with them (a neighbour's Jacobian, at the same n)
        slot = memo.get(_LU_SLOT) if memo is not None else None
        inherit = slot[1] if slot is not None and slot[0] is cur else None
        lus: dict = {}
        q = _attempt(th, nu, model, opts, pred, n_low, inherit=inherit, lu_out=lus)
        if not q.usable and n_low < n_old:
            # failed from the coarser grid (Newton on a layer it does not resolve, or a
            # ladder whose last change is at Newton's round-off floor): the neighbour's own
            # resolution, as before
            q = _attempt(th, nu, model, opts, pred, n_old, inherit=inherit, lu_out=lus)
        if memo is not None and q.usable:
            memo[_LU_SLOT] = (q, lus)
        if q.usable and s != 1.0:
            q = _with_tangent(q, opts)
        return Trial(q.usable, q)

    res = continue_to(solve, nb, 0.0, 1.0, StepRules(retry="subdivide", max_depth=opts.substeps))
    # the answer is the last attempt at the target (a failed one carries the error)
    last = res.last_at(1.0)
    assert last is not None  # continue_to always attempts the target
    return _with_tangent(last.value, opts)


def _cold(theta, nu0, model, opts) -> _Point:
    return _with_tangent(_attempt(theta, nu0, model, opts, None, opts.n, cold=True), opts)
