"""A Fourier-space preconditioner that couples neighbouring modes: the Jacobian truncated to
the first x-harmonics of its coefficients.

The linearisation of the pointwise rows (:meth:`Discretisation.pointwise_rows`) about an
x-dependent state is δR(x, y) = Σ_jets c(x, y) ∂_x^b ∂_y^c δf with the coefficients c of
:func:`~chuteflow.dns.columns.jet_coefficients` (one-sided differences of the compiled
residual, eqs (2.1)–(2.3) with the floor conditions (2.9), (2.10)). In Fourier modes
m = −M … M it couples mode m to m' through the harmonic ĉ_{m−m'} of the coefficients:

    (J δC)_m = Σ_{m'} Σ_jets ĉ_{m−m'}(y) (i k_{m'})^b D^c δC_{m'},

with the x-derivatives exact in every mode (the transport of ln ν included). The x-mean
preconditioner keeps m' = m only (and the mean state's coefficients); this one keeps
|m − m'| ≤ ``reach`` (a block-banded matrix in the mode index, :func:`coupled_blocks`) and
the per-mode top conditions of u, v, T (eq. (4.5)) exactly. :class:`CoupledPreconditioner`
(reach 1) factorises it by block elimination and is reused across steps;
:func:`coupled_matrix` assembles any reach as one sparse matrix (a reference for the tests,
and the measurement of reach 2). The uniform mass source λ of the mode-0 mass rows is left
out, as in the other preconditioners. docs/dns.md, *Where a nonlinear step's time goes*.
"""

from __future__ import annotations

from dataclasses import InitVar, dataclass, field

import numpy as np
import scipy.sparse as sps

from .columns import PRIMITIVE_JETS, jet_coefficients
from .discretisation import BDF2, UNKNOWNS, Discretisation

__all__ = ["CoupledPreconditioner", "coupled_matrix"]


def coupled_blocks(
    disc: Discretisation, coefficients: dict[str, np.ndarray], ms: np.ndarray, reach: int = 1
) -> np.ndarray:
    """Blocks (len(ms), 2 reach + 1, 4(N+1), 4(N+1)) of the mode-coupled Jacobian: entry
    [i, q + reach] couples row mode ``ms[i]`` to column mode ``ms[i] − q`` (zero where that
    is beyond ±M); ``coefficients`` on the padded grid
    (:func:`~chuteflow.dns.columns.jet_coefficients`). Rows of the top node of u, v, T are the
    per-mode top conditions (eq. (4.5))."""
    mm, M = disc.n + 1, disc.modes
    size = 4 * mm
    g = disc.grid
    dy = (np.eye(mm), g.D, g.D2)
    ms = np.asarray(ms)
    qs = range(-reach, reach + 1)
    blocks = np.zeros((len(ms), len(qs), size, size), dtype=complex)
    for name, f, b, c in PRIMITIVE_JETS:
        A = coefficients[name].copy()
        A[1:, -1] = 0.0  # the top rows of u, v, T are the per-mode conditions below
        if not np.any(A):
            continue
        nxp = A.shape[-1]
        H = np.fft.fft(A, axis=-1) / nxp  # harmonics ĉ_q of the coefficients
        fc = UNKNOWNS.index(f)
        for qi, q in enumerate(qs):
            G = (H[..., q % nxp][:, :, None] * dy[c][None]).reshape(size, mm)
            src = ms - q  # m' = m − q
            fac = np.where(np.abs(src) <= M, (1j * 2.0 * np.pi * src / disc.length) ** b, 0.0)
            blocks[:, qi, :, fc * mm : (fc + 1) * mm] += fac[:, None, None] * G[None]
    kabs = 2.0 * np.pi * np.abs(ms) / disc.length
    for r, f in enumerate(UNKNOWNS[1:], start=1):
        for c, kpow, coef in disc._top_terms[f]:
            blocks[:, reach, r * mm + mm - 1, r * mm : (r + 1) * mm] += (
                coef * kabs[:, None] ** kpow * dy[c][-1][None]
            )
    return blocks


