"""Steady flows uniform along the slope (paper §3): Chebyshev–Newton on a free top boundary.

For given θ and floor density ν0(0) the unknowns are ln ν0, u0, T0 at the Chebyshev nodes of
[0, y_max] (clustered at the layer's edge by a sinh map, :func:`layer_grid_map`) and the
height y_max itself, fixed by ν0(y_max) = ``nu_top`` (paper: 1e-9). The
equations are the uniform-state residuals of :mod:`chuteflow.equations`: y-momentum and
energy (eqs 3.5, 3.6) at the inner nodes, x-momentum in its integrated form
eq. (3.7) (μ u0' = tanθ p, the weight of the tail above y_max included;
:func:`chuteflow.equations.first_integrals`), the floor conditions eqs (2.9) and (2.10)
(equivalent to eqs (3.11), (3.12)), T0' = 0 on top (eq. (3.13): the far-field condition of
:func:`chuteflow.equations.far_field_conditions` at k = 0) and ν0(0) given. Every row and
its exact Jacobian come from the compiled equations, so this module states no physics of
its own; Newton converges quadratically.

Unlike the paper's shooting on u0(0), no growing mode is integrated, so there is nothing to
tune by hand. The cold start is an isothermal estimate of the layer (closed form in T),
polished on a coarse grid; continuation (families, maps, the θ fallback of
:func:`~chuteflow.steady.solve_steady`) starts from neighbouring solutions instead.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from ..closures.model import FUNCTIONS, ORDERS
from ..equations import BASE, TOP_OF, arguments, compiled_equations
from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from ..spectral import ChebyshevGrid, barycentric, coefficients, reference_nodes
from ._newton_kernel import OUTPUTS, SLOT, row_kernel
from .result import fine_sampling, steady_grid

_FIELDS = ("nu", "u", "T")
#: Rows of the compiled outputs (:data:`._newton_kernel.SLOT`) by unknown (s = ln ν0, u0, T0:
#: the Jacobian's blocks 0, 1, 2) and derivative order.
_SLOTS = tuple(tuple(SLOT[(f, c)] for c in range(3)) for f in ("s", "u", "T"))

#: Width of the steady grid's sinh map in units of the dilute top's scale height T0(h)/cos θ
#: (the same choice as the stability operator's map, :func:`chuteflow.stability.layer_map`).
MAP_WIDTH = 2.0
#: Maps wider than this fraction of y_max are dropped (plain Chebyshev nodes): the layer
#: then has no sharp edge and the sinh map would only move nodes away from the floor.
_MAP_MAX = 0.5


@functools.lru_cache(maxsize=8)
def reference_grid(n: int, grid_map: tuple[float, float] | None = None) -> ChebyshevGrid:
    """The steady grid on ξ = y/y_max ∈ [0, 1] (:func:`~chuteflow.steady.result.steady_grid`
    with y_max = 1); cached, its arrays are shared. The map differs from flow to flow, so
    only the last few are kept (a Newton solve asks for its grid at every iteration; 64
    grids with their D and D2 held 42 MiB after one row of a 60 × 60 diagram, 8 hold
    ~5 MiB and miss 4 % more often)."""
    return steady_grid(n, 1.0, grid_map)


@dataclass
class NewtonState:
    """Nodal unknowns: s = ln ν0 (keeps relative accuracy over nine decades), u0, T0, y_max,
    on the nodes ξ_j y_max of :func:`reference_grid` (n, ``grid_map``)."""

    n: int
    s: np.ndarray
    u: np.ndarray
    T: np.ndarray
    L: float
    grid_map: tuple[float, float] | None = None
    #: Set by Newton (:meth:`SteadyNewton.solve` with ``tangents``) on the state it returns:
    #: (dX/dβ, relative size of the last Newton step), the family tangent (β = ν0(0))
    #: solved with the last Jacobian, which was taken at the state before that step.
    tangents: tuple | None = field(default=None, repr=False, compare=False)
    #: Set by Newton with chord steps (:attr:`SteadyNewton.chord`) on the state it returns:
    #: J⁻¹ B from the last LU it used (:meth:`SteadyNewton.factored_step`), for the chord
    #: steps of a neighbour's solve at the same n (:attr:`SteadyNewton.inherit`).
    lu: Any = field(default=None, repr=False, compare=False)

    @property
    def nu(self):
        return np.exp(self.s)

    @property
    def ref(self) -> ChebyshevGrid:
        """The grid of the nodes in ξ = y/y_max."""
        return reference_grid(self.n, self.grid_map)

    def pack(self):
        return np.concatenate([self.s, self.u, self.T, [self.L]])

    @classmethod
    def unpack(cls, n, X, grid_map=None):
        m = n + 1
        return cls(n, X[:m].copy(), X[m : 2 * m].copy(), X[2 * m : 3 * m].copy(), float(X[-1]), grid_map)


def layer_grid_map(st: NewtonState, theta_deg: float) -> tuple[float, float] | None:
    """The sinh map (ξ_c, ξ_w) that clusters nodes at the edge of the layer of ``st``.

    Above the dense layer the density falls with the scale height T0/cos θ of an
    isothermal atmosphere (y-momentum balance p' = −ν cos θ with p ≈ νT): at the edge of a
    dense band under a cold top (the upper existence boundary, T0 ~ 0.1 there) ln ν0 bends
    from the band's profile to that slope within a few scale heights, which a plain Chebyshev
    grid on [0, y_max] resolves only with n ≈ 500 (its nodes crowd the floor and the top
    instead). The map of :class:`~chuteflow.spectral.MappedChebyshevGrid` centred at the
    thickness h (ν0 at 1 % of its maximum, to the spacing of 8n + 1 samples equidistant in
    the grid's variable x) with width ε = :data:`MAP_WIDTH` T0(h)/cos θ puts a fixed number
    of nodes across that bend; the converged flow does not depend on it (the ladder of
    :func:`~chuteflow.steady.api.solve_point` checks the resolution).

    Returns None (plain grid) where the width exceeds half the domain or the profile has
    no edge (a state far from converged).
    """
    try:
        ref = st.ref
        # sampled at 8n + 1 points equidistant in the grid's own variable x (the series'
        # variable: one matrix product, :func:`~chuteflow.steady.result.fine_sampling`)
        xf, V = fine_sampling(st.n)
        s = V @ coefficients(st.s)
        k = int(np.argmax(s))
        below = np.nonzero(s[k:] <= s[k] + math.log(0.01))[0]
        if not len(below):
            return None
        xc = float(ref.from_computational(xf[k + below[0]]))
        T_h = float(ref.interpolate(st.T, np.array([xc]))[0])
        xw = MAP_WIDTH * T_h / math.cos(math.radians(theta_deg)) / st.L
    except (ValueError, ArithmeticError, IndexError):
        return None
    if not (math.isfinite(xw) and 0.0 < xw <= _MAP_MAX and 0.0 < xc < 1.0):
        return None
    return (xc, xw)


def validate_point(theta, nu0, model, nu_top):
    """(θ, ν0(0)) as floats after checking θ ∈ (0, 90)°, ν0(0) ∈ (0, ν_m), ``nu_top`` ∈ (0, 1e-3 ν0(0)).

    Raises :class:`~chuteflow.errors.ParameterError` naming the parameter and its range.
    """
    try:
        theta = float(theta)
        nu0 = float(nu0)
    except (TypeError, ValueError):
        raise ParameterError("theta and nu0 must be numbers") from None
    if not (0.0 < theta < 90.0) or not math.isfinite(theta):
        raise ParameterError(
            f"theta = {theta!r} is outside (0, 90) degrees: the slope "
            "angle must be positive for a flow down the incline"
        )
    if not (0.0 < nu0 < model.nu_max):
        raise ParameterError(
            f"nu0 = {nu0!r} is outside (0, nu_max = {model.nu_max:g}): the "
            "floor packing fraction must be positive and below maximum packing"
        )
    if not (0.0 < nu_top < 1e-3 * nu0):
        raise ParameterError(
            f"nu_top = {nu_top!r} must lie in (0, 1e-3·nu0): it is the "
            "density at which the domain ends (paper: 1e-9)"
        )
    return theta, nu0


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


def _rows(v, sl: slice, m: int) -> np.ndarray:
    """The rows ``sl`` of a compiled coefficient or residual: an array over the m nodes,
    or a constant (the generated code returns scalars for node-independent terms)."""
    v = np.asarray(v, dtype=float)
    if v.ndim:
        return v[sl]
    return np.full(len(range(*sl.indices(m))), float(v))


@functools.cache
def _steady_terms(ce) -> tuple[tuple[int, str, int, int], ...]:
    """The terms of a compiled equation that a uniform steady state feels — no t, x, z
    dependence, v = w = 0, |k| = 0 — as (coefficient index, field, field's block, order)."""
    return tuple(
        (i, t.field, _FIELDS.index(t.field), t.c)
        for i, t in enumerate(ce.terms)
        if not (t.a or t.b or t.d or t.k or t.field in ("v", "w"))
    )


class SteadyNewton:
    """Residual and exact Jacobian of the steady free-boundary problem on n + 1 nodes."""

    def __init__(self, n, theta_deg, nu0, model, nu_top, integrated=True, grid_map=None):
        self.n = n
        self.integrated = integrated
        self.grid_map = grid_map
        self.ref = reference_grid(n, grid_map)
        th = math.radians(theta_deg)
        self.sin, self.cos = math.sin(th), math.cos(th)
        self.nu0, self.model = nu0, model
        self.ln0, self.lntop = math.log(nu0), math.log(nu_top)
        self.eqs = compiled_equations()
        self._last: tuple[np.ndarray, dict] | None = None  # see evaluate
        #: Newton also solves for dX/dβ (β = ν0(0)) with each LU (see _solve)
        self.tangents = False
        #: Newton reuses its last LU for chord steps while they contract fast (see _solve)
        self.chord = False
        #: with chord: a neighbour's LU at this n (:attr:`NewtonState.lu`), for chord steps
        #: from the start (continuation: the Jacobian of a nearby flow)
        self.inherit = None
        self._latest = None  # the last LU a chord solve used (see solve)
        # (equation, rows of the system, nodes it is imposed at, row-scaling kind), and
        # where u0' enters the rows once eliminated (:meth:`step`; None: not eliminable)
        self._layout, self._w_pattern = _layout(n, integrated)
        self.eliminate = self._w_pattern is not None
        #: the compiled road (:mod:`._newton_kernel`): (closures' kernel, rows' kernel, index
        #: plan, closure parameters, row parameters), or None: the numpy road
        parts = _road_parts(n, integrated, model.closures)
        self._fast = (
            None
            if parts is None
            else (
                *parts,
                np.array(model._params, dtype=float),
                np.array([self.sin, self.cos, 1.0 / nu0]),
            )
        )

    def evaluate(self, st: NewtonState, jac=True):
        """Scaled residual R and (if ``jac``) its exact Jacobian J (None otherwise).

        The residual's pieces of the last state are kept: ``evaluate(st, jac=False)`` and
        then ``evaluate(st)`` with the same state object (Newton's line search: the
        Jacobian only of the accepted trial, and only when another step is needed) compute
        the closures and equations once for that state."""
        ctx = self._context(st)
        return ctx["R"].copy(), (self._jacobian_of(ctx) if jac else None)

    def _jacobian_of(self, ctx: dict, g0: np.ndarray | None = None) -> np.ndarray:
        return self._jacobian(ctx, g0) if "out" not in ctx else self._jacobian_compiled(ctx, g0)

    def _context(self, st: NewtonState) -> dict:
        """The residual's pieces of ``st``, kept for the last state evaluated."""
        X = st.pack()
        if self._last is None or not np.array_equal(self._last[0], X):
            self._last = (X, self._residual(st) if self._fast is None else self._residual_compiled(st))
        return self._last[1]

    def _residual_compiled(self, st: NewtonState) -> dict:
        """:meth:`_residual` by the compiled rows (:func:`._newton_kernel.row_kernel`): the
        scaled residual, and the Jacobian's coefficients kept for :meth:`_jacobian`."""
        n, m, L = self.n, self.n + 1, st.L
        assert self._fast is not None  # set when the compiled rows are used
        closures, rows, plan, cparams, rparams = self._fast
        X = np.empty((plan.n_args, m))  # the kernel's arguments: BASE jets, then partials
        self._jets(st, X)
        ptrs = plan.offsets + np.uintp(X.ctypes.data)
        closures.raw(m, ptrs[plan.closure_args], cparams, X[plan.n_base :])
        out = np.empty(plan.n_out + 1)  # the last element: the zero that rows without a term read
        out[-1] = 0.0
        rows.raw(m, ptrs, rparams, out)
        R = out[plan.gather[SLOT["R"]]]
        # the unknowns' own conditions: ν(0) = ν0; free boundary ln ν(y_max) = ln ν_top
        R[0] = st.s[0] - self.ln0
        R[-1] = st.s[n] - self.lntop
        return {"R": R, "L": L, "out": out}

    def _jacobian_compiled(self, ctx: dict, g0: np.ndarray | None = None) -> np.ndarray:
        """:meth:`_jacobian` from the compiled rows' coefficients (the same matrix to
        round-off): each row block's field block is diag(d) + diag(e1) D1 + diag(e2) D2,
        the products only where the equation has such a term (:func:`_row_plan`)."""
        n, m, L = self.n, self.n + 1, ctx["L"]
        assert self._fast is not None
        plan = self._fast[2]
        V = ctx["out"][plan.gather]  # (outputs, rows)
        N = 3 * m + 1
        J = np.zeros((N, N))
        Jf = J.reshape(-1)
        D1, D2 = self.ref.D, self.ref.D2
        per = (0.0, 1.0 / L, 1.0 / L**2)
        for r0, r1, j0, j1, k, c, first in plan.products if g0 is None else plan.products_w:
            e = (V[_SLOTS[k][c], r0:r1] * per[c])[:, None]
            blk = J[r0:r1, k * m : (k + 1) * m]
            M = D1 if c == 1 else D2
            if first:
                np.multiply(M[j0:j1], e, out=blk)
            else:
                blk += M[j0:j1] * e
        for k in (0, 2) if g0 is not None else (0, 1, 2):
            Jf[plan.diagonal[k]] += V[_SLOTS[k][0]][plan.rows]
        if g0 is not None:
            # in (u0(0), w): u0 at node 0 is u0(0) (column m), u0' at node j ≥ 1 is w_j,
            # u0' at node 0 is g0 · (u0(0), w) (see _u_basis)
            J[:, m] += V[_SLOTS[1][0]]
            Jf[plan.diagonal_w] += V[_SLOTS[1][1]][plan.bulk]
            J[plan.floor, m : 2 * m] += V[_SLOTS[1][1]][plan.floor][:, None] * g0
        J[:, -1] = (-1.0 / L) * V[SLOT["Lsum"]]
        J[0, 0] = 1.0
        J[-1, n] = 1.0
        return J

    def _jets(self, st: NewtonState, X: np.ndarray) -> tuple:
        """The base jets of ``st`` (:data:`~chuteflow.equations.BASE`: ν0, u0, T0 and their
        first two y-derivatives, ν0's through ν0 = e^s) into rows 0…8 of ``X``; returns
        (s', s'')."""
        Dx, Dxx = self.ref.D, self.ref.D2  # on y ∈ [0, 1]: y-derivatives are these / L, / L²
        c1 = 1.0 / st.L
        c2 = c1 * c1
        nu = X[0]
        np.exp(st.s, out=nu)
        s1, s2 = (Dx @ st.s) * c1, (Dxx @ st.s) * c2
        np.multiply(nu, s1, out=X[1])
        np.multiply(nu, s2 + s1**2, out=X[2])
        X[3], X[6] = st.u, st.T
        np.multiply(Dx @ st.u, c1, out=X[4])
        np.multiply(Dxx @ st.u, c2, out=X[5])
        np.multiply(Dx @ st.T, c1, out=X[7])
        np.multiply(Dxx @ st.T, c2, out=X[8])
        return s1, s2

    def _residual(self, st: NewtonState) -> dict:
        n, m, L = self.n, self.n + 1, st.L
        X = np.empty((len(BASE), m))
        s1, s2 = self._jets(st, X)
        D1, D2 = self.ref.D / L, self.ref.D2 / L**2
        base = dict(zip(BASE, X))
        nu, u1, u2, T1, T2 = base["nu"], base["u_y"], base["u_yy"], base["T_y"], base["T_yy"]
        part = self.model.evaluate(nu, st.T, compiled=True)
        R = np.empty(3 * m + 1)
        kap = part["kappa"]
        # rows are scaled pointwise (ν-rows by 1/ν, T-rows by 1/κ; x-momentum by the constant
        # 1/ν0(0): (μu0')' carries absolute round-off that 1/ν would amplify at the dilute
        # top). The scale's own derivative is kept so that J is the exact Jacobian.
        scales = {"nu": 1.0 / nu, "u": np.full(m, 1.0 / self.nu0), "T": 1.0 / kap[(0, 0)], "one": np.ones(m)}
        args = arguments(base, part, self.sin, self.cos)  # shared by every equation below
        rows_out = []
        for name, rows, sl, kind in self._layout:
            ce = self.eqs[name]
            res, coefs = ce.evaluate_arguments(args)
            res = _rows(res, sl, m)
            scale = scales[kind][sl]
            R[rows] = scale * res
            rows_out.append((ce, rows, sl, kind, res, coefs, scale))
        # the unknowns' own conditions: ν(0) = ν0; free boundary ln ν(y_max) = ln ν_top
        R[0] = st.s[0] - self.ln0
        R[-1] = st.s[n] - self.lntop
        return {
            "R": R,
            "L": L,
            "D1": D1,
            "D2": D2,
            "nu": nu,
            "s1": s1,
            "s2": s2,
            "jets": {"u": (st.u, u1, u2), "T": (st.T, T1, T2), "nu": (nu, base["nu_y"], base["nu_yy"])},
            "kap": kap,
            "rows": rows_out,
        }

    def _jacobian(self, ctx: dict, g0: np.ndarray | None = None) -> np.ndarray:
        """The exact Jacobian J; with ``g0`` = row 0 of D1 M⁻¹ (:func:`_u_basis`), J T
        instead, T = diag(I, M⁻¹, I, 1): the columns of u0 at the nodes replaced by those of
        (u0(0), u0'(ξ_1…ξ_n)), which is how :meth:`step` eliminates u0' (the equations'
        u0-terms are then those :func:`_u_prime_pattern` allows)."""
        n, m = self.n, self.n + 1
        L, D1, D2, nu, s1, s2 = ctx["L"], ctx["D1"], ctx["D2"], ctx["nu"], ctx["s1"], ctx["s2"]
        jets, kap = ctx["jets"], ctx["kap"]
        N = 3 * m + 1
        J = np.zeros((N, N))
        mats = (None, D1, D2)
        for ce, rows, sl, kind, res, coefs, scale in ctx["rows"]:
            Jr = J[rows]  # view into J: rows of this equation
            dL = np.zeros(len(res))
            idx = np.arange(m)[sl]
            r_idx = np.arange(len(idx))
            # each field's block is diag(d) + diag(e1) D1 + diag(e2) D2 (rows ``sl``), with
            # the row scale folded in; ν-terms through ν = e^s: d(ν_y)/ds = ν (s_y + D1),
            # d(ν_yy)/ds = ν (s_yy + s_y² + D2 + 2 s_y D1)
            acc: dict[int, list] = {}
            nus, s1s, s2s = nu[sl], s1[sl], s2[sl]
            for i, fname, k, c in _steady_terms(ce):
                cf = _rows(coefs[i], sl, m)
                if c:
                    dL += cf * (-c / L) * jets[fname][c][sl]
                if g0 is not None and fname == "u":
                    # in (u0(0), w): u0' at node j ≥ 1 is w_j (D1 M⁻¹ is the identity on rows
                    # 1…n), u0' at node 0 is g0 · (u0(0), w), u0 at node 0 is u0(0)
                    if c == 0:
                        Jr[:, m] += scale * cf
                    elif sl.start >= 1:
                        Jr[r_idx, m + idx] += scale * cf
                    else:
                        Jr[:, m : 2 * m] += (scale * cf)[:, None] * g0
                    continue
                d_e = acc.get(k)
                if d_e is None:
                    d_e = acc[k] = [np.zeros(len(idx)), None, None]
                if fname == "nu":
                    g = cf * nus
                    if c == 0:
                        d_e[0] += g
                    elif c == 1:
                        d_e[0] += g * s1s
                        d_e[1] = g if d_e[1] is None else d_e[1] + g
                    else:
                        d_e[0] += g * (s2s + s1s**2)
                        d_e[2] = g if d_e[2] is None else d_e[2] + g
                        d_e[1] = 2.0 * g * s1s if d_e[1] is None else d_e[1] + 2.0 * g * s1s
                elif c == 0:
                    d_e[0] += cf
                else:
                    d_e[c] = cf if d_e[c] is None else d_e[c] + cf
            for k, (d, e1, e2) in acc.items():
                blk = Jr[:, k * m : (k + 1) * m]
                for e, M in ((e1, mats[1]), (e2, mats[2])):
                    if e is not None:
                        blk += (scale * e)[:, None] * M[sl]
                blk[r_idx, idx] += scale * d
            Jr[:, -1] = scale * dL
            # derivative of the row scale
            if kind == "nu":
                Jr[r_idx, idx] -= res * scale
            elif kind == "T":
                Jr[r_idx, idx] -= res * scale**2 * kap[(1, 0)][sl] * nu[sl]
                Jr[r_idx, 2 * m + idx] -= res * scale**2 * kap[(0, 1)][sl]
        J[0, 0] = 1.0
        J[-1, n] = 1.0
        return J

    def step(self, st: NewtonState, B: np.ndarray) -> np.ndarray:
        """J⁻¹ B for the exact Jacobian J at ``st`` (columns of B: right-hand sides).

        Where the equations allow (:attr:`eliminate`: u0 enters every row only through
        u0', except the floor rows, which may also hold u0(0); the integrated x-momentum
        eq. (3.7) μ u0' = tanθ p is the first such row), the unknowns u0(ξ_j) are replaced
        by (u0(0), w_j = u0'(ξ_j), j = 1…n), u0 = M⁻¹ (u0(0), w) with M = [e_0; D1 rows
        1…n] (:func:`_u_basis`). The x-momentum rows then hold w_j at their own node only
        (a diagonal block), and so do the energy rows; eliminating w leaves a dense system of
        2(n + 1) + 1 instead of 3(n + 1) + 1 unknowns (a third of the LU's work), whose
        Schur complement costs O(n²). Otherwise, a dense LU of J."""
        return self._step(st, B, keep=False)[0]

    def factored_step(self, st: NewtonState, B: np.ndarray) -> tuple[np.ndarray, Any]:
        """(J⁻¹ B, solve) as :meth:`step`, with ``solve(B2)`` = J⁻¹ B2 for the same J from
        its kept LU factors (O(n²) a right-hand side: Newton's chord steps, :meth:`solve`
        with :attr:`chord`). Uses scipy's LU (``lu_factor``, imported here)."""
        return self._step(st, B, keep=True)

    def _step(self, st: NewtonState, B: np.ndarray, keep: bool) -> tuple[np.ndarray, Any]:
        ctx = self._context(st)
        if self._w_pattern is None:
            J = self._jacobian_of(ctx)
            if not keep:
                return np.linalg.solve(J, B), None
            lu = _lu_factor(J)
            return _lu_solve(lu, B), functools.partial(_lu_solve, lu)
        n, m = self.n, self.n + 1
        q, g = _u_basis(n, self.grid_map, ctx["L"])
        JT = self._jacobian_of(ctx, g)
        Mq = _u_basis_ref(n)[0] * q

        def to_u(Y):  # u0 = M⁻¹ (u0(0), w)
            Y[m : 2 * m] = Mq @ Y[m : 2 * m]
            return Y

        # rows of eq. (3.7) at nodes 1…n and the columns of w_j: the block m+1 … 2m−1;
        # the rest (r = 2m + 2 rows and columns) is the block before and the block after
        w, r = slice(m + 1, 2 * m), 2 * m + 2
        a = np.diagonal(JT[w, w]).copy()
        if not (np.all(np.isfinite(a)) and np.all(a != 0)):
            if not keep:
                return to_u(np.linalg.solve(JT, B)), None
            lu = _lu_factor(JT)
            return to_u(_lu_solve(lu, B)), lambda B2: to_u(_lu_solve(lu, B2))
        # (the chord road factorises S in place with LAPACK, :func:`_lu_factor`; the plain
        # road keeps numpy.linalg.solve and its copies, ~10 % of the LU, because the steady
        # command must not import scipy: tests/test_codegen.py::test_warm_steady_skips_typer_and_scipy)
        S = np.empty((r, r))
        S[: m + 1, : m + 1], S[: m + 1, m + 1 :] = JT[: m + 1, : m + 1], JT[: m + 1, 2 * m :]
        S[m + 1 :, : m + 1], S[m + 1 :, m + 1 :] = JT[2 * m :, : m + 1], JT[2 * m :, 2 * m :]
        Z = np.empty((n, r))  # w = b_w/a − Z y
        ai = a[:, None]
        np.divide(JT[w, : m + 1], ai, out=Z[:, : m + 1])
        np.divide(JT[w, 2 * m :], ai, out=Z[:, m + 1 :])

        def rest(i):  # row i of J as a row of S (rows m+1 … 2m−1 are eliminated)
            return i if i <= m else i - n

        # S = A_rr − A_rw Z (and the right-hand side alike), with A_rw's pattern
        diagonal, full = self._w_pattern
        couplings = []  # (rows of S, values of A_rw, rows of Z) of the diagonal blocks
        for rows, j0 in diagonal:
            k = rows.stop - rows.start
            vals = np.diagonal(JT[rows, m + j0 : m + j0 + k]).copy()[:, None]
            rs = slice(rest(rows.start), rest(rows.start) + k)
            zs = slice(j0 - 1, j0 - 1 + k)
            S[rs] -= vals * Z[zs]
            couplings.append((rs, vals, zs))
        dense = [(rest(i), JT[i, w].copy()) for i in full]  # (copies: JT is not kept)
        for ri, row in dense:
            S[ri] -= row @ Z

        def reduce(B):  # (b_w/a, the right-hand side of S)
            bw = B[w] / ai
            rhs = np.empty((r, B.shape[1]))
            rhs[: m + 1], rhs[m + 1 :] = B[: m + 1], B[2 * m :]
            for rs, vals, zs in couplings:
                rhs[rs] -= vals * bw[zs]
            for ri, row in dense:
                rhs[ri] -= row @ bw
            return bw, rhs

        size = len(JT)  # (not JT itself in the closures: a kept LU must not keep J alive)

        def expand(y, bw):
            Y = np.empty((size, y.shape[1]))
            Y[: m + 1], Y[2 * m :] = y[: m + 1], y[m + 1 :]
            Y[w] = bw - Z @ y
            return to_u(Y)

        bw, rhs = reduce(B)
        if not keep:
            return expand(np.linalg.solve(S, rhs), bw), None
        lu = _lu_factor(S)

        def again(B2):
            bw2, rhs2 = reduce(B2)
            return expand(_lu_solve(lu, rhs2), bw2)

        return expand(_lu_solve(lu, rhs), bw), again

    def solve(self, st: NewtonState, tol=1e-10, maxiter=60, y_cap=1e5, lam_min=1e-6, min_iter=0):
        # trial steps may leave the closures' domain (ν > ν_m, T < 0): the NaN/inf they give
        # is handled by the line search, so numpy's warnings about it are noise
        with np.errstate(all="ignore"):
            out = self._solve(st, tol, maxiter, y_cap, lam_min, min_iter)
        out[0].lu = self._latest  # the last LU used (with chord), for a neighbour's solve
        return out

    def _solve(self, st, tol, maxiter, y_cap, lam_min, min_iter):
        """Damped Newton. Converged when the scaled residual is below ``tol``, or when the
        relative Newton step falls below 1e-11 with the residual at its round-off floor.
        Fails when the backtracking step would fall below ``lam_min`` (a continuation
        guess that needs heavy damping is on the wrong side of a fold: fail fast), or when
        :data:`_CRAWL` steps in a row were accepted only at the two smallest step lengths
        allowed (λ < 4 ``lam_min``): each of them lowers the residual by less than
        0.1 λ, a crawl that does not reach Newton's quadratic phase within the iterations
        of a continuation attempt. On the 60 × 60 paper steady map and the diagram's
        steady rows no solve that converged had more than two such steps in a row, while
        ~120 failing continuation attempts crawled on to ``maxiter``.

        The round-off floor of the residual grows like n⁴ (second derivatives near the ends),
        so ``tol`` is raised accordingly above n = 64; the accuracy of a result is checked
        independently by the change between two resolutions (:func:`solve_steady`)."""
        tol = max(tol, 1e-11 * (self.n / 64.0) ** 4)
        hist = []
        crawl = 0  # steps in a row accepted at λ < 4 lam_min
        steps = 0  # corrections taken (Newton and chord)
        # with chord: J⁻¹ B from the last LU (after a full step only, or a neighbour's);
        # the relative distance from the state of that Jacobian, and its dX/dβ
        again = self._latest = self.inherit if self.chord else None
        walked, tangent = math.inf, None
        R, _ = self.evaluate(st, jac=False)
        res = np.abs(R).max()
        for _ in range(maxiter):
            hist.append(res)
            if not np.isfinite(res):
                break
            if res < tol and steps >= min_iter:
                return st, steps, res, hist
            while again is not None:
                # chord step: the last LU (its Jacobian a Newton step or a few back), kept
                # while it lowers the residual at least 1/_CHORD_RATIO times, down to
                # _CHORD_RATIO tol (a full Newton step ends well below tol; stopping just
                # below it would leave Newton's error larger than before) or to the
                # round-off floor (a step below tol that no longer contracts)
                X0 = st.pack()
                dX = -again(R[:, None])[:, 0]
                trial = NewtonState.unpack(self.n, X0 + dX, self.grid_map)
                rt = math.inf
                kept = self._last  # st's residual pieces, for its Jacobian if this step fails
                if (trial.T > 0).all() and 0 < trial.L < y_cap:
                    Rt, _ = self.evaluate(trial, jac=False)
                    rt = np.abs(Rt).max()
                # (a correction that keeps the residual below tol counts for min_iter: the
                # finer rung of a ladder from a neighbour's LU)
                contracts = rt < _CHORD_RATIO * res
                if not (contracts or (steps < min_iter and rt < tol)):
                    again, self._last = None, kept
                    break
                walked += np.abs(dX).max() / max(np.abs(X0).max(), 1.0)
                if self.tangents:
                    if tangent is None:  # a neighbour's LU: its dX/dβ here (approximate)
                        Bb = np.zeros((len(R), 1))
                        Bb[0, 0] = 1.0 / self.nu0
                        tangent = again(Bb)[:, 0]
                    trial.tangents = (tangent, walked)
                st, R, res = trial, Rt, rt
                steps += 1
                hist.append(res)
                if res < tol and steps >= min_iter and (res < _CHORD_RATIO * tol or not contracts):
                    return st, steps, res, hist
            if res < tol and steps >= min_iter:
                return st, steps, res, hist
            # with ``tangents``, dX/dβ as a second right-hand side of the same LU (O(n²)):
            # J dX/dβ = −∂R/∂β, and β = ν0(0) enters only through R[0] = ln ν(0) − ln β
            if self.tangents:
                B = np.zeros((len(R), 2))
                B[:, 0], B[0, 1] = R, 1.0 / self.nu0
            else:
                B = R[:, None].copy()
            try:
                # the Jacobian only now that a step is needed (the residual's pieces of this
                # state are kept by evaluate)
                if self.chord:
                    sol, again = self.factored_step(st, B)
                    self._latest = again
                else:
                    sol = self.step(st, B)
            except (ValueError, np.linalg.LinAlgError):
                break
            dX = -sol[:, 0]
            X0 = st.pack()
            step = np.abs(dX).max() / max(np.abs(X0).max(), 1.0)
            # at large n the residual floor grows like eps·n⁴ (D2 near the ends): accept a
            # stalled residual when the Newton step is at noise level too; the accuracy of
            # the result is checked independently by the change between two resolutions
            stalled = len(hist) > 2 and res > 0.5 * hist[-2] and (res < 1e-7 or (step < 1e-7 and res < 1e-4))
            if ((step < 1e-11 and res < 1e-6) or stalled) and steps >= min_iter:
                if self.tangents:  # this Jacobian was taken at st itself
                    st.tangents = (sol[:, 1].copy(), 0.0)
                return st, steps, res, hist
            lam = 1.0
            while lam >= lam_min:
                trial = NewtonState.unpack(self.n, X0 + lam * dX, self.grid_map)
                if (trial.T > 0).all() and 0 < trial.L < y_cap:
                    Rt, _ = self.evaluate(trial, jac=False)
                    rt = np.abs(Rt).max()
                    better = rt < (1 - 0.1 * lam) * res or (lam == 1.0 and rt < 1e-6)
                    if np.isfinite(rt) and better:
                        if self.tangents:
                            tangent = sol[:, 1].copy()
                            trial.tangents = (tangent, lam * step)
                        st, R, res = trial, Rt, rt
                        steps += 1
                        break
                lam *= 0.5
            else:
                break
            walked = lam * step
            if lam < 1.0:
                again = None  # damped: not yet in Newton's quadratic phase
            crawl = crawl + 1 if lam < 4.0 * lam_min else 0
            if crawl >= _CRAWL:
                break
        else:
            if res < 1e-7 and len(hist) >= min_iter:
                # iterations used up at the round-off floor (residual still creeping down)
                return st, steps, res, hist
        hist.append(res)
        raise _NewtonFailure(st, hist)


@functools.lru_cache(maxsize=32)
def _layout(n: int, integrated: bool) -> tuple[tuple, Any]:
    """The rows of :class:`SteadyNewton` at n: ((equation, rows of the system, nodes it is
    imposed at, row-scaling kind), ...), and :func:`_u_prime_pattern` of them (None where
    u0' is not eliminated)."""
    m = n + 1
    # (equation, rows of the system, nodes it is imposed at, row-scaling kind)
    layout: tuple[tuple[str, slice, slice, str], ...] = (
        ("ymom", slice(1, m), slice(1, m), "nu"),
        ("floor_x", slice(m, m + 1), slice(0, 1), "u"),
        ("floor_energy", slice(2 * m, 2 * m + 1), slice(0, 1), "T"),
        ("energy", slice(2 * m + 1, 2 * m + n), slice(1, n), "T"),
        # T0' = 0 on top (eq. 3.13)
        (TOP_OF["T"], slice(2 * m + n, 2 * m + n + 1), slice(n, n + 1), "one"),
    )
    if integrated:
        # x-momentum in its once-integrated form, eq. (3.7): Σxy = −tanθ Σyy, i.e.
        # μ u0' = tanθ p at nodes 1..n. Integrating the x- and y-momentum balances from
        # y to ∞ with the stresses vanishing at infinity (eq. 2.15) gives it exactly,
        # so the weight of the dilute tail above y_max is kept: the result does not
        # depend on where the domain ends (a stress-free top at y_max instead would make
        # an O(ν_top) error, 1e-7 relative at ν_top = 1e-9). Being first order in u0 it
        # also avoids the D2 round-off (∝ n⁴) of (μ u0')' that otherwise sets the
        # residual floor.
        layout += (("xmom_integrated", slice(m + 1, 2 * m), slice(1, m), "u"),)
    else:
        # second-order form (μ u0')' + ν0 sinθ = 0 inside, u0' = 0 on top: used only for
        # the cold start, where its residual does not favour the collapsed layer (the
        # integrated form's does: every term vanishes with T0)
        layout += (
            ("xmom", slice(m + 1, m + n), slice(1, n), "u"),
            (TOP_OF["u"], slice(m + n, m + n + 1), slice(n, n + 1), "one"),
        )
    return layout, (_u_prime_pattern(layout, compiled_equations()) if integrated else None)


def _u_prime_pattern(layout, eqs):
    """Where u0' enters the steady rows once it is an unknown (:meth:`SteadyNewton.step`):
    (diagonal, full), ``diagonal`` the (rows, first node) of the rows at nodes ≥ 1 other than
    eq. (3.7)'s, each holding u0' at its own node only; ``full`` the rows at the floor,
    holding u0'(0) = g0 · (u0(0), w). None where u0' cannot be eliminated: u0 enters a bulk
    row other than through u0' (Galilean invariance: the bulk equations hold velocity
    differences only; u0(0) appears in the floor rows), or the integrated x-momentum
    eq. (3.7) is not among the rows."""
    if not any(name == "xmom_integrated" for name, *_ in layout):
        return None
    diagonal: list[tuple[slice, int]] = []
    full: list[int] = []
    for name, rows, sl, _ in layout:
        orders = {c for _i, fname, _k, c in _steady_terms(eqs[name]) if fname == "u"}
        node0 = sl == slice(0, 1)
        if not orders <= ({0, 1} if node0 else {1}):
            return None
        if not orders or name == "xmom_integrated":
            continue
        if node0:
            full += list(range(rows.start, rows.stop))
        else:
            diagonal.append((rows, sl.start))
    return diagonal, full


@functools.lru_cache(maxsize=16)
def _u_basis_ref(n: int) -> tuple[np.ndarray, np.ndarray]:
    """M_x⁻¹ and g_x = D_x[0] M_x⁻¹ for the Chebyshev differentiation matrix D_x on
    x ∈ [−1, 1], M_x = [e_0; D_x rows 1…n]: u = M_x⁻¹ (u(x_0), du/dx at x_1…x_n), exactly
    for polynomials of degree n. Any grid of n + 1 nodes y(x_j) (mapped or not) has
    D1 = diag(1/y'(x_j)) D_x, hence M⁻¹ = M_x⁻¹ diag(1, y'(x_1), …): one inverse per n."""
    Dx = reference_nodes(n)[1]
    Minv = np.linalg.inv(np.vstack([np.eye(1, n + 1), Dx[1:]]))
    Minv[0] = np.eye(1, n + 1)[0]  # u(0) = u(0): exact
    g = Dx[0] @ Minv
    Minv.flags.writeable = False
    g.flags.writeable = False
    return Minv, g


def _u_basis(n: int, grid_map, L: float) -> tuple[np.ndarray, np.ndarray]:
    """(q, g0) on [0, L] for M = [e_0; D1 rows 1…n]: M⁻¹ = M_x⁻¹ diag(q) maps (u0(0),
    u0'(y_1…y_n)) to u0 at the nodes, and g0 = D1[0] M⁻¹ gives u0'(0) from them (the other
    rows of D1 M⁻¹ are those of the identity: they are M's own)."""
    Minv_x, g_x = _u_basis_ref(n)
    dydx = L * reference_grid(n, grid_map).jacobian  # y = L ξ(x)
    q = dydx.copy()
    q[0] = 1.0
    return q, g_x * q / dydx[0]


class _RowPlan(NamedTuple):
    """Index arrays of the compiled road of :class:`SteadyNewton` for one layout and n."""

    products: tuple  # (r0, r1, j0, j1, field k, order c, first) of the terms c ≥ 1
    products_w: tuple  # the same without those of u0 (eliminated: SteadyNewton.step)
    n_base: int  # base jets among the kernel's arguments
    n_args: int  # all its arguments (jets and closures' partials)
    n_out: int  # its outputs (layout × OUTPUTS, per node)
    offsets: np.ndarray  # byte offsets of the argument rows (uintp)
    closure_args: np.ndarray  # the rows of ν and T (the closures' arguments)
    gather: np.ndarray  # (OUTPUTS, rows) indices into the outputs (the appended zero: none)
    node: np.ndarray  # the node of each row (0 for the unknowns' own conditions)
    rows: np.ndarray  # rows of equations
    diagonal: tuple  # flat indices of (row, field k's column at the row's node), rows ``rows``
    bulk: np.ndarray  # rows of equations at nodes ≥ 1
    diagonal_w: np.ndarray  # flat indices of (row, w at its node), rows ``bulk``
    floor: np.ndarray  # rows of equations at node 0


@functools.lru_cache(maxsize=16)
def _row_plan(layout_key: tuple, n: int) -> _RowPlan:
    m = n + 1
    N, K = 3 * m + 1, len(OUTPUTS)
    n_base, n_args = len(BASE), len(BASE) + len(FUNCTIONS) * len(ORDERS)
    n_out = len(layout_key) * K * m
    gather = np.full((K, N), n_out, dtype=np.intp)
    node = np.zeros(N, dtype=np.intp)
    has = np.zeros(N, dtype=bool)
    products: list[tuple[int, int, int, int, int, int, bool]] = []
    for r0, r1, j0, j1, orders in layout_key:
        for k, c in orders:
            if c:
                first = not any(p[:2] == (r0, r1) and p[4] == k for p in products)
                products.append((r0, r1, j0, j1, k, c, first))
    products_w = tuple(p for p in products if p[4] != 1)
    for e, (r0, r1, j0, j1, _orders) in enumerate(layout_key):
        r, j = np.arange(r0, r1), np.arange(j0, j1)
        node[r], has[r] = j, True
        for k in range(K):
            gather[k, r] = (e * K + k) * m + j
    rows = np.nonzero(has)[0]
    bulk = np.nonzero(has & (node >= 1))[0]
    floor = np.nonzero(has & (node == 0))[0]
    return _RowPlan(
        tuple(products),
        products_w,
        n_base,
        n_args,
        n_out,
        np.arange(n_args, dtype=np.uintp) * np.uintp(8 * m),
        np.array([BASE.index("nu"), BASE.index("T")]),
        gather,
        node,
        rows,
        tuple(rows * N + k * m + node[rows] for k in range(3)),
        bulk,
        bulk * N + m + node[bulk],
        floor,
    )


def _orders(ce) -> tuple[tuple[int, int], ...]:
    """(field block, derivative order) of the unknowns s = ln ν0, u0, T0 that the rows of
    ``ce`` hold (:mod:`._newton_kernel`: through ν = e^s, d^c ν/dy^c brings s's orders
    0…c)."""
    out = set()
    for _i, fname, k, c in _steady_terms(ce):
        out |= {(k, cc) for cc in range(c + 1)} if fname == "nu" else {(k, c)}
    return tuple(sorted(out))


@functools.lru_cache(maxsize=32)
def _road_parts(n: int, integrated: bool, closures: tuple):
    """(closures' kernel, rows' kernel, plan) of the compiled road of :class:`SteadyNewton`
    for the closure objects ``closures``, or None where compiled kernels are unavailable."""
    from ..closures.model import _compiled_c, vanishing_functions

    layout = _layout(n, integrated)[0]
    rows = row_kernel(tuple((name, kind) for name, _r, _s, kind in layout), vanishing_functions(*closures))
    kernel = _compiled_c(*closures) if rows is not None else None
    if rows is None or kernel is None:
        return None
    eqs = compiled_equations()
    key = tuple((r.start, r.stop, sl.start, sl.stop, _orders(eqs[name])) for name, r, sl, _kind in layout)
    return kernel, rows, _row_plan(key, n)


#: Steps in a row accepted at the two smallest step lengths after which Newton gives up
#: (:meth:`SteadyNewton._solve`).
_CRAWL = 3
#: A chord step (:attr:`SteadyNewton.chord`) is kept when it lowers the residual at least
#: this much (relative); otherwise Newton factorises the Jacobian where it stands.
_CHORD_RATIO = 0.1


@functools.cache
def _lapack() -> tuple:
    # scipy only where chord steps are asked for (not at the steady command's start)
    from scipy.linalg.lapack import dgetrf, dgetrs

    return dgetrf, dgetrs


def _lu_factor(A: np.ndarray) -> tuple:
    """LU factors of the C-ordered ``A`` (overwritten): LAPACK's dgetrf on Aᵀ, which is
    Fortran-ordered as it stands (no copy); :func:`_lu_solve` solves with its transpose."""
    lu, piv, info = _lapack()[0](A.T, overwrite_a=1)
    if info != 0:
        raise np.linalg.LinAlgError("singular Jacobian")
    return lu, piv


def _lu_solve(f: tuple, B: np.ndarray) -> np.ndarray:
    """A⁻¹ B from :func:`_lu_factor`'s factors of A (dgetrs on (Aᵀ)ᵀ)."""
    x, info = _lapack()[1](f[0], f[1], B, trans=1)
    if info != 0:
        raise np.linalg.LinAlgError("bad LU factors")
    return x


class _NewtonFailure(Exception):
    def __init__(self, state, history):
        super().__init__("Newton did not converge")
        self.state, self.history = state, history


_SAME: Any = object()


def _resample(st: NewtonState, n: int, grid_map: Any = _SAME) -> NewtonState:
    """Interpolate a state to n + 1 nodes on the same [0, y_max] (log ν for positivity), on
    the grid ``grid_map`` (default: the state's own)."""
    gm = st.grid_map if grid_map is _SAME else grid_map
    if st.n == n and gm == st.grid_map:
        return NewtonState(n, st.s.copy(), st.u.copy(), st.T.copy(), st.L, gm)
    if gm == st.grid_map:
        # the same map: the new nodes are the Chebyshev nodes of n in the computational
        # variable, whatever the map (one cached interpolation matrix per pair of n)
        v = np.stack([st.s, st.u, st.T]) @ _node_interpolation(st.n, n)
    else:
        v = st.ref.interpolate(np.stack([st.s, st.u, st.T]), reference_grid(n, gm).y)
    return NewtonState(n, v[0].copy(), v[1].copy(), v[2].copy(), st.L, gm)


@functools.lru_cache(maxsize=16)
def _node_interpolation(n_old: int, n_new: int) -> np.ndarray:
    """M with f(x_new) = f(x_old) @ M: the interpolant on the n_old + 1 Chebyshev nodes at
    the n_new + 1 ones (barycentric formula; read-only)."""
    M = barycentric(np.eye(n_old + 1), n_old, reference_nodes(n_new)[0])
    M.flags.writeable = False
    return M


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

    Without ``guess`` the cold start runs Newton on a coarse grid first (n = 32: its
    iterations are a third of the cost) and refines; the result does not depend on it.
    The grid is ``grid_map`` ((ξ_c, ξ_w) or None: plain Chebyshev nodes); by default
    (``"auto"``) the map of :func:`layer_grid_map` for the starting state (cold start or
    ``guess``). ``tangents`` sets the state's :attr:`NewtonState.tangents` (dX/dβ from
    Newton's last Jacobian). ``chord``: Newton reuses its last LU while that contracts
    fast (:attr:`SteadyNewton.chord`; imports scipy.linalg), from the start with
    ``inherit`` (:attr:`SteadyNewton.inherit`: a neighbour's LU at n) if given.
    """
    it0 = 0
    if guess is None:
        guess, it0 = _cold_start(theta, nu0, model, nu_top, n)
    gm = layer_grid_map(guess, theta) if isinstance(grid_map, str) else grid_map
    guess = _resample(guess, n, gm)
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


_COARSE = 32


def _cold_start(theta, nu0, model, nu_top, n, maxiter=30):
    """Isothermal guess polished by Newton (second-order x-momentum form, see
    :meth:`SteadyNewton.evaluate`) on the coarse grid; (state, iterations). If the coarse Newton
    got close (residual < 1e-3) but not below tolerance, the layer may be under-resolved
    and the n grid is tried too. A cold start that converges needs at most ~15 iterations:
    failing after ``maxiter`` (and backtracking at most 10 halvings) keeps the cost of a
    point without a steady flow bounded."""
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


def _diagnose(theta, nu0, model, fail):
    """Turn a failed Newton solve into an error that says which case it is."""
    st = fail.state
    where = (
        f"theta = {theta:g} deg, nu0 = {nu0:g}, roughness = {model.roughness:g}, "
        f"wall_loss = {model.wall_loss:g}"
    )
    if st.L > 2e3:
        return NoSteadyFlowError(
            f"no steady flow at {where}: the density decay length diverges (y_max grew past "
            f"{st.L:.3g} diameters) — the angle is too large for this roughness"
        )
    if st.L < 2.0 or st.T.min() < 1e-3:
        how = (
            f"decay length {st.L:.2g} diameters, below one particle diameter"
            if st.L < 2.0
            else f"the temperature falls to {st.T.min():.2g}: the layer freezes"
        )
        return NoSteadyFlowError(
            f"no steady flow at {where}: the layer collapses ({how}) — the angle is too "
            "small for this roughness, or the floor density too low"
        )
    return ConvergenceError(
        f"steady solver did not converge at {where}: Newton stalled with residual "
        f"{fail.history[-1]:.2e} after {len(fail.history)} iterations"
    )
