"""A physical-space preconditioner for the nonlinear phase: the Jacobian of each x-column.

At finite amplitude the coefficients of the Jacobian vary along the wave by orders of
magnitude (at a fixed height in the dilute top ν, and with it the diffusivities ∝ T^{1/2}/ν,
change by decades between crest and trough), which the per-mode linearisation about the
x-averaged state (:meth:`Discretisation.linear_blocks`) cannot describe. This preconditioner
keeps the local state instead: on the 2M + 1 collocation points x_i of the unknowns it is the
Jacobian of the pointwise rows (:meth:`Discretisation.pointwise_rows`) with

* the coefficient of every jet ∂_x^b ∂_y^c of s = ln ν, u, v, T at every point, as the
  derivative of the compiled residual (:mod:`chuteflow.dns.residual`, derived from
  :func:`chuteflow.equations.governing_equations`) with respect to that jet — one-sided
  differences, so nothing of the physics is restated here — projected onto the modes m ≤ M
  and evaluated at the x_i;
* x-derivatives by the second-order periodic central differences on the x_i, y-derivatives
  by second-order finite differences on the Chebyshev nodes (``y="fd"``, the default:
  :func:`~chuteflow.spectral.fd_matrices`; finite differences precondition collocation
  uniformly in N, Orszag 1980) or exact (``y="chebyshev"``, the dense Chebyshev matrices) —
  the approximations of this preconditioner;
* the per-mode top conditions of u, v, T (eq. (4.5)) exact: |k| as the circulant matrix of
  its symbol on the x_i.

The matrix is block tridiagonal and periodic in x (blocks 4(N+1) square: dense with the
Chebyshev matrices, banded with the finite differences) plus the coupling of the top nodes by
|k|; it is factorised once by :func:`scipy.sparse.linalg.splu` and reused across steps
(docs/dns.md, *Solver*). With the finite differences in y its LU is 3.5 times smaller and
seven to ten times faster to build at P1, L = 2000 (nx = 97, N = 64), for 1.5 times the GMRES
iterations: 1.8–2.1 times less wall time per unit of simulated time at ±80 % (docs/dns.md,
*Finite differences in y*). The uniform mass source λ of the mode-0 mass rows is left out,
as in the per-mode preconditioner.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps
from scipy.sparse.linalg import splu

from ..errors import ParameterError
from ..spectral import fd_matrices
from .discretisation import BDF2, UNKNOWNS, Discretisation

__all__ = [
    "ColumnPreconditioner",
    "PRIMITIVE_JETS",
    "column_coefficients",
    "check_column_order",
    "check_column_y",
    "column_matrix",
    "jet_coefficients",
    "y_matrices",
]

#: The jets of s, u, v, T the pointwise rows depend on, with their orders (b in x, c in y).
PRIMITIVE_JETS = tuple(
    (f + sfx, f, b, c)
    for f in UNKNOWNS
    for sfx, b, c in (("", 0, 0), ("_x", 1, 0), ("_y", 0, 1), ("_xx", 2, 0), ("_xy", 1, 1), ("_yy", 0, 2))
)
#: Central differences on a periodic grid of spacing h: order b → ((offset, weight × h^b), …).
_STENCIL = {0: ((0, 1.0),), 1: ((-1, -0.5), (1, 0.5)), 2: ((-1, 1.0), (0, -2.0), (1, 1.0))}
#: Fourth-order central differences (``order=4``): the symbol of ∂_x is (8 sin kh − sin 2kh)/6h,
#: closer to k over the middle third of the modes (docs/dns.md, *Solver*).
_STENCIL4 = {
    0: ((0, 1.0),),
    1: ((-2, 1 / 12), (-1, -8 / 12), (1, 8 / 12), (2, -1 / 12)),
    2: ((-2, -1 / 12), (-1, 16 / 12), (0, -30 / 12), (1, 16 / 12), (2, -1 / 12)),
}
#: Orders of the x-differences of the column preconditioner.
ORDERS = (2, 4)
#: How the column preconditioner differentiates in y (:func:`column_matrix`).
Y_DERIVATIVES = ("fd", "chebyshev")
#: The largest x grid of the column preconditioner by default, per way of differentiating
#: in y (:attr:`~chuteflow.dns.NewtonSettings.columns_nx_limit`): beyond it the sparse LU
#: fills in. Measured at P1, L = 2000, N = 64: with "fd" nx = 257 costs 0.48 GB of factors
#: and 5.7 s to build (513: 1.15 GB, 20 s); with "chebyshev" nx = 129 costs 0.75 GB and
#: 16 s, nx = 257 more than 4.9 GB and 15 min (docs/dns.md, *Finite differences in y*).
NX_LIMIT = {"fd": 257, "chebyshev": 129}


def check_column_order(order: int) -> int:
    """``order`` if it is one of :data:`ORDERS`, else a one-line ParameterError."""
    if order not in ORDERS:
        raise ParameterError(
            f"column_order = {order!r}: choose {' or '.join(map(str, ORDERS))} "
            "(the order of the x-differences of the column preconditioner)"
        )
    return order


def _at_points(disc: Discretisation, values: np.ndarray) -> np.ndarray:
    """Values on the padded grid → their projection onto m ≤ M at the 2M + 1 points x_i."""
    nx = 2 * disc.modes + 1
    return np.fft.irfft(disc.to_modes(values) * nx, n=nx, axis=-1)


def column_coefficients(
    disc: Discretisation, C: np.ndarray, history: tuple, dt: float, bdf=BDF2, rel_step: float = 1e-7
) -> dict[str, np.ndarray]:
    """Coefficients ∂(row)/∂(jet) (4, N+1, 2M+1) of every jet of :data:`PRIMITIVE_JETS`.

    One-sided differences of :meth:`Discretisation.pointwise_rows` at the state ``C`` with
    the step ``rel_step`` × max(1, max |jet|); the mass rows are divided by ν̄_j =
    exp(ŝ_0(y_j)) as :meth:`Discretisation.residual` divides their modes. Evaluated on the
    padded grid, then projected onto the modes m ≤ M and taken at the 2M + 1 points x_i.
    """
    padded = jet_coefficients(disc, C, history, dt, bdf, rel_step)
    return {name: _at_points(disc, A) for name, A in padded.items()}


def jet_coefficients(
    disc: Discretisation, C: np.ndarray, history: tuple, dt: float, bdf=BDF2, rel_step: float = 1e-7
) -> dict[str, np.ndarray]:
    """The coefficients of :func:`column_coefficients` on the padded grid (4, N+1, nxp)."""
    prim = disc.primitive_jets(C)
    inflow = ~(prim["v"][-1] > 0)  # the upwind choice at the top, kept while differentiating
    R0 = disc.pointwise_rows(disc.state_jets(prim), history, dt, bdf, inflow)
    nubar = disc.mass_scale(C)
    last = disc.n if disc.top == "transport" else disc.n - 1
    out = {}
    for name, *_ in PRIMITIVE_JETS:
        base = prim[name]
        h = rel_step * max(1.0, float(np.max(np.abs(base))))
        pert = dict(prim)
        pert[name] = base + h
        A = (disc.pointwise_rows(disc.state_jets(pert), history, dt, bdf, inflow) - R0) / h
        A[0, 1 : last + 1] /= nubar[1 : last + 1, None]
        out[name] = A
    if disc.x_map is not None:
        _to_s_jets(disc, out, last)
    return out


def _to_s_jets(disc: Discretisation, out: dict[str, np.ndarray], last: int) -> None:
    """On a mapped grid (:mod:`chuteflow.dns.xmap`): the coefficients of the x-jets → those of
    the s-jets the unknowns are differentiated by (f_x = a f_s, f_xx = a² f_ss + b f_s,
    f_xy = a f_sy: :meth:`Discretisation.map_metric`), and the mass rows times g' as
    :meth:`Discretisation.residual` weights them. The names stay ``"s_x"``, … (b = 1 is then
    ∂_s)."""
    a, b = disc.map_metric
    gp = disc.x_weights
    for f in UNKNOWNS:
        ax, axx, axy = out[f + "_x"], out[f + "_xx"], out[f + "_xy"]
        out[f + "_x"] = a * ax + b * axx
        out[f + "_xx"] = a * a * axx
        out[f + "_xy"] = a * axy
    for A in out.values():
        A[0, 1 : last + 1] *= gp


def check_column_y(y: str) -> str:
    """``y`` if it names a way of :func:`y_matrices`, else a one-line ParameterError."""
    if y not in Y_DERIVATIVES:
        raise ParameterError(
            f"column_y = {y!r}: choose 'fd' (finite differences in y, a sparse LU) or 'chebyshev' "
            "(the exact y-derivatives, a dense block per x point) for the column preconditioner"
        )
    return y


def y_matrices(disc: Discretisation, y: str = "fd") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(1, d/dy, d²/dy²) on the Chebyshev nodes of ``disc``: second-order finite differences
    (``y="fd"``, :func:`~chuteflow.spectral.fd_matrices`) or the grid's Chebyshev matrices
    (``"chebyshev"``)."""
    check_column_y(y)
    g = disc.grid
    D, D2 = fd_matrices(g.y) if y == "fd" else (g.D, g.D2)
    return np.eye(disc.n + 1), D, D2


