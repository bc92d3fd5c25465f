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

__all__ = ["CoupledPreconditioner", "coupled_blocks", "coupled_matrix", "coupling_factors"]


def coupling_factors(
    disc: Discretisation, coefficients: dict[str, np.ndarray], ms: np.ndarray, reach: int = 1
) -> np.ndarray:
    """The mode-coupled Jacobian in factored form: E (len(ms), 2 reach + 1, 4 fields,
    3 y-orders, 4 equations, N+1) with

        block [i, q + reach] = Σ_{f, c} diag(E[i, q + reach, f, c]) D^c   (columns of field f),

    i.e. Σ over the jets of field f with y-order c of the harmonic ĉ_q(y) of their
    coefficients times (i k_{m'})^b, m' = ``ms[i]`` − q (zero beyond ±M); ``coefficients``
    on the padded grid (:func:`~chuteflow.dns.columns.jet_coefficients`). The top rows of
    u, v, T hold only, on a mapped grid, the off-diagonal part of their (1/g')|∂_s| terms
    (:func:`coupled_blocks` puts the per-mode conditions in the diagonal blocks)."""
    mm, M = disc.n + 1, disc.modes
    ms = np.asarray(ms)
    qs = range(-reach, reach + 1)
    E = np.zeros((len(ms), len(qs), 4, 3, 4, mm), dtype=complex)
    for name, f, b, c in PRIMITIVE_JETS:
        A = coefficients[name].copy()
        A[1:, -1] = 0.0  # the top rows of u, v, T are the per-mode conditions
        if not np.any(A):
            continue
        nxp = A.shape[-1]
        H = np.fft.fft(A, axis=-1) / nxp  # harmonics ĉ_q of the coefficients
        fc = UNKNOWNS.index(f)
        for qi, q in enumerate(qs):
            src = ms - q  # m' = m − q
            fac = np.where(np.abs(src) <= M, (1j * 2.0 * np.pi * src / disc.length) ** b, 0.0)
            E[:, qi, fc, c] += fac[:, None, None] * H[..., q % nxp][None]
    if disc.x_map is not None:
        # the top conditions' |∂_x| = (1/g')|∂_s| (eq. (4.5)): row mode m, column mode m − q
        # through the harmonic â_q of 1/g' — a first harmonic of s for the tan map, so the
        # blocks q = ±1 hold it exactly (q = 0, its mean: the diagonal blocks, _dense)
        nxp = disc.nxp
        ahat = np.fft.fft(disc.map_metric[0]) / nxp
        for qi, q in enumerate(qs):
            if q == 0:
                continue
            src = ms - q
            kab = np.where(np.abs(src) <= M, 2.0 * np.pi * np.abs(src) / disc.length, 0.0)
            for r, f in enumerate(UNKNOWNS[1:], start=1):
                for c, kpow, coef in disc._top_terms[f]:
                    if kpow == 1:
                        E[:, qi, r, c, r, -1] += coef * ahat[q % nxp] * kab
    return E


def coupled_blocks(
    disc: Discretisation, coefficients: dict[str, np.ndarray], ms: np.ndarray, reach: int = 1
) -> np.ndarray:
    """Blocks (len(ms), 2 reach + 1, 4(N+1), 4(N+1)) of the mode-coupled Jacobian: entry
    [i, q + reach] couples row mode ``ms[i]`` to column mode ``ms[i] − q`` (zero where that
    is beyond ±M); the dense form of :func:`coupling_factors`. Rows of the top node of u, v,
    T are the per-mode top conditions (eq. (4.5))."""
    return _blocks_of(disc, coupling_factors(disc, coefficients, ms, reach), np.asarray(ms), reach)


def _blocks_of(disc: Discretisation, E: np.ndarray, ms: np.ndarray, reach: int) -> np.ndarray:
    """The dense blocks of the factors ``E`` (:func:`coupling_factors`) with the per-mode
    top conditions of u, v, T in the diagonal blocks."""
    size = 4 * (disc.n + 1)
    blocks = np.empty((len(ms), 2 * reach + 1, size, size), dtype=complex)
    for i, m in enumerate(ms):
        for qi in range(2 * reach + 1):
            blocks[i, qi] = _dense(disc, E[i, qi], m if qi == reach else None)
    return blocks


