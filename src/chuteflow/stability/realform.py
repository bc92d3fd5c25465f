"""The real form of the k_x = 0 pencil and its real-arithmetic solvers (paper §5.3).

Across the slope (k_x = 0) the pencil is real after the diagonal similarity ŵ → i ŵ (every
term odd in ∂_z couples ŵ to the other fields): A' = S⁻¹ A S, S = diag(s), s = i on the ŵ
block and 1 elsewhere, B' = B (:func:`real_form`). Its eigenvalues are real or come in
conjugate pairs, and

* the dense eigenproblem is the real QZ (:func:`pencil_qz`: :func:`~chuteflow.stability.eigen.qz`
  on (A', B'), about half the complex one's cost);
* a shift-invert with a real shift needs one real LU (about a fifth of the complex one's
  time at N = 80–125): :class:`_RealFormShiftInvert`, :func:`_nearest_kx0`;
* the real inverse iteration of the transverse tracker (:func:`_inverse_iteration`) and the
  seeding spectrum past its branch (:func:`_seed_spectrum`, the dense eigenproblem of
  (A' − σB')⁻¹B') run on the same matrices.

A'(k_z) = R0 + k_z R1 + k_z² R2 is built from three real pieces computed once per operator
(:func:`_real_pieces`); the pieces and the last k_z's matrix are memoised on the operator
(:attr:`StabilityOperator.memo <chuteflow.stability.StabilityOperator>`), dropped with it.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import ConvergenceError, ParameterError
from .eigen import ShiftInvert, factor_shifted, qz, shifted_spectrum
from .operator import Pencil, StabilityOperator

__all__ = ["pencil_qz", "real_form"]


def real_form(pencil: Pencil) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A', B', s): the equilibrated pencil at k_x = 0 made real by A' = S⁻¹ A S, S = diag(s)
    with s = i on the ŵ block and 1 elsewhere (B' = B). An eigenvector W' of (A', B') is
    W = S W' of the equilibrated pencil."""
    if pencil.kx != 0 or "w" not in pencil.fields:
        raise ParameterError("real_form: needs the three-dimensional pencil at kx = 0")
    A, B = pencil.equilibrated()
    s = np.ones(A.shape[0], dtype=complex)
    s[pencil.slices()["w"]] = 1j
    Ar = (A * s[None, :]) / s[:, None]
    scale = np.abs(Ar).max()
    if np.abs(Ar.imag).max() > 1e-12 * scale:  # pragma: no cover - structural identity
        raise AssertionError("the kx = 0 pencil is not real after ŵ → iŵ")
    return np.ascontiguousarray(Ar.real), np.asarray(B, dtype=float), s


def pencil_qz(pencil: Pencil, vectors: bool = True):
    """Finite eigenvalues (decreasing Re) and, if asked, eigenvectors (unit 2-norm) of the
    equilibrated pencil by dense QZ (:func:`~chuteflow.stability.eigen.qz`); at k_x = 0 in
    3D on the real form (:func:`real_form`, the real QZ), its eigenvectors mapped back by S."""
    if pencil.kx == 0 and "w" in pencil.fields:
        A, B, s = real_form(pencil)
        w, V = qz(A, B, vectors=vectors)
        return w, (None if V is None else V * s[:, None])
    return qz(*pencil.equilibrated(), vectors=vectors)


def _shifted(A: np.ndarray, bdiag: np.ndarray, sigma, dtype=float) -> np.ndarray:
    """A − σ diag(bdiag), a new array in Fortran order: LAPACK's, so that ``lu_factor``
    factors it in place instead of copying a C-ordered array first (bitwise the same
    factors, one copy of the matrix fewer)."""
    M = np.empty(A.shape, dtype=dtype, order="F")
    M[...] = A
    i = np.arange(A.shape[0])
    M[i, i] -= sigma * bdiag
    return M


