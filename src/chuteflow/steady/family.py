"""Families of steady flows at fixed inclination, by continuation in ν0(0) (paper §3.2).

Along a family the neighbouring solution, advanced along the exact tangent dX/dβ
(β = ν0(0), :func:`~chuteflow.steady.steady_tangent`), is an excellent Newton start: two
or three iterations instead of a cold start's ten, and it follows the branch through
parameter regions where the isothermal cold start fails (the non-monotonic layers with a
dilute hot cushion under a denser band). Every point is nevertheless converged and
checked at two resolutions exactly as :func:`~chuteflow.steady.solve_steady` does.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._version import __version__
from ..closures import ChuteModel
from ..continuation import StepRules, Trial, continue_to
from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from ..spectral import coefficients
from .api import (
    ResolutionError,
    ThinLayerError,
    newton_tangent,
    solve_point,
    state_of,
    state_tangent_vectors,
    tangent_from,
    tangent_vectors,
)
from .existence import ExistenceVerdict, steady_existence
from .result import SteadyFlow
from .solver import NewtonState, _resample, validate_point

#: Scalar variables of a family / map dataset (float, NaN where no steady flow).
SCALARS = (
    "h",
    "nu_mean",
    "rho_bar",
    "Q",
    "T_mean",
    "u_floor",
    "T_floor",
    "y_max",
    "y_peak",
    "nu_peak",
    "convergence",
    "dQ_drho",
    "drho_dnu0",
    "dQ_dnu0",
)

_ATTRS = {
    "h": ("thickness h (ν0 = 1 % of its maximum)", "sigma"),
    "nu_mean": ("mean density ν̄ = ρ̄0 / h", "1"),
    "rho_bar": ("one-dimensional density ρ̄0 = ∫ν0 dy (eq. (3.15))", "sigma"),
    "Q": ("flux Q0 = ∫ν0 u0 dy (eq. (3.15))", "sigma^2 sqrt(g/sigma)"),
    "T_mean": ("density-weighted temperature T̄0", "g sigma"),
    "u_floor": ("slip velocity u0(0)", "sqrt(g sigma)"),
    "T_floor": ("floor temperature T0(0)", "g sigma"),
    "y_max": ("top of the domain, ν0(y_max) = nu_top", "sigma"),
    "y_peak": ("height of the density maximum (0 if monotonic)", "sigma"),
    "nu_peak": ("maximum packing fraction", "1"),
    "convergence": ("relative change of the scalars between resolutions n and 3n/2", "1"),
    "dQ_drho": ("dQ0/dρ̄0 along the family (exact tangent; eq. (B 6))", "sqrt(g sigma)"),
    "drho_dnu0": ("dρ̄0/dν0(0) along the family (exact tangent)", "sigma"),
    "dQ_dnu0": ("dQ0/dν0(0) along the family (exact tangent)", "sigma^2 sqrt(g/sigma)"),
    "monotonic": ("1 if ν0 decreases monotonically from the floor, 0 if its maximum is above the floor", "1"),
    "n": ("Chebyshev intervals of the accepted resolution", "1"),
    "status": ("'ok', 'thin' (h < min_thickness), 'no_steady_flow' or 'not_converged'", ""),
    "error": ("message of the error for points without a steady flow", ""),
}

#: A flow whose dense layer ends within this fraction of its thickness h below the top of
#: the domain (y_max − h < _TOP_GAP h: a cold top, the upper existence boundary near) is not
#: continued to a larger ν0(0): towards the boundary the layer's edge sharpens and meets the
#: top, and the Euler predictor misses (residuals 0.2–2.5, Newton stalls). Measured, steps up
#: in ν0(0) from such flows: on the 60 × 60 paper maps 51 of 51 failed
#: (φ = 0.05) and 56 of 56 (φ = 0.10); on the rows of the 60 × 60 φ = 0.05 diagram, whose ν0
#: steps are shorter, 91 of 111 (4.7 s of CPU, against 2.8 s for the 20 that converged).
#: Skipping them leaves the maps bit for bit the same and the diagram with every status and
#: stability label (13 flows reached by another road moved by ≤ 4.4e-10, within their
#: estimates; their dQ0/dρ̄0 by ≤ 1.2e-7), with 7–11 % less Newton work in its rows. The
#: point is still tried from its other neighbours and decided by the shooting scan: the
#: rule changes the road, never the answer. (At 0.3 the maps still lose no step, but the
#: diagram's rows lose 53 more that converge.)
_TOP_GAP = 0.1

#: Newton settings from a continuation guess (a good guess needs 2–5 full steps): failing
#: fast matters because beyond the existence boundary every point fails.
_CONT_MAXITER = 10
_CONT_LAM_MIN = 1.0 / 16


@dataclass(frozen=True)
class Options:
    """Solver settings shared by every point of a family or map.

    ``noise_exit``: a point's resolution ladder stops (the point is not converged) once the
    change between resolutions is at the solver's round-off floor, which grows with n, instead
    of climbing to n_max (:func:`~chuteflow.steady.api.solve_point`); on the 40 × 40 quick
    stability diagrams of both φ this changes no status and no value.

    Continuation steps take Newton's chord steps from the LUs of the row's last solve
    (:func:`_continue`) at the first rung of their ladder; ``beta_tangents`` (the default)
    keeps a fresh LU at the finer rungs, whose exact dX/dβ each flow then carries for
    :func:`~chuteflow.steady.api.steady_tangent` (the long-wave theory and the sweep's
    metrics of the same flows use it). A map, whose flows are only summarised, sets it
    False: every rung starts from the neighbour's LU (no factorisation where its chord
    steps converge), and steady_tangent would factorise.
    """

    nu_top: float = 1e-9
    n: int = 64
    rtol: float = 1e-8
    n_max: int = 384
    min_thickness: float = 1.0
    tangent: bool = True
    substeps: int = 1
    max_cold: int = 4
    max_cold_seeded: int = 1
    maxiter: int = _CONT_MAXITER
    lam_min: float = _CONT_LAM_MIN
    decide: bool = True
    noise_exit: bool = True
    beta_tangents: bool = True


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
    for a cold start, Newton takes chord steps (:attr:`~chuteflow.steady.solver.SteadyNewton.chord`),
    from the start with ``inherit`` ({n: LU} of a neighbour's solve); ``lu_out`` (a dict)
    receives those of this solve, {n: LU} at its two accepted resolutions, if it gives a flow."""
    kw: dict[str, Any] = (
        {}
        if cold
        else {
            "maxiter": opts.maxiter,
            "lam_min": opts.lam_min,
            "chord": True,
            "inherit": inherit,
            "inherit_fine": not opts.beta_tangents,
        }
    )
    keep: dict = {}
    try:
        flow = solve_point(
            theta,
            nu0,
            model,
            opts.nu_top,
            n,
            opts.rtol,
            opts.n_max,
            start,
            opts.min_thickness,
            noise_exit=opts.noise_exit,
            keep=keep,
            **kw,
        )
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
    (:func:`~chuteflow.steady.api.solve_point` with ``keep``), dX/dθ left for
    :func:`_predict` to add if a step in θ needs it: for a predictor, dX/dβ of the coarser
    accepted resolution; with ``opts.tangent`` (an output), that of the finer one if Newton's
    last step after that LU was small enough (:func:`~chuteflow.steady.api.newton_tangent`;
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
        st0 = _resample(st0, len(point.vectors[0]) // 3 - 1)
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
    ``opts.tangent``, the derivatives along the family (:func:`tangent_from`). Those are
    outputs and use the exact Jacobian at the accepted resolution; a predictor needs no such
    accuracy, so without ``opts.tangent`` the vectors come from the coarser of the two
    resolutions the flow was checked at (a third of the cost of the LU factorisation)."""
    if point.flow is not None and point.vectors is None:
        f = point.flow
        try:
            if opts.tangent and point.status == "ok":
                point.vectors = tangent_vectors(f, theta=True)
                point.tangent = tangent_from(f, point.vectors[0])
            else:
                st = state_of(f)
                st = _resample(st, _start_n(f, opts))
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

    ``memo`` (a dict shared by the calls of one row, :func:`continue_row`) keeps every
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


def _top_bound(point: _Point) -> bool:
    """Whether ``point``'s dense layer ends within :data:`_TOP_GAP` h of the top of its
    domain (no continuation from it to a larger ν0(0))."""
    f = point.flow
    return f is not None and f.y_max - f.h < _TOP_GAP * f.h


_TOP_BOUND_MESSAGE = (
    "not continued from the smaller floor density: its dense layer ends at the top of the "
    "domain (the upper existence boundary is near)"
)


def _cold(theta, nu0, model, opts) -> _Point:
    return _with_tangent(_attempt(theta, nu0, model, opts, None, opts.n, cold=True), opts)


#: Verdict kinds of :func:`~chuteflow.steady.existence.steady_existence` that extend to
#: smaller θ and ν0(0) (the layer is too thin / heats up) and to larger θ and ν0(0) (it
#: collapses or packs): the region with a steady flow lies between them.
_LOW_KINDS = ("too_small", "thin")
_HIGH_KINDS = ("too_large",)


@dataclass(frozen=True)
class Proof:
    """A point where the shooting scan proves that no (physical) steady flow exists.

    The scan's verdicts are ordered (tests/steady/test_existence_map.py checks this against
    an independent shooting scan over the paper's ranges): a layer too thin or heating up
    at (θ, ν0(0)) (kind ``too_small`` or ``thin``) is so at every smaller θ and ν0(0); one
    that collapses or packs (``too_large``) is so at every larger θ and ν0(0). A proof
    therefore decides a whole quadrant of a map without further scans.
    """

    theta: float
    nu0: float
    kind: str
    reason: str

    def covers(self, theta: float, nu0: float) -> bool:
        """Whether the quadrant of this verdict contains (θ, ν0(0))."""
        eps = 1e-12
        if self.kind in _LOW_KINDS:
            return theta <= self.theta + eps and nu0 <= self.nu0 * (1 + eps)
        if self.kind in _HIGH_KINDS:
            return theta >= self.theta - eps and nu0 >= self.nu0 * (1 - eps)
        return abs(theta - self.theta) < eps and abs(nu0 - self.nu0) <= eps * self.nu0


def _implied(theta, nu0, model, proof: Proof) -> _Point:
    side = "smaller" if proof.kind in _LOW_KINDS else "larger"
    where = (
        f"theta = {theta:g} deg, nu0 = {nu0:g}, roughness = {model.roughness:g}, "
        f"wall_loss = {model.wall_loss:g}"
    )
    return _Point(
        "no_steady_flow",
        None,
        f"no steady flow at {where}: the shooting scan at theta = {proof.theta:g} deg, "
        f"nu0 = {proof.nu0:g} finds none ({proof.kind.replace('_', ' ')}), and that verdict "
        f"holds at every {side} angle and floor density — there: {proof.reason}",
    )


def _estimate(v: ExistenceVerdict) -> str:
    return f"u0(0) = {v.u_floor:.6g}, h = {v.h:.4g}, y_max = {v.y_max:.4g}"


def _decide(theta, nu0, model, opts: Options) -> tuple[_Point, ExistenceVerdict | None]:
    """The shooting scan's verdict at (θ, ν0(0)) (:func:`steady_existence`); where a flow
    exists, Newton from the shot profile at n, 2n, … ≤ n_max (a layer thinner than
    ``min_thickness``: from n only; one thinner than a diameter: from n and 2n)."""
    try:
        v = steady_existence(theta, nu0, model, nu_top=opts.nu_top, min_thickness=opts.min_thickness)
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        return _Point("not_converged", None, f"the shooting scan failed: {type(exc).__name__}: {exc}"), None
    if not v.exists:
        return _Point("no_steady_flow", None, v.reason), v
    m, errors = opts.n, []
    if not v.physical:  # thinner than min_thickness: kept only as a thin layer
        m_last = opts.n
    elif v.h < 1.0:
        # below one diameter (outside the hydrodynamics, §3.2) Newton from the shot profile
        # converges from n or 2n, or stalls at a resolution change of 1e-7…1e-4 from every
        # start: the start from 4n (its ladder also climbs to n_max, ~0.5 s a point)
        # converged nowhere on the 40 × 40 quick diagrams
        m_last = 2 * opts.n
    else:
        m_last = opts.n_max
    while m <= m_last:
        # the shot profile is accurate to ~1e-6: Newton converges in a few steps where the
        # grid resolves the layer, so fail fast as from a continuation guess
        p = _attempt(theta, nu0, model, opts, v.starting_state(m), m)
        if p.usable:
            return _with_tangent(p, opts), v
        errors.append(f"n = {m}: {p.error}")
        m *= 2
    if not v.physical:
        # the scan's solution is thinner than min_thickness: a thin layer, as where Newton
        # resolves it (the label must not depend on which of the two found it)
        return _Point("thin", None, v.reason), v
    if v.h < 1.0:
        # accepted by min_thickness < 1, but thinner than a diameter: outside the
        # hydrodynamics and not examined by the paper (§3.2, figure 6: h < 1)
        return (
            _Point(
                "no_steady_flow",
                None,
                f"no physical steady flow at theta = {theta:g} deg, nu0 = {nu0:g}: the shooting "
                f"scan finds a layer thinner than one diameter ({_estimate(v)}), which Newton "
                f"does not resolve with n_max = {opts.n_max} and the hydrodynamics cannot "
                "describe (§3.2)",
            ),
            v,
        )
    return (
        _Point(
            "not_converged",
            None,
            f"a steady flow exists at theta = {theta:g} deg, nu0 = {nu0:g} (shooting scan: "
            f"{_estimate(v)}) but is not resolved: Newton from the continuation neighbours, the "
            f"isothermal start and the shooting profile did not converge to rtol = "
            f"{opts.rtol:g} with n_max = {opts.n_max} ({'; '.join(errors)})",
        ),
        v,
    )


def _undecided_target(pts, settled, usable) -> int | None:
    """Next point to decide by the shooting scan: in a run of undecided points, the end
    next to a point where ``usable`` holds (a converged flow: the existence boundary is
    there; or a point the scan has decided), else the middle."""
    N = len(pts)
    runs, i = [], 0
    while i < N:
        if settled(i):
            i += 1
            continue
        j = i
        while j + 1 < N and not settled(j + 1):
            j += 1
        runs.append((i, j))
        i = j + 1
    for a, b in runs:
        if b + 1 < N and usable(b + 1):
            return b
        if a > 0 and usable(a - 1):
            return a
    if runs:
        a, b = runs[0]
        return (a + b) // 2
    return None


def _anchor_order(n: int) -> list[int]:
    """Cold-start candidates spread over the row: middle, quartiles, eighths, …"""
    order: list[int] = []
    seen: set[int] = set()
    k = 2
    while len(order) < n:
        for j in range(1, k, 2):
            i = min(n - 1, (j * n) // k)
            if i not in seen:
                seen.add(i)
                order.append(i)
        k *= 2
        if k > 4 * n:
            order += [i for i in range(n) if i not in seen]
            break
    return order


def continue_row(
    theta: float,
    nu0_values,
    model: ChuteModel,
    opts: Options,
    previous: list[_Point] | None = None,
    existing: list[_Point] | None = None,
    cold_starts: bool = True,
    proofs: list[Proof] | None = None,
) -> list[_Point]:
    """Solve at every ν0 of a row (sorted ascending) by continuation.

    A point is started from a converged neighbour: the one below or above in ν0 (predicted
    along the exact tangent), or the same ν0 in ``previous`` (the neighbouring θ row of a
    map; predicted along dX/dθ). Each source is tried once per point; a step up in ν0 from a
    flow whose layer reaches the top of its domain is not taken (:data:`_TOP_GAP`). Walks
    along ν0 go first; when they stall, one point is seeded from ``previous`` and the walks
    resume.
    When nothing more can be reached, a cold start is tried at a spread-out point not yet
    attempted (at most ``opts.max_cold`` per row, ``opts.max_cold_seeded`` if ``previous``
    is given: in a map the existence region is reached from the neighbouring rows).

    Continuation is only the fast road. Every point it does not reach is decided
    (``opts.decide``) by the shooting scan :func:`~chuteflow.steady.existence.steady_existence`
    or by an earlier scan's verdict that covers it (:class:`Proof`; ``proofs`` collects
    them and may be shared by the rows of a map): no flow (with the scan's reason), or a
    flow, solved by Newton from the shot profile and then continued to its neighbours. A
    run of undecided points is scanned at its end next to a converged flow, where the
    existence boundary lies (or next to a point already scanned: outwards), so that one
    verdict usually settles the whole run; while such a run is undecided no cold start is
    tried, and none ever at a point a verdict covers. In a family (no ``previous``) a point
    where the scan finds a flow that Newton from the shot profile does not resolve gets the
    cold start as the last resort. With ``opts.decide = False`` the points continuation did
    not reach are 'unreached'.
    """
    nus = [float(v) for v in nu0_values]
    N = len(nus)
    pts: list[_Point | None] = [None] * N
    tried: list[set] = [set() for _ in range(N)]
    if existing is not None:
        for i, p in enumerate(existing):
            if p is not None and p.status != _UNREACHED:
                pts[i], tried[i] = p, set(p.tried)
    prev = previous if previous is not None else [None] * N
    order = _anchor_order(N)
    # a θ source is identified by its angle, so that both neighbouring rows can be tried
    ttag = ("theta", next((p.flow.theta for p in prev if p is not None and p.flow is not None), None))
    proofs = proofs if proofs is not None else []
    memo: dict = {}  # continuation steps already tried in this row (see _continue)

    def usable(i):
        return pts[i] is not None and pts[i].usable

    def proven(i):
        # decided by the shooting scan (or a scan's covering verdict) to have no flow:
        # continuation does not try it again
        return not usable(i) and ("scan" in tried[i] or "proof" in tried[i])

    def settled(i):
        return usable(i) or "scan" in tried[i] or "proof" in tried[i]

    def anchor(i):
        # where a run of undecided points is decided from: next to a flow (the existence
        # boundary is there) or next to a scanned point (outwards from the boundary)
        return usable(i) or "scan" in tried[i]

    def open_(i):
        return not usable(i) and not proven(i)

    def attempt(i, tag, make):
        tried[i].add(tag)
        p = make()
        if pts[i] is None or p.usable:
            pts[i] = p

    cold = [0]

    def covering(i) -> Proof | None:
        # a scan's verdict that decides point i (no flow there), if any
        return next((q for q in proofs if q.covers(theta, nus[i])), None)

    def walk():
        while True:
            walked = False
            for i in range(1, N):
                below = pts[i - 1]
                if open_(i) and below is not None and below.usable and "below" not in tried[i]:
                    if _top_bound(below):
                        # recorded as a failed step, without its cost (_TOP_GAP)
                        attempt(i, "below", lambda: _Point("not_converged", None, _TOP_BOUND_MESSAGE))
                        continue
                    attempt(i, "below", functools.partial(_continue, below, theta, nus[i], model, opts, memo))
                    walked = True
            for i in range(N - 2, -1, -1):
                above = pts[i + 1]
                if open_(i) and above is not None and above.usable and "above" not in tried[i]:
                    attempt(i, "above", functools.partial(_continue, above, theta, nus[i], model, opts, memo))
                    walked = True
            if walked:
                continue
            seeded = [
                (i, src)
                for i in order
                if open_(i) and (src := prev[i]) is not None and src.usable and ttag not in tried[i]
            ]
            if seeded:
                i, seed = seeded[0]
                attempt(i, ttag, functools.partial(_continue, seed, theta, nus[i], model, opts, memo))
                continue
            if not cold_starts:
                return
            if opts.decide:
                # with the scan deciding, the ends of the pieces of the branch found so far
                # go first, outwards: the verdict there (a proof for a whole quadrant,
                # usually the rest of the run) says where a cold start is pointless (a
                # failed cold start costs ~0.15 s, a too_small verdict 0.04 s), and a scan
                # finds any other piece of the branch
                t = _undecided_target(pts, settled, anchor)
                if t is not None and any(0 <= j < N and anchor(j) for j in (t - 1, t + 1)):
                    return
            # walks stalled: a cold start where nothing has been attempted yet (a separate
            # piece of the branch, or no piece found so far), unless a scan's verdict
            # already proves that there is none
            cand = [i for i in order if not tried[i] and covering(i) is None]
            if previous is None and not cand and not opts.decide:
                # a family without the scan: points where continuation failed get a cold
                # start too (the isothermal start sometimes succeeds where a far
                # neighbour's predictor does not; with the scan, after it: see below)
                cand = [
                    i
                    for i in order
                    if open_(i)
                    and "cold" not in tried[i]
                    and ((i > 0 and usable(i - 1)) or (i < N - 1 and usable(i + 1)))
                ]
            if not cand or cold[0] >= (opts.max_cold if previous is None else opts.max_cold_seeded):
                return
            cold[0] += 1
            attempt(cand[0], "cold", functools.partial(_cold, theta, nus[cand[0]], model, opts))

    while True:
        walk()
        if not opts.decide:
            break
        target = _undecided_target(pts, settled, anchor)
        if target is None:
            break
        i = target
        cover = covering(i)
        if cover is not None:
            tried[i].add("proof")
            pts[i] = _implied(theta, nus[i], model, cover)
            continue
        tried[i].add("scan")
        p, v = _decide(theta, nus[i], model, opts)
        nb = [j for j in (i - 1, i + 1) if 0 <= j < N and usable(j)]
        if not p.usable and v is not None and v.exists and nb and "substeps" not in tried[i]:
            # the scan finds a flow that Newton from the shot profile does not resolve: next
            # to a converged flow, shorter continuation steps often reach it (a sharp layer
            # near the upper existence boundary). After the scan, not before: the scan's
            # verdict (5–30 ms) usually settles the point, shorter steps cost ~0.1 s
            tried[i].add("substeps")
            fine = dataclasses.replace(opts, substeps=max(opts.substeps, 2))
            seed = pts[nb[0]]
            assert seed is not None  # usable
            q = _continue(seed, theta, nus[i], model, fine, memo)
            p = q if q.usable else p
        if p.status == "not_converged" and previous is None and cold_starts and "cold" not in tried[i]:
            # a flow exists but Newton from the shot profile did not converge: the isothermal
            # cold start sometimes does (the family's rule for points where continuation
            # failed, above, applied after the scan)
            tried[i].add("cold")
            q = _cold(theta, nus[i], model, opts)
            p = q if q.usable else p
        pts[i] = p
        if v is not None and (v.kind in _LOW_KINDS or v.kind in _HIGH_KINDS) and p.status != "ok":
            proofs.append(Proof(theta, nus[i], v.kind, v.reason))
    out = []
    for pt, t in zip(pts, tried):
        point = (
            pt
            if pt is not None
            else _Point(
                _UNREACHED,
                None,
                "not reached: no converged neighbour to continue from and no cold start tried here",
            )
        )
        point.tried = frozenset(t)
        out.append(point)
    return out


def row_arrays(points: list[_Point]) -> dict[str, np.ndarray]:
    """Scalar results of solved family points as arrays (NaN where not ``ok``), by variable."""
    N = len(points)
    out = {k: np.full(N, np.nan) for k in SCALARS}
    out["monotonic"] = np.full(N, np.nan)
    out["n"] = np.zeros(N, dtype=int)
    out["status"] = np.array([p.status for p in points], dtype=object)
    out["error"] = np.array([p.error for p in points], dtype=object)
    for i, p in enumerate(points):
        if p.status != "ok":
            continue
        f = p.flow
        assert f is not None  # status "ok" carries a flow
        for k in (
            "h",
            "nu_mean",
            "rho_bar",
            "Q",
            "T_mean",
            "u_floor",
            "T_floor",
            "y_max",
            "y_peak",
            "nu_peak",
            "convergence",
        ):
            out[k][i] = getattr(f, k)
        out["monotonic"][i] = 1.0 if f.monotonic else 0.0
        out["n"][i] = f.n
        if p.tangent is not None:
            out["dQ_drho"][i] = p.tangent["dQ_drho"]
            out["drho_dnu0"][i] = p.tangent["drho_bar"]
            out["dQ_dnu0"][i] = p.tangent["dQ"]
    return out


def dataset_attrs(model: ChuteModel, opts: Options) -> dict:
    """Attributes of a family or map Dataset: the model, the solver options and the version."""
    attrs = dict(model.attrs())
    attrs.update(
        nu_top=opts.nu_top,
        rtol=opts.rtol,
        min_thickness=opts.min_thickness,
        chuteflow_version=__version__,
        source="Mitarai & Nakanishi §3.2",
    )
    return {k: (str(v) if isinstance(v, bool) else v) for k, v in attrs.items()}


def check_nu0(nu0_values, model) -> np.ndarray:
    """Validated floor densities: a non-empty, strictly increasing 1-D array in (0, ν_m)."""
    nus = np.atleast_1d(np.asarray(nu0_values, dtype=float))
    if nus.ndim != 1 or len(nus) == 0:
        raise ParameterError("nu0_values: expected a non-empty 1-D sequence of floor densities")
    if len(nus) > 1 and not (np.all(np.diff(nus) > 0)):
        raise ParameterError("nu0_values must be strictly increasing (continuation walks along them)")
    for v in nus:
        validate_point(20.0, v, model, min(1e-9, 1e-4 * nus.min()))
    return nus


def steady_family(
    theta: float,
    nu0_values,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    n: int = 64,
    rtol: float = 1e-8,
    n_max: int = 384,
    min_thickness: float = 1.0,
    tangent: bool = True,
    return_flows: bool = False,
):
    """Steady flows at inclination ``theta`` for each floor density in ``nu0_values``.

    Parameters
    ----------
    theta : float
        Inclination θ in degrees.
    nu0_values : sequence of float
        Floor densities ν0(0), strictly increasing.
    model : ChuteModel, optional
        Closure parameters (paper defaults).
    nu_top, n, rtol, n_max, min_thickness
        As for :func:`~chuteflow.steady.solve_steady`.
    tangent : bool
        Also compute dQ0/dρ̄0, dρ̄0/dν0(0), dQ0/dν0(0) from the exact family tangent
        (eq. (B 6)); about 2 ms per point.
    return_flows : bool
        Also return the list of :class:`SteadyFlow` (None where there is none).

    Returns
    -------
    xarray.Dataset
        Over ``nu0``: the scalars of :data:`SCALARS`, ``monotonic`` (1/0), ``n``,
        ``status`` and ``error`` (strings). Points without a physical steady flow are NaN
        with their status; no exception is raised for them. Attributes: the model
        parameters, ``theta``, ``nu_top``, ``rtol``, ``min_thickness`` and the chuteflow
        version.
    """
    import xarray as xr

    model = model or ChuteModel()
    opts = Options(nu_top=nu_top, n=n, rtol=rtol, n_max=n_max, min_thickness=min_thickness, tangent=tangent)
    theta, nus, pts = _row(theta, nu0_values, model, opts)
    arr = row_arrays(pts)
    ds = xr.Dataset(
        {k: ("nu0", v, variable_attrs(k)) for k, v in arr.items()},
        coords={"nu0": ("nu0", nus, {"long_name": "floor packing fraction ν0(0)", "units": "1"})},
        attrs={**dataset_attrs(model, opts), "theta": theta},
    )
    if return_flows:
        return ds, [p.flow if p.status == "ok" else None for p in pts]
    return ds


def _row(theta, nu0_values, model: ChuteModel, opts: Options):
    theta = validate_point(theta, 0.5 * model.nu_max, model, 1e-9)[0]
    nus = check_nu0(nu0_values, model)
    validate_point(theta, nus[0], model, opts.nu_top)
    return theta, nus, continue_row(theta, nus, model, opts)


def steady_row(
    theta: float,
    nu0_values,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    n: int = 64,
    rtol: float = 1e-8,
    n_max: int = 384,
    min_thickness: float = 1.0,
) -> list[tuple[str, SteadyFlow | None, str]]:
    """The solves of :func:`steady_family` without the Dataset: (status, flow, error) per
    floor density, the flow None unless the status is ``"ok"``.

    For callers that need the flows only (a sweep's rows: no table of derived scalars, and
    no xarray in a worker process). Same arguments as :func:`steady_family` (without the
    family tangent); the same solves, so the same flows bit for bit.
    """
    model = model or ChuteModel()
    opts = Options(nu_top=nu_top, n=n, rtol=rtol, n_max=n_max, min_thickness=min_thickness, tangent=False)
    pts = _row(theta, nu0_values, model, opts)[2]
    return [(p.status, p.flow if p.status == "ok" else None, p.error) for p in pts]


def variable_attrs(k):
    """``long_name`` and ``units`` attributes of the family variable ``k``."""
    name, units = _ATTRS.get(k, (k, ""))
    return {"long_name": name, "units": units}


def flux_minimum(
    theta: float,
    model: ChuteModel | None = None,
    *,
    nu0_values=None,
    nu_top: float = 1e-9,
    rtol: float = 1e-8,
    xtol: float = 1e-9,
):
    """Minimum of Q0(ρ̄0) at fixed θ: the root of dQ0/dν0(0) along the family (eq. B 6).

    A family on ``nu0_values`` (default 30 values from 0.005 to 0.3, geometric) brackets a
    sign change of dQ0/dρ̄0 from − to + (both from the exact tangent); Brent's method then
    refines it, each evaluation continued from the nearest converged flow.

    Returns
    -------
    dict or None
        None when dQ0/dρ̄0 keeps its sign on the family (Q0 monotonic in ρ̄0). Otherwise
        ``nu0``, ``rho_bar``, ``Q``, ``h``, ``nu_mean`` at the minimum, ``bracket`` (the two
        family points around it) and ``family`` (the dataset).
    """
    from .._memory import brentq  # scipy's, without keeping the family's flows alive

    model = model or ChuteModel()
    if nu0_values is None:
        nu0_values = np.geomspace(0.005, 0.3, 30)
    fam, flows = steady_family(theta, nu0_values, model, nu_top=nu_top, rtol=rtol, return_flows=True)
    ok = np.nonzero(fam.status.values == "ok")[0]
    slope = fam.dQ_drho.values
    idx = [i for a, i in zip(ok[:-1], ok[1:]) if i == a + 1 and slope[a] < 0 < slope[i]]
    if not idx:
        return None
    i = idx[0]
    opts = Options(nu_top=nu_top, rtol=rtol, min_thickness=0.0)
    cache: dict[float, _Point] = {}
    seeds = [_with_tangent(_Point("ok", flows[i - 1]), opts), _with_tangent(_Point("ok", flows[i]), opts)]

    def g(nu0):
        nb = min(seeds, key=lambda p: abs(p.flow.nu0 - nu0))  # type: ignore[union-attr]  # seeds have flows
        p = _continue(nb, theta, nu0, model, opts)
        if not p.usable:
            raise ConvergenceError(
                f"flux minimum at theta = {theta:g}: no converged flow at nu0 = {nu0:g} ({p.error})"
            )
        cache[nu0] = p
        assert p.tangent is not None  # a usable point has its tangent
        return p.tangent["dQ_drho"]

    root = brentq(g, float(fam.nu0[i - 1]), float(fam.nu0[i]), xtol=xtol, rtol=1e-12)
    f = (cache.get(root) or _continue(seeds[0], theta, root, model, opts)).flow
    assert f is not None  # g(root) was evaluated, and g raises where no flow converged
    return {
        "nu0": root,
        "rho_bar": f.rho_bar,
        "Q": f.Q,
        "h": f.h,
        "nu_mean": f.nu_mean,
        "bracket": (float(fam.nu0[i - 1]), float(fam.nu0[i])),
        "family": fam,
    }


def separatrix(
    model: ChuteModel | None = None,
    *,
    theta_range=(14.0, 15.0),
    nu0_small: float = 0.006,
    nu0_ref: float = 0.012,
    xtol: float = 0.01,
    nu_top: float = 1e-9,
) -> dict:
    """Angle θ* separating contours of θ that collapse (h → 0) from those that diverge
    (h → ∞) as ν̄ decreases (§3.2, figure 2(a)).

    A family is *diverging* at θ when it reaches ν0(0) = ``nu0_small`` with h still growing
    as ν0(0) decreases (h(nu0_small) > h(nu0_ref)); otherwise (h falling, or the branch ending
    before ``nu0_small``) it is *collapsing*. θ* is bracketed in ``theta_range`` and bisected
    to ``xtol``. Since ν0(0) cannot reach 0, this locates the separatrix at ν̄ ≈ 1e-3, not in
    the limit.

    Returns
    -------
    dict
        ``theta`` (θ*, midpoint of the final bracket), ``bracket``, ``h`` (thickness at
        ν0(0) = ``nu0_small`` on the diverging side of the bracket), ``nu_mean`` there, and
        ``h_lo_side`` (the last h reached on the collapsing side).
    """
    model = model or ChuteModel()
    nus = np.array(sorted({nu0_small, nu0_ref, 0.0085, 0.018, 0.025, 0.035, 0.05, 0.07}))
    i_small, i_ref = int(np.argmin(abs(nus - nu0_small))), int(np.argmin(abs(nus - nu0_ref)))

    def classify(theta):
        ds = steady_family(theta, nus, model, nu_top=nu_top, min_thickness=0.0, tangent=False)
        h = ds.h.values
        ok = ds.status.values == "ok"
        diverging = bool(ok[i_small] and ok[i_ref] and h[i_small] > h[i_ref])
        last = h[np.nonzero(ok)[0][0]] if ok.any() else float("nan")
        return diverging, ds, last

    lo, hi = map(float, theta_range)
    d_lo, _, last_lo = classify(lo)
    d_hi, ds_hi, _ = classify(hi)
    if d_lo or not d_hi:
        raise ConvergenceError(
            f"separatrix: theta_range = {theta_range} does not bracket it (diverging at "
            f"{lo:g}: {d_lo}, at {hi:g}: {d_hi})"
        )
    while hi - lo > xtol:
        mid = 0.5 * (lo + hi)
        d, ds, last = classify(mid)
        if d:
            hi, ds_hi = mid, ds
        else:
            lo, last_lo = mid, last
    return {
        "theta": 0.5 * (lo + hi),
        "bracket": (lo, hi),
        "h": float(ds_hi.h.values[i_small]),
        "nu_mean": float(ds_hi.nu_mean.values[i_small]),
        "h_lo_side": float(last_lo),
    }


__all__ = ["steady_family", "flux_minimum", "separatrix", "SCALARS", "Options", "continue_row"]