def _dense(disc: Discretisation, E: np.ndarray, m: int | None = None) -> np.ndarray:
    """One dense block 4(N+1)-square of its factors ``E`` (4 fields, 3 y-orders, 4 equations,
    N+1): block[(r, j), (f, l)] = Σ_c E[f, c, r, j] D^c[j, l]; with ``m`` (a diagonal block)
    the top conditions of u, v, T of mode m in their top rows."""
    mm = disc.n + 1
    size = 4 * mm
    g = disc.grid
    jets = np.zeros((4, mm, 4, mm), dtype=complex)  # (r, j, f, l)
    for c, Dc in enumerate((None, g.D, g.D2)):
        Ec = E[:, c].transpose(1, 2, 0)  # (r, j, f)
        if Dc is None:
            idx = np.arange(mm)
            jets[:, idx, :, idx] += Ec.transpose(1, 0, 2)
        else:
            jets += Ec[..., None] * Dc[None, :, None, :]
    block = jets.reshape(size, size)
    if m is not None:
        kabs = 2.0 * np.pi * abs(m) / disc.length
        if disc.x_map is not None:
            # (1/g') |∂_s|: its mean here, the first harmonics in the neighbouring blocks
            # (coupling_factors)
            kabs *= float(np.mean(disc.map_metric[0]))
        dy = (np.eye(mm), g.D, g.D2)
        for r, f in enumerate(UNKNOWNS[1:], start=1):
            for c, kpow, coef in disc._top_terms[f]:
                block[r * mm + mm - 1, r * mm : (r + 1) * mm] += coef * kabs**kpow * dy[c][-1]
    return block


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
    are S_m⁻¹ (dense, 4(N+1)-square) and U_m, L_m in their factored form
    (:func:`coupling_factors`: one harmonic of the coefficients per field and y-order times
    the shared Chebyshev matrices), so that an application is 2M products with the S_m⁻¹ —
    read down and then up again, so that the last read are still in cache — plus 2M with the
    factors, which read a few vectors per mode instead of a dense block. The products are
    bound by the memory traffic of the blocks: at P1, L = 1000, 41 × 80, the earlier three
    dense blocks per mode (S_m⁻¹, S_m⁻¹ L_m, U_{m−1} S_m⁻¹) made the application 55 % of a
    run's time (``benchmarks/bench_dns.py``, ``dns_coupled_apply``). The build assembles only
    the D_m, one mode at a time, and forms U_{m−1} S_m⁻¹ L_m from the factors too
    (:meth:`_schur`; 10.5 → 5.0 s at 257 × 96, ``dns_coupled_build``).
    """

    disc: Discretisation
    factors: InitVar[np.ndarray]  # (M + 1, 3, 4, 3, 4, N+1) of coupling_factors; not kept
    upper: np.ndarray = field(init=False, repr=False)  # (M + 1, 4, 3, 4, N+1): U_m (q = −1)
    lower: np.ndarray = field(init=False, repr=False)  # (M + 1, 4, 3, 4, N+1): L_m (q = +1)
    _sinv: list = field(init=False, repr=False)
    _dy: np.ndarray = field(init=False, repr=False)

    def __post_init__(self, factors):
        E = factors
        M = E.shape[0] - 1
        self.upper, self.lower = np.ascontiguousarray(E[:, 0]), np.ascontiguousarray(E[:, 2])
        sinv: list = [None] * (M + 1)
        S = _dense(self.disc, E[M, 1], M)
        for m in range(M, 0, -1):
            si = np.linalg.inv(S)
            sinv[m] = si
            UK = self._schur(self.upper[m - 1], si, self.lower[m])  # U_{m−1} S_m⁻¹ L_m
            D = _dense(self.disc, E[m - 1, 1], m - 1)
            S = D - UK if m > 1 else D.real - 2.0 * UK.real  # (row 0: x_0 real)
        sinv[0] = np.linalg.inv(S.real)
        self._sinv = sinv
        g = self.disc.grid
        mm = self.disc.n + 1
        self._dy = np.ascontiguousarray(np.concatenate((np.eye(mm), g.D.T, g.D2.T), axis=1))

    @classmethod
    def build(
        cls, disc: Discretisation, C: np.ndarray, history: tuple, dt: float, bdf=BDF2
    ) -> CoupledPreconditioner:
        """Coefficients at the state ``C`` (:func:`~chuteflow.dns.columns.jet_coefficients`),
        their harmonics for the modes m = 0 … M, elimination."""
        coefs = jet_coefficients(disc, C, history, dt, bdf)
        return cls(disc, coupling_factors(disc, coefs, np.arange(disc.modes + 1), 1))

    def _schur(self, Eu: np.ndarray, si: np.ndarray, El: np.ndarray) -> np.ndarray:
        """U S⁻¹ L (dense, 4(N+1)-square) with U, L from their factors ``Eu``, ``El``
        (:func:`coupling_factors`): L's columns of field f are Σ_c diag(E[f, c]) D^c, so
        S⁻¹ L = Σ_c W_c D^c with W_c = S⁻¹ diag(E[·, c]) (columns scaled), and U X = Σ_{f, c}
        diag(E[f, c]) D^c X_f — products with the real Chebyshev matrices, the real and
        imaginary parts apart, in place of two dense complex products (four times the
        arithmetic)."""
        mm = self.disc.n + 1
        size = 4 * mm
        g = self.disc.grid
        # S⁻¹ L by its column blocks: K[f] = Σ_c W[c, f] D^c, W[c, f][a, j] = Σ_r S⁻¹[a, (r, j)] E[f, c, r, j]
        # (products batched over j: four times faster than einsum's loops)
        A = si.reshape(size, 4, mm).transpose(2, 0, 1)  # (j, a, r)
        W = (A @ El.transpose(3, 2, 1, 0).reshape(mm, 4, 12)).reshape(mm, size, 3, 4).transpose(2, 3, 1, 0)
        K = W[0].copy()
        for c, Dc in ((1, g.D), (2, g.D2)):
            Wc = W[c].reshape(4 * size, mm)
            K += (Wc.real @ Dc + 1j * (Wc.imag @ Dc)).reshape(4, size, mm)
        # U K = Σ_{f, c} diag(E[f, c]) D^c K_f, K_f the rows of K of field f (mm, size)
        Kmat = K.transpose(1, 0, 2).reshape(size, size)  # K[a, (f, l)]
        Kt = Kmat.reshape(4, mm, size).transpose(1, 0, 2).reshape(mm, 4 * size)  # (l, (f, b))
        Y = [Kt] + [Dc @ Kt.real + 1j * (Dc @ Kt.imag) for Dc in (g.D, g.D2)]
        Yc = np.stack(Y).reshape(3, mm, 4, size).transpose(1, 0, 2, 3).reshape(mm, 12, size)  # (j, (c, f), b)
        Eb = Eu.transpose(3, 2, 1, 0).reshape(mm, 4, 12)  # (j, r, (c, f))
        return (Eb @ Yc).transpose(1, 0, 2).reshape(size, size)  # (r, j, b)

    def _factored(self, E: np.ndarray, y: np.ndarray) -> np.ndarray:
        """A coupling block times y from its factors E (:func:`coupling_factors`):
        Σ_{f, c} E[f, c] ⊙ (D^c y_f) (real products with the stacked [1 | Dᵀ | D²ᵀ], the
        real and imaginary parts apart: three times faster than one complex product at
        N = 80)."""
        mm = self.disc.n + 1
        Y = y.reshape(4, mm)
        d = (Y.real @ self._dy + 1j * (Y.imag @ self._dy)).reshape(4, 3, 1, mm)  # (f, c, ·, j)
        return (E * d).sum(axis=(0, 1)).reshape(-1)

    def apply(self, R: np.ndarray) -> np.ndarray:
        """The preconditioned correction (4, N+1, M+1) of the residual ``R``."""
        M = self.disc.modes
        size = 4 * (self.disc.n + 1)
        r = R.reshape(size, M + 1).T  # (M + 1, size)
        rho = r.astype(complex)
        for m in range(M, 1, -1):
            rho[m - 1] -= self._factored(self.upper[m - 1], self._sinv[m] @ rho[m])
        x = np.empty_like(rho)
        if M:
            x[0] = self._sinv[0] @ (
                r[0].real - 2.0 * self._factored(self.upper[0], self._sinv[1] @ rho[1]).real
            )
        else:
            x[0] = self._sinv[0] @ r[0].real
        # (the blocks S_m⁻¹ in the reverse order of the sweep above: the last read are in cache)
        for m in range(1, M + 1):
            x[m] = self._sinv[m] @ (rho[m] - self._factored(self.lower[m], x[m - 1]))
        out = x.T.reshape(R.shape)
        out[..., 0] = out[..., 0].real
        return out
