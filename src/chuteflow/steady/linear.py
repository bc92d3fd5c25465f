"""Newton's linear solves for the steady system: LAPACK's LU, and the elimination of u0'."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..spectral import reference_nodes
from .grid import reference_grid
from .state import NewtonState
from .system import SteadySystem


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


def eliminated_step(
    system: SteadySystem, st: NewtonState, B: np.ndarray, keep: bool
) -> tuple[np.ndarray, Any]:
    """J⁻¹ B for the exact Jacobian J of ``system`` at ``st``, and (with ``keep``) a solve with
    the same LU for further right-hand sides (:meth:`~chuteflow.steady.newton.SteadyNewton.step`
    and :meth:`~chuteflow.steady.newton.SteadyNewton.factored_step` describe both)."""
    ctx = system._context(st)
    if system._w_pattern is None:
        J = system._jacobian_of(ctx)
        if not keep:
            return np.linalg.solve(J, B), None
        lu = _lu_factor(J)
        return _lu_solve(lu, B), functools.partial(_lu_solve, lu)
    n, m = system.n, system.n + 1
    q, g = _u_basis(n, system.grid_map, ctx["L"])
    JT = system._jacobian_of(ctx, g)
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
    diagonal, full = system._w_pattern
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