def coupled_matrix(
    disc: Discretisation, coefficients: dict[str, np.ndarray], reach: int = 1
) -> sps.csc_matrix:
    """The complex sparse matrix of the preconditioner (:func:`coupled_blocks` for every mode),
    unknowns ordered (m = −M … M, field, y_j)."""
    M = disc.modes
    nm = 2 * M + 1
    size = 4 * (disc.n + 1)
    blocks = coupled_blocks(disc, coefficients, np.arange(-M, M + 1), reach)
    rows, cols, vals = [], [], []
    for qi, q in enumerate(range(-reach, reach + 1)):
        p, br, bc = np.nonzero(blocks[:, qi])
        pp = p - q
        keep = (pp >= 0) & (pp < nm)
        rows.append(p[keep] * size + br[keep])
        cols.append(pp[keep] * size + bc[keep])
        vals.append(blocks[:, qi][p[keep], br[keep], bc[keep]])
    n = nm * size
    J = sps.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    J.sum_duplicates()
    return J


@dataclass
class CoupledPreconditioner:
    """The mode-coupled Jacobian with ``reach`` = 1, factorised by block elimination;
    :meth:`apply` maps a residual (modes m ≥ 0) to a correction.

    With reach 1 the matrix is block tridiagonal in m. For a real field C_{−m} = conj(C_m),
    so only m = 0 … M are unknowns: row 0 reads D_0 x_0 + 2 Re(U_0 x_1) = r_0 (x_0 real),
    row m ≥ 1 L_m x_{m−1} + D_m x_m + U_m x_{m+1} = r_m. Eliminating from m = M down,
    S_M = D_M, S_m = D_m − U_m S_{m+1}⁻¹ L_{m+1}, S_0 = D_0 − 2 Re(U_0 S_1⁻¹ L_1); stored
    are S_m⁻¹, K_m = S_m⁻¹ L_m and W_m = U_{m−1} S_m⁻¹, so that an application is 3M dense
    products of 4(N+1)-square blocks (the x-mean preconditioner: M + 1).
    """

    disc: Discretisation
    blocks: InitVar[np.ndarray]  # (M + 1, 3, size, size) of coupled_blocks; not kept
    _sinv: list = field(init=False, repr=False)
    _k: list = field(init=False, repr=False)
    _w: list = field(init=False, repr=False)

    def __post_init__(self, blocks):
        B = blocks  # q = −1 (U), 0 (D), +1 (L)
        M = B.shape[0] - 1
        U, D, L = B[:, 0], B[:, 1], B[:, 2]
        sinv: list = [None] * (M + 1)
        k: list = [None] * (M + 1)
        w: list = [None] * (M + 1)
        S = D[M]
        for m in range(M, 0, -1):
            si = np.linalg.inv(S)
            sinv[m] = si
            k[m] = si @ L[m]
            w[m] = U[m - 1] @ si
            S = D[m - 1] - w[m] @ L[m]
        S0 = D[0].real - 2.0 * (w[1] @ L[1]).real if M else D[0].real
        sinv[0] = np.linalg.inv(S0)
        self._sinv, self._k, self._w = sinv, k, w

    @classmethod
    def build(
        cls, disc: Discretisation, C: np.ndarray, history: tuple, dt: float, bdf=BDF2
    ) -> CoupledPreconditioner:
        """Coefficients at the state ``C`` (:func:`~chuteflow.dns.columns.jet_coefficients`),
        blocks of the modes m = 0 … M, elimination."""
        coefs = jet_coefficients(disc, C, history, dt, bdf)
        return cls(disc, coupled_blocks(disc, coefs, np.arange(disc.modes + 1), 1))

    def apply(self, R: np.ndarray) -> np.ndarray:
        """The preconditioned correction (4, N+1, M+1) of the residual ``R``."""
        M = self.disc.modes
        size = 4 * (self.disc.n + 1)
        r = R.reshape(size, M + 1).T  # (M + 1, size)
        rho = r.astype(complex)
        for m in range(M - 1, 0, -1):
            rho[m] -= self._w[m + 1] @ rho[m + 1]
        x = np.empty_like(rho)
        if M:
            x[0] = self._sinv[0] @ (r[0].real - 2.0 * (self._w[1] @ rho[1]).real)
        else:
            x[0] = self._sinv[0] @ r[0].real
        for m in range(1, M + 1):
            x[m] = self._sinv[m] @ rho[m] - self._k[m] @ x[m - 1]
        out = x.T.reshape(R.shape)
        out[..., 0] = out[..., 0].real
        return out