def column_matrix(
    disc: Discretisation, coefficients: dict[str, np.ndarray], order: int = 2, y: str = "fd"
) -> sps.csc_matrix:
    """The sparse matrix of the preconditioner, unknowns ordered (x_i, field, y_j).

    ``coefficients`` as from :func:`column_coefficients`; x-differences of ``order`` 2 or 4,
    y-derivatives by :func:`y_matrices` (``y``). Rows of the top node of u, v, T are the
    per-mode top conditions (with |k| as a circulant matrix on the x_i).
    """
    m, nx = disc.n + 1, 2 * disc.modes + 1
    hx = disc.length / nx
    dy = y_matrices(disc, y)
    stencil = _STENCIL if order == 2 else _STENCIL4
    reach = 1 if order == 2 or nx < 5 else 2
    if reach == 1:
        stencil = _STENCIL
    blocks = {o: np.zeros((nx, 4 * m, 4 * m)) for o in range(-reach, reach + 1)}
    for name, f, b, c in PRIMITIVE_JETS:
        A = coefficients[name].copy()  # (4, m, nx)
        A[1:, -1] = 0.0  # the top rows of u, v, T are the per-mode conditions below
        if not np.any(A):
            continue
        fc = UNKNOWNS.index(f)
        for o, w in stencil[b]:
            W = A * (w / hx**b)  # (4, m, nx)
            # block[i][(r, j), (fc, j')] += W[r, j, i] · dy[c][j, j']
            blk = W.transpose(2, 0, 1)[..., None] * dy[c][None, None]  # (nx, 4, m, m)
            blocks[o][:, :, fc * m : (fc + 1) * m] += blk.reshape(nx, 4 * m, m)
    # top conditions of u, v, T: Σ coef |k|^p (D^c f)(y_max), |k|^p the circulant of its symbol
    # (on a mapped grid (1/g') |∂_s|: Discretisation.abs_dx)
    kabs = np.abs(disc.k)
    a_pts = np.ones(nx) if disc.x_map is None else 1.0 / disc.x_map.dx_ds(np.arange(nx) * hx)
    rows, cols, vals = [], [], []
    for r, f in enumerate(UNKNOWNS[1:], start=1):
        for c, kpow, coef in disc._top_terms[f]:
            dtop = dy[c][-1]
            if kpow == 0:
                blocks[0][:, r * m + m - 1, r * m : (r + 1) * m] += coef * dtop
                continue
            circ = np.fft.irfft(kabs**kpow, n=nx)  # h_{i − i'}
            H = circ[(np.arange(nx)[:, None] - np.arange(nx)[None, :]) % nx]
            ii, kk, jj = np.nonzero(np.ones((nx, nx, m)) * (dtop != 0)[None, None])
            rows.append((ii * 4 + r) * m + m - 1)
            cols.append((kk * 4 + r) * m + jj)
            vals.append(coef * a_pts[ii] * H[ii, kk] * dtop[jj])
    n_tot = 4 * m * nx
    size = 4 * m
    for o, blk in blocks.items():
        bi, br, bc = np.nonzero(blk)
        rows.append(bi * size + br)
        cols.append(((bi + o) % nx) * size + bc)
        vals.append(blk[bi, br, bc])
    J = sps.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_tot, n_tot)
    )
    J.sum_duplicates()
    J.eliminate_zeros()
    return sps.csc_matrix(J)