def _real_lu(A: np.ndarray, bdiag: np.ndarray, sigma: float):
    return sla.lu_factor(_shifted(A, bdiag, sigma), overwrite_a=True, check_finite=False)


def _inverse_iteration(lu, bdiag, sigma, v0, *, maxiter=14, tol=1e-9, floor=1e-15):
    """Real inverse iteration x ↦ (A' − σB')⁻¹ B' x from v0: (α, v) or None if unsettled.

    Settled: |Δα| ≤ tol |α − σ| + 1e-13 |α| + ``floor``; the absolute floor is the
    round-off of the solves (~1e-17 at P1 near α ~ 1e-8, where A' − σB' is nearly singular),
    far below the drift threshold 1e-7."""
    v = np.asarray(v0, dtype=float)
    nv = np.linalg.norm(v)
    if nv == 0 or not np.isfinite(nv):
        return None
    v = v / nv
    prev = None
    (getrs,) = sla.get_lapack_funcs(("getrs",), (lu[0],))  # lu_solve's routine, unchecked
    for _ in range(maxiter):
        w, _info = getrs(lu[0], lu[1], bdiag * v)
        vw = float(v @ w)
        nw = float(np.linalg.norm(w))
        if vw == 0 or not np.isfinite(nw) or nw == 0:
            return None
        alpha = sigma + 1.0 / vw
        v = w / nw
        if prev is not None and abs(alpha - prev) <= tol * abs(alpha - sigma) + 1e-13 * abs(alpha) + floor:
            return alpha, v
        prev = alpha
    return None


def _real_pieces(op: StabilityOperator):
    """(R0, R1, R2, diag B', s) of the real form A'(k_z) = S⁻¹ A(0, k_z) S = R0 + k_z R1 +
    k_z² R2 (:func:`real_form`) at k_z ≥ 0, straight from the operator's equilibrated real
    pieces: A(0, k_z) = Σ_d (ik_z)^d A_{0,d} + k_z K, each term times i^d s_c / s_r, which is
    real wherever the piece is not zero (checked)."""
    m, M = op.grid.n + 1, op.size
    jw = op.fields.index("w")
    s = np.ones(M, dtype=complex)
    s[jw * m : (jw + 1) * m] = 1j
    inw = np.zeros(M)
    inw[jw * m : (jw + 1) * m] = 1.0
    # i^d s_c / s_r: d even → (−1)^(d/2) within the ŵ block and outside it (imaginary across);
    # d odd → +1 from the ŵ rows to the other columns, −1 from the other rows to ŵ
    # (imaginary within): the real factor of each order and where it vanishes
    cross = np.abs(inw[:, None] - inw[None, :])  # 1 across the ŵ block's edge
    odd = inw[:, None] - inw[None, :]
    R = [np.zeros((M, M)) for _ in range(3)]
    scale, worst = 0.0, 0.0
    for (b, d), P in op._pieces_eq.items():  # the same package's operator
        if b:
            continue
        if d > 2:  # pragma: no cover - the equations are of second order in ∂_z
            raise AssertionError(f"a piece of order {d} in k_z")
        if d == 1:
            R[1] += odd * P
            imag = (1.0 - cross) * P
        else:
            R[d] += (1.0 - cross) * P if d == 0 else (cross - 1.0) * P
            imag = cross * P
        scale, worst = max(scale, float(np.abs(P).max())), max(worst, float(np.abs(imag).max()))
    rows, cols, vals = op._K_eq  # the |k| coefficient (top conditions)
    c = cross[rows, cols]
    np.add.at(R[1], (rows, cols), (1.0 - c) * vals)
    worst = max(worst, float(np.abs(c * vals).max(initial=0.0)))
    if worst > 1e-12 * scale:  # pragma: no cover - structural identity
        raise AssertionError("the kx = 0 pencil is not real after ŵ → iŵ")
    return R[0], R[1], R[2], np.diag(op.B_eq).copy(), s


