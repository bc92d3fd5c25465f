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
* x-derivatives by the second-order periodic central differences on the x_i — each row's
  transport of its own field, a ∂_x f, by first-order upwind differences (``x="upwind"``, the
  default: the central ones' symbol i sin(kh)/h vanishes at the grid's highest modes, where
  the spectral residual's is ik, so the preconditioned transport spread with nx; the upwind
  symbol (1 − e^{−ikh})/h stays within 2/π … 1 of ik in size), y-derivatives
  exact (``y="chebyshev"``, the dense Chebyshev matrices; the stepper's default) or by
  second-order finite differences on the Chebyshev nodes (``y="fd"``:
  :func:`~chuteflow.spectral.fd_matrices`; finite differences precondition collocation
  uniformly in N, Orszag 1980) — the approximations of this preconditioner;
* the per-mode top conditions of u, v, T (eq. (4.5)), |k| by its circulant matrix on the x_i
  restricted to the neighbours the x-differences reach (the whole circulant served no better:
  :func:`column_blocks`).

The matrix is block tridiagonal and periodic in x (blocks 4(N+1) square: dense with the
Chebyshev matrices, banded with the finite differences), factorised once and reused across
steps (docs/dns.md, *Solver*): the dense blocks by the periodic block-tridiagonal LU
(:class:`~chuteflow.dns.cyclic.CyclicBlockLU`: at P5's mapped bore, 129 × 96, 5.5 s where the
general sparse LU took 290 s and 2.2 GB), the banded ones by :func:`scipy.sparse.linalg.splu`.
The uniform mass source λ of the mode-0 mass rows is left out,
as in the per-mode preconditioner.
"""

from __future__ import annotations

from dataclasses import InitVar, dataclass, field

import numpy as np
import scipy.sparse as sps
from scipy.sparse.linalg import splu

from ..errors import ParameterError
from ..spectral import fd_matrices
from .cyclic import CyclicBlockLU
from .discretisation import BDF2, UNKNOWNS, Discretisation

__all__ = [
    "ColumnPreconditioner",
    "PRIMITIVE_JETS",
    "column_blocks",
    "column_coefficients",
    "check_column_order",
    "check_column_x",
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
#: How the column preconditioner differences each row's transport of its own field in x
#: (:func:`column_blocks`). Measured (GMRES iterations a step of the Chebyshev columns, three
#: steps from a checkpoint; ``benchmarks/probes/dns_krylov.py --variants
#: columns_chebyshev,columns_central``): P1 at L = 2000, ±41 … 77 %, 257 × 96, Δt 4:
#: central 84/85/85, upwind 36/37/37 (8.3 → 3.9 s a step); mapped 145 × 96, −46 … +71 %:
#: 72/82/82 → 35/36/37; P5's mapped bore (129 × 96, Δt 8): 41/59/71 → 26/33/41. Half the
#: upwind dissipation served less (44, 40 a step), one and a half times it no better.
X_TRANSPORTS = ("upwind", "central")
#: The time-derivative jets whose coefficients :func:`column_coefficients` adds (the
#: direction the upwind differences dissipate in: :func:`column_blocks`).
TIME_JETS = tuple(f + "_t" for f in UNKNOWNS)
#: How the column preconditioner differentiates in y (:func:`column_blocks`).
Y_DERIVATIVES = ("chebyshev", "fd")
#: How :class:`ColumnPreconditioner` factorises its matrix.
FACTORISATIONS = ("cyclic", "sparse")
#: The largest x grid of the column preconditioner by default
#: (:attr:`~chuteflow.dns.NewtonSettings.columns_nx_limit`), either way of differentiating in
#: y: the factors grow with nx (at N = 96, Chebyshev blocks at P5's mapped bore: 0.66 GB and
#: 5.3 s at nx = 129, 1.28 GB and 8.5 s at 257, peak 2.4 GB; finite differences, a ±20 % wave
#: of P1: 0.78 GB and 12 s at 257, 1.76 GB and 35 s at 513; docs/dns.md, *Solver*).
NX_LIMIT = 257


def _choice(name: str, value, choices: tuple, why: str):
    """``value`` if it is one of ``choices``, else a one-line ParameterError naming ``name``,
    the choices and ``why`` (what the setting is)."""
    if value not in choices:
        raise ParameterError(f"{name} = {value!r}: choose {' or '.join(map(repr, choices))} ({why})")
    return value


def check_column_x(x: str) -> str:
    """``x`` if it is one of :data:`X_TRANSPORTS`, else a one-line ParameterError."""
    return _choice(
        "column_x",
        x,
        X_TRANSPORTS,
        "how the column preconditioner differences each row's transport of its own field in x: "
        "first-order upwind, the default, or central as its other x-differences",
    )


def check_column_order(order: int) -> int:
    """``order`` if it is one of :data:`ORDERS`, else a one-line ParameterError."""
    return _choice("column_order", order, ORDERS, "the order of the column preconditioner's x-differences")


def _at_points(disc: Discretisation, values: np.ndarray) -> np.ndarray:
    """Values on the padded grid → their projection onto m ≤ M at the 2M + 1 points x_i."""
    nx = 2 * disc.modes + 1
    return np.fft.irfft(disc.to_modes(values) * nx, n=nx, axis=-1)


def column_coefficients(
    disc: Discretisation,
    C: np.ndarray,
    history: tuple,
    dt: float,
    bdf=BDF2,
    rel_step: float = 1e-7,
    time: bool = True,
) -> dict[str, np.ndarray]:
    """Coefficients ∂(row)/∂(jet) (4, N+1, 2M+1) of every jet of :data:`PRIMITIVE_JETS`
    (with ``time``, those of :data:`TIME_JETS` too: what ``x="upwind"`` needs).

    One-sided differences of :meth:`Discretisation.pointwise_rows` at the state ``C`` with
    the step ``rel_step`` × max(1, max |jet|); the mass rows are divided by ν̄_j =
    exp(ŝ_0(y_j)) as :meth:`Discretisation.residual` divides their modes. Evaluated on the
    padded grid, then projected onto the modes m ≤ M and taken at the 2M + 1 points x_i.
    """
    padded = jet_coefficients(disc, C, history, dt, bdf, rel_step, time=time)
    return {name: _at_points(disc, A) for name, A in padded.items()}


def jet_coefficients(
    disc: Discretisation,
    C: np.ndarray,
    history: tuple,
    dt: float,
    bdf=BDF2,
    rel_step: float = 1e-7,
    time: bool = False,
) -> dict[str, np.ndarray]:
    """The coefficients of :func:`column_coefficients` on the padded grid (4, N+1, nxp); with
    ``time``, also those of the time derivatives ∂_t s, ∂_t u, ∂_t v, ∂_t T (:data:`TIME_JETS`),
    from the history they are formed of (the BDF weight of the last level, ``bdf[1]``/Δt)."""
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
    if time:
        h0 = np.array(history[0])  # (nu, u, v, T) at the last level
        for i, f in enumerate(UNKNOWNS):
            h = rel_step * max(1.0, float(np.max(np.abs(h0[i]))))
            pert_h = h0.copy()
            pert_h[i] = h0[i] + h
            R1 = disc.pointwise_rows(disc.state_jets(prim), (pert_h, *history[1:]), dt, bdf, inflow)
            A = (R1 - R0) * (dt / (bdf[1] * h))
            if i == 0:
                A = A * np.exp(prim["s"])  # ∂_t ν = ν ∂_t s
            A[0, 1 : last + 1] /= nubar[1 : last + 1, None]
            out[f + "_t"] = A
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
    for A in out.values():  # (the time jets too, where present)
        A[0, 1 : last + 1] *= gp


def check_column_y(y: str) -> str:
    """``y`` if it names a way of :func:`y_matrices`, else a one-line ParameterError."""
    return _choice(
        "column_y",
        y,
        Y_DERIVATIVES,
        "the column preconditioner's y-derivatives: exact, a dense block per x point, or finite "
        "differences, a sparse LU",
    )


def y_matrices(disc: Discretisation, y: str = "chebyshev") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(1, d/dy, d²/dy²) on the Chebyshev nodes of ``disc``: the grid's Chebyshev matrices
    (``y="chebyshev"``) or second-order finite differences (``"fd"``,
    :func:`~chuteflow.spectral.fd_matrices`)."""
    check_column_y(y)
    g = disc.grid
    D, D2 = fd_matrices(g.y) if y == "fd" else (g.D, g.D2)
    return np.eye(disc.n + 1), D, D2


def column_blocks(
    disc: Discretisation,
    coefficients: dict[str, np.ndarray],
    order: int = 2,
    y: str = "chebyshev",
    x: str = "upwind",
) -> dict[int, np.ndarray]:
    """The blocks of the preconditioner's matrix by x-offset: ``blocks[o][i]`` (4(N+1) square,
    unknowns (field, y_j)) couples the point x_i to x_{i+o} (indices modulo 2M + 1), o = −1, 0, 1
    for ``order`` 2 (and −2 … 2 for 4).

    ``coefficients`` as from :func:`column_coefficients`; x-differences of ``order`` 2 or 4,
    y-derivatives by :func:`y_matrices` (``y``). Rows of the top node of u, v, T are the
    per-mode top conditions, |k| (on a mapped grid (1/g') |∂_s|) as its circulant on the x_i
    restricted to the offsets the x-differences reach: at P5's mapped bore (129 × 96, Δt 8)
    the fd-y columns took 145, 156, 156 GMRES iterations with the whole circulant and with its
    nearest neighbours alone (docs/dns.md, *Solver*), so the matrix keeps the block structure.

    With ``x="upwind"`` (:data:`X_TRANSPORTS`) each row's transport of its own field, a ∂_x f
    (a the row's coefficient of its field's x-jet), is differenced upwind: the central
    difference plus the dissipation |a| h/2 ∂_xx with the sign of the row's coefficient of
    ∂_t f (``coefficients[f + "_t"]``, :data:`TIME_JETS`; none where the row has no time
    derivative: the wall's and the top's conditions), i.e. (f_i − f_{i∓1})/h from the side
    the transport comes from. Upwind differences are first-order: they enter the
    preconditioner, never the residual.
    """
    check_column_x(x)
    m, nx = disc.n + 1, 2 * disc.modes + 1
    hx = disc.length / nx
    dy = y_matrices(disc, y)
    stencil = _STENCIL if order == 2 else _STENCIL4
    reach = 1 if order == 2 or nx < 5 else 2
    if reach == 1:
        stencil = _STENCIL
    blocks = {o: np.zeros((nx, 4 * m, 4 * m)) for o in range(-reach, reach + 1)}
    # the jets' coefficients summed by (offset, field, y-order): W[r, j, i] (4, m, nx)
    summed: dict[tuple[int, int, int], np.ndarray] = {}
    for name, f, b, c in PRIMITIVE_JETS:
        A = coefficients[name].copy()  # (4, m, nx)
        A[1:, -1] = 0.0  # the top rows of u, v, T are the per-mode conditions below
        if not np.any(A):
            continue
        for o, w in stencil[b]:
            key = (o, UNKNOWNS.index(f), c)
            summed[key] = summed.get(key, 0.0) + A * (w / hx**b)
    j = np.arange(m)
    for (o, fc, c), W in summed.items():
        cols = slice(fc * m, (fc + 1) * m)
        for r in range(4):
            if not np.any(W[r]):
                continue
            rows = slice(r * m, (r + 1) * m)
            if c == 0:
                # block[i][(r, j), (fc, j)] += W[r, j, i]: the identity in y
                blocks[o][:, r * m + j, fc * m + j] += W[r].T
            else:
                # block[i][(r, j), (fc, j')] += W[r, j, i] · dy[c][j, j']
                blocks[o][:, rows, cols] += W[r].T[:, :, None] * dy[c][None]
    if x == "upwind":
        _upwind_transport(blocks, coefficients, m, hx)
    # top conditions of u, v, T: Σ coef |k|^p (D^c f)(y_max), |k|^p by its circulant h_{i − i'}
    kabs = np.abs(disc.k)
    a_pts = np.ones(nx) if disc.x_map is None else 1.0 / disc.x_map.dx_ds(np.arange(nx) * hx)
    for r, f in enumerate(UNKNOWNS[1:], start=1):
        top = r * m + m - 1
        for c, kpow, coef in disc._top_terms[f]:
            dtop = dy[c][-1]
            if kpow == 0:
                blocks[0][:, top, r * m : (r + 1) * m] += coef * dtop
                continue
            circ = np.fft.irfft(kabs**kpow, n=nx)
            for o in blocks:
                blocks[o][:, top, r * m : (r + 1) * m] += (coef * a_pts * circ[-o % nx])[:, None] * dtop
    return blocks


def _upwind_transport(blocks: dict[int, np.ndarray], coefficients: dict[str, np.ndarray], m: int, hx: float):
    """Add to the central blocks the dissipation that makes each row's transport of its own
    field first-order upwind (:func:`column_blocks`, ``x="upwind"``)."""
    missing = [f + "_t" for f in UNKNOWNS if f + "_t" not in coefficients]
    if missing:
        raise ParameterError(
            f"column_blocks(x='upwind') needs the coefficients of {', '.join(missing)} "
            "(column_coefficients gives them), or x='central'"
        )
    for r, f in enumerate(UNKNOWNS):
        a = coefficients[f + "_x"][r].copy()  # (m, nx)
        tau = coefficients[f + "_t"][r]
        if r > 0:
            a[-1] = 0.0  # the top rows of u, v, T are the per-mode conditions
        big = float(np.max(np.abs(tau)))
        side = np.where(np.abs(tau) > 1e-8 * big, np.sign(tau), 0.0)
        diss = side * np.abs(a) / (2.0 * hx)  # (m, nx)
        idx = np.arange(r * m, (r + 1) * m)
        for o, w in ((-1, -1.0), (0, 2.0), (1, -1.0)):
            blocks[o][:, idx, idx] += (w * diss).T


def column_matrix(disc: Discretisation, coefficients: dict[str, np.ndarray], *args, **kw) -> sps.csc_matrix:
    """The sparse matrix of the preconditioner, unknowns ordered (x_i, field, y_j): the blocks
    of :func:`column_blocks` (the same arguments: ``order``, ``y``, ``x``) assembled."""
    return _assemble(column_blocks(disc, coefficients, *args, **kw))


def _assemble(blocks: dict[int, np.ndarray]) -> sps.csc_matrix:
    nx, size, _ = blocks[0].shape
    rows, cols, vals = [], [], []
    for o, blk in blocks.items():
        bi, br, bc = np.nonzero(blk)
        rows.append(bi * size + br)
        cols.append(((bi + o) % nx) * size + bc)
        vals.append(blk[bi, br, bc])
    n_tot = size * nx
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
    blocks : dict of int to ndarray
        The blocks by x-offset (:func:`column_blocks`; an init-only argument: the factors
        alone are kept).
    factorisation : {"cyclic", "sparse"}
        ``"cyclic"``: the periodic block-tridiagonal LU
        (:class:`~chuteflow.dns.cyclic.CyclicBlockLU`; three blocks per point, i.e.
        second-order x-differences); ``"sparse"``: the sparse LU of the assembled matrix
        (``scipy.sparse.linalg.splu``, COLAMD). :meth:`build` takes the first for dense
        blocks (exact Chebyshev y-derivatives; at P5's mapped bore, 129 × 96: 5.5 s and
        0.6 GB where ``splu`` took 290 s and 2.2 GB) and the second for the banded blocks of
        the finite differences (there ``splu``'s solve reads less: 44 against 58 ms per GMRES
        iteration on the same state; docs/dns.md, *Solver*).
    """

    disc: Discretisation
    blocks: InitVar[dict[int, np.ndarray]]
    factorisation: str = "sparse"
    _lu: object = field(init=False, repr=False)
    _matrix_bytes: int = field(init=False, repr=False, default=0)

    def __post_init__(self, blocks: dict[int, np.ndarray]):
        _choice("factorisation", self.factorisation, FACTORISATIONS, "block-tridiagonal or general sparse LU")
        if self.factorisation == "cyclic":
            if set(blocks) != {-1, 0, 1}:
                raise ParameterError(
                    "factorisation = 'cyclic' needs three blocks per point (second-order x-differences, "
                    "column_order = 2)"
                )
            self._lu = CyclicBlockLU(blocks[0], blocks[-1], blocks[1])
        else:
            matrix = _assemble(blocks)
            self._matrix_bytes = int(matrix.data.nbytes + matrix.indices.nbytes)
            self._lu = splu(matrix, permc_spec="COLAMD")

    @classmethod
    def build(
        cls,
        disc: Discretisation,
        C: np.ndarray,
        history: tuple,
        dt: float,
        bdf=BDF2,
        order: int = 2,
        y: str = "chebyshev",
        x: str = "upwind",
    ) -> ColumnPreconditioner:
        """Coefficients at the state ``C`` (:func:`column_coefficients`), blocks (x-differences
        of ``order`` 2 or 4, each row's own transport by ``x``, y-derivatives by ``y``:
        :func:`column_blocks`), factorisation (``"cyclic"`` for the dense blocks of
        ``y="chebyshev"`` at ``order`` 2, else ``"sparse"``)."""
        coefficients = column_coefficients(disc, C, history, dt, bdf, time=x == "upwind")
        blocks = column_blocks(disc, coefficients, order, y, x)
        return cls(disc, blocks, "cyclic" if order == 2 and y == "chebyshev" else "sparse")

    @property
    def nbytes(self) -> int:
        """Memory of the factors (bytes)."""
        lu = self._lu
        if isinstance(lu, CyclicBlockLU):
            return lu.nbytes
        return self._matrix_bytes + 12 * int(lu.L.nnz + lu.U.nnz)  # type: ignore[attr-defined]

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