@dataclass
class ColumnPreconditioner:
    """The factorised column Jacobian; :meth:`apply` maps a residual (modes) to a correction.

    Attributes
    ----------
    disc : Discretisation
        Grid and equations.
    matrix : scipy.sparse.csc_matrix
        The assembled matrix (:func:`column_matrix`).
    """

    disc: Discretisation
    matrix: sps.csc_matrix
    _lu: object = field(init=False, repr=False)

    def __post_init__(self):
        self._lu = splu(self.matrix, permc_spec="COLAMD")

    @classmethod
    def build(
        cls,
        disc: Discretisation,
        C: np.ndarray,
        history: tuple,
        dt: float,
        bdf=BDF2,
        order: int = 2,
        y: str = "fd",
    ) -> ColumnPreconditioner:
        """Coefficients at the state ``C`` (:func:`column_coefficients`), matrix (x-differences
        of ``order`` 2 or 4, y-derivatives by ``y``: :func:`y_matrices`), factorisation."""
        return cls(disc, column_matrix(disc, column_coefficients(disc, C, history, dt, bdf), order, y))

    @property
    def nbytes(self) -> int:
        """Memory of the matrix and its LU factors (bytes)."""
        lu = self._lu
        return int(
            self.matrix.data.nbytes + self.matrix.indices.nbytes + 12 * (lu.L.nnz + lu.U.nnz)  # type: ignore[attr-defined]
        )

    def to_points(self, R: np.ndarray) -> np.ndarray:
        """Coefficients (4, N+1, M+1) → vector of values at (x_i, field, y_j)."""
        nx = 2 * self.disc.modes + 1
        v = np.fft.irfft(R * nx, n=nx, axis=-1)
        return np.ascontiguousarray(v.transpose(2, 0, 1)).ravel()

    def to_modes(self, z: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`to_points`."""
        d = self.disc
        nx = 2 * d.modes + 1
        f = z.reshape(nx, 4, d.n + 1).transpose(1, 2, 0)
        out = np.fft.rfft(f, axis=-1) / nx
        out[..., 0] = out[..., 0].real
        return out

    def apply(self, R: np.ndarray) -> np.ndarray:
        """The preconditioned correction: modes of matrix⁻¹ (R at the points x_i)."""
        return self.to_modes(self._lu.solve(self.to_points(R)))  # type: ignore[attr-defined]