def _real_entry(op: StabilityOperator, kz: float):
    """((pencil, A', diag B', s), memo) at (0, k_z ≥ 0) on ``op``: A'(k_z) = R0 + k_z R1 +
    k_z² R2 from the real form's three pieces (:func:`_real_pieces`, once per operator), a
    few additions per k_z instead of a complex assembly. The pieces and the last k_z's
    answer are kept in ``op.memo``; ``memo`` is a dict that lives as long as that answer
    (what solvers derive from A', e.g. its norm)."""
    pieces = op.memo.get("real_form_pieces")
    if pieces is None:
        pieces = op.memo["real_form_pieces"] = _real_pieces(op)
    R0, R1, R2, bd, s = pieces
    kz = abs(float(kz))
    last = op.memo.get("real_form_last")
    if last is not None and last[0] == kz:
        return last[1], last[2]  # the same k_z again (candidates, drifts, judging): not rebuilt
    A = R1 * kz
    A += R0
    if kz:
        A += (kz * kz) * R2
    out = (op.pencil(0.0, kz), A, bd, s)
    memo: dict = {}
    op.memo["real_form_last"] = (kz, out, memo)
    return out, memo


def _real_pencil(op: StabilityOperator, kz: float):
    """(pencil, A', diag B', s) at (0, k_z ≥ 0) on ``op`` (:func:`_real_entry`; the last k_z
    of each operator is kept). Callers must not write into A'."""
    return _real_entry(op, kz)[0]


