"""Steady flows uniform along the slope (paper §3): Chebyshev–Newton on a free top boundary.

For given θ and floor density ν0(0) the unknowns are ln ν0, u0, T0 at the Chebyshev nodes of
[0, y_max] (clustered at the layer's edge by a sinh map,
:func:`~chuteflow.steady.grid.layer_grid_map`) and the height y_max itself, fixed by ν0(y_max)
= ``nu_top`` (paper: 1e-9). The equations are the uniform-state residuals of
:mod:`chuteflow.equations`: y-momentum and energy (eqs 3.5, 3.6) at the inner nodes,
x-momentum in its integrated form eq. (3.7) (μ u0' = tanθ p, the weight of the tail above
y_max included; :func:`chuteflow.equations.first_integrals`), the floor conditions eqs (2.9)
and (2.10) (equivalent to eqs (3.11), (3.12)), T0' = 0 on top (eq. (3.13): the far-field
condition of :func:`chuteflow.equations.far_field_conditions` at k = 0) and ν0(0) given. Every
row and its exact Jacobian come from the compiled equations, so this module states no physics
of its own; Newton converges quadratically.

Unlike the paper's shooting on u0(0), no growing mode is integrated, so there is nothing to
tune by hand. The cold start is an isothermal estimate of the layer (closed form in T),
polished on a coarse grid; continuation (families, maps, the θ fallback of
:func:`~chuteflow.steady.solve_steady`) starts from neighbouring solutions instead.

This module holds the residual and its exact Jacobian (:class:`SteadySystem`); Newton's
iteration is :mod:`chuteflow.steady.newton`, its linear solves :mod:`chuteflow.steady.linear`,
the cold start :mod:`chuteflow.steady.cold_start`.
"""

from __future__ import annotations

import math

import numpy as np

from ..equations import BASE, arguments, compiled_equations
from ._newton_kernel import SLOT
from .grid import reference_grid
from .layout import _SLOTS, _layout, _road_parts, _rows, _steady_terms
from .state import NewtonState


class SteadySystem:
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
        # (equation, rows of the system, nodes it is imposed at, row-scaling kind), and
        # where u0' enters the rows once eliminated (SteadyNewton.step; None: not eliminable)
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
        the products only where the equation has such a term (:func:`~chuteflow.steady.layout._row_plan`)."""
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
        """The exact Jacobian J; with ``g0`` = row 0 of D1 M⁻¹
        (:func:`~chuteflow.steady.linear._u_basis`), J T
        instead, T = diag(I, M⁻¹, I, 1): the columns of u0 at the nodes replaced by those of
        (u0(0), u0'(ξ_1…ξ_n)), which is how :meth:`~chuteflow.steady.newton.SteadyNewton.step`
        eliminates u0' (the equations' u0-terms are then those
        :func:`~chuteflow.steady.layout._u_prime_pattern` allows)."""
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