class _RealFormShiftInvert(ShiftInvert):
    """:class:`~chuteflow.stability.eigen.ShiftInvert` on the real form (A', diag B') of the
    k_x = 0 pencil (:func:`real_form`). For a real shift the LU of A' − σB' is real (about a
    fifth of the complex one's time at N = 80–125) and a complex vector is solved as two
    real right-hand sides; for a complex shift it is the complex LU of the real A'. Vectors
    live in the real form's coordinates W' = S⁻¹W; |s| = 1, so norms, inner products and
    residuals are those of the equilibrated pencil and every iteration (inverse iteration,
    Arnoldi, polish) is the one :class:`ShiftInvert` runs on (A, B). ``memo``: a dict kept
    with A' (:func:`_real_entry`), where ‖A'‖∞ is remembered across shifts."""

    def __init__(self, Ar: np.ndarray, bdiag: np.ndarray, sigma: complex, *, memo: dict | None = None):
        self.A, self.sigma, self._bdiag, self._bd = Ar, complex(sigma), bdiag, bdiag
        self.size = Ar.shape[0]
        self._memo = {} if memo is None else memo
        self._real = self.sigma.imag == 0
        M = _shifted(Ar, bdiag, self.sigma.real) if self._real else _shifted(Ar, bdiag, self.sigma, complex)
        self.lu = factor_shifted(M, self.sigma)
        (self._getrs,) = sla.get_lapack_funcs(("getrs",), (self.lu[0],))

    @property
    def B(self) -> np.ndarray:  # type: ignore[override]
        """The diagonal B' as a matrix."""
        return np.diag(self._bd)

    def norms(self) -> tuple[float, float]:
        """(‖A'‖∞, ‖B'‖∞) = those of the equilibrated pencil (|s| = 1), ‖A'‖∞ kept with A'."""
        if not hasattr(self, "_norms"):
            if "norm_inf" not in self._memo:
                self._memo["norm_inf"] = float(np.abs(self.A).sum(axis=1).max())
            self._norms = (self._memo["norm_inf"], float(np.abs(self._bd).max()))
        return self._norms

    def solve(self, x):
        """(A' − σB')⁻¹ x."""
        x = np.asarray(x, dtype=complex)
        if not self._real:
            return super().solve(x)
        rhs = np.empty((self.size, 2 * (x.size // self.size)), order="F")
        xr = x.reshape(self.size, -1)
        rhs[:, 0::2], rhs[:, 1::2] = xr.real, xr.imag
        y, info = self._getrs(self.lu[0], self.lu[1], rhs)
        if info != 0:  # pragma: no cover - only for malformed arguments
            raise ValueError(f"getrs: illegal value in argument {-info}")
        return (y[:, 0::2] + 1j * y[:, 1::2]).reshape(x.shape)


def _real_null_vector(op: StabilityOperator) -> np.ndarray:
    """The right eigenvector of the equilibrated k = 0 pencil for its eigenvalue nearest 0:
    the shift-invert Arnoldi at σ = 0 of :func:`~chuteflow.stability.tracking.null_vectors`
    on the real form (a real LU; the left vector is not needed here)."""
    (_, Ar, bd, s), memo = _real_entry(op, 0.0)
    _, W = _RealFormShiftInvert.nudged(Ar, bd, 0.0, memo=memo).nearest(1)
    return s * W[:, 0]


def _nearest_kx0(op: StabilityOperator, kz: float, sigma: complex, v0=None, *, real_rtol: float = 1e-8):
    """:func:`~chuteflow.stability.nearest_eigenpair` on ``op.pencil(0, k_z)`` computed on
    its real form (:class:`_RealFormShiftInvert`, the matrix from :func:`_real_pencil`'s
    pieces instead of a complex assembly): the same inverse iteration from ``v0`` (a random
    start without it), the same nudge of a shift on an eigenvalue and the same Arnoldi
    fallback, so the same eigenpair up to round-off. A shift whose imaginary part is within
    ``real_rtol`` of its modulus is taken as real (the real LU): real eigenvalues solved in
    complex arithmetic carry imaginary parts of round-off, up to 1.4e-9 relative at P1 next
    to the continuum; the complex pairs past the branch have |Im α| > 0.1 |α|. Returns
    (α, w, pencil), w an eigenvector of the equilibrated pencil."""
    (p, Ar, bd, s), memo = _real_entry(op, kz)
    sigma = complex(sigma)
    if abs(sigma.imag) <= real_rtol * abs(sigma):
        sigma = complex(sigma.real)
    si = _RealFormShiftInvert.nudged(Ar, bd, sigma, memo=memo)
    sigma = si.sigma
    if v0 is not None:
        start = np.asarray(v0, dtype=complex) / s
        found = si.iterate(start)
    else:
        rng = np.random.default_rng(2024)
        start = si.apply((rng.standard_normal(si.size) + 1j * rng.standard_normal(si.size)) / s)
        found = si.iterate(start, maxiter=16)
    if found is None:
        alpha, V = si.nearest(1, v0=si.apply(start))
        if len(alpha) == 0:
            raise ConvergenceError(f"no eigenvalue converged near {complex(sigma):.6g} at N = {p.n}")
        found = alpha[0], V[:, 0]
    return found[0], s * found[1], p


def _seed_spectrum(op: StabilityOperator, kz: float, shift: float = 0.5):
    """Finite eigenvalues (decreasing Re) and eigenvectors of the equilibrated pencil at
    (0, k_z) on ``op``, as :func:`pencil_qz` returns them (up to the vectors' scale), by the
    dense eigenproblem of C = (A' − σB')⁻¹B' (real form, σ = ``shift``, to the right of the
    decaying spectrum past the tracked branch: one real LU and a real ``geev``; α = σ + 1/θ
    for the eigenvalues θ ≠ 0 of C, the infinite ones mapping to θ = 0): about a third of
    the real QZ's time at N = 48. The same eigenpairs: at P1, k_z = 0.004–3, the seeds
    (eigenvalues and tails) agree with the QZ ones to 1e-12 and 1e-9 relative. Falls back
    on QZ when σ lies on an eigenvalue (a zero pivot or θ not finite)."""
    p, Ar, bd, s = _real_pencil(op, kz)
    got = shifted_spectrum(Ar, bd, shift, keep_rtol=1e-10, normalise=False)  # real arithmetic
    if got is None:
        return pencil_qz(p, True)
    w, Y = got
    return w, Y * s[:, None]
