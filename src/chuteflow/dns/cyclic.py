"""LU of a periodic block-tridiagonal matrix: the column preconditioner's solver.

The column preconditioner (:mod:`chuteflow.dns.columns`) with second-order x-differences is
block tridiagonal and periodic in x: on the 2M + 1 points x_i a block D_i (the column at
x_i, 4(N+1) square) and its couplings L_i to x_{i−1} and U_i to x_{i+1}, indices modulo the
number of points. A general sparse LU (``scipy.sparse.linalg.splu``) of that matrix fills in
the dense blocks of exact Chebyshev y-derivatives: 2.2 GB and 290 s at 129 × 96 (docs/dns.md,
*Solver*). Block Gaussian elimination along x, with the periodic corner carried as a border
(the last block column and the last block row), costs instead about 13 b³ flops a block
(b = 4(N+1)) in dense BLAS-3 products and keeps five blocks per point, the coupling L_i
sparse (below; a bordered block LU; e.g. Golub & Van Loan, *Matrix Computations*, 4th ed.,
§4.5). Pivoting is within the diagonal
blocks only (``numpy.linalg.inv``, LAPACK's partially pivoted LU): the blocks carry the
implicit step's a0/Δt on the diagonal of the time-dependent rows.

The border fill decays geometrically away from the corner (at P5's mapped bore, 129 × 96, by
≈ 3 a block: 1e-12 of the corner's after 80 of the 128 blocks); border blocks smaller than
:data:`BORDER_DROP` times the largest are dropped, which changes the solve by less than that
relative amount — far below GMRES's tolerance (1e-6) — and saves about a third of the
memory traffic of a solve.

A solve is bound by that memory traffic: per point it reads D_i⁻¹, D_i⁻¹ U_i and L_i. The
couplings L_i, U_i are sparse (the x-differences: diagonal in y, dense only in the rows of the
mixed ∂_x∂_y jets and the top conditions; 13 % of the entries at P1's mapped wave, 225 × 96),
so a coupling with fewer than :data:`SPARSE_BELOW` of its entries nonzero is kept in CSR form:
its product in the solve reads a seventh as much (a solve there 64.6 → 50.8 ms; the
factorisation, dominated by the inversions of the diagonal blocks, hardly changes: docs/dns.md,
*The columns' couplings kept sparse*).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps

__all__ = ["BORDER_DROP", "SPARSE_BELOW", "CyclicBlockLU"]

#: Border blocks (the periodic corner's fill) below this fraction of the largest are dropped.
BORDER_DROP = 1e-12
#: A coupling block with fewer nonzero entries than this fraction is kept sparse (CSR).
SPARSE_BELOW = 0.3


def _thin(block: np.ndarray):
    """``block`` in CSR form where fewer than :data:`SPARSE_BELOW` of its entries are nonzero."""
    if np.count_nonzero(block) < SPARSE_BELOW * block.size:
        return sps.csr_array(block)
    return block


class CyclicBlockLU:
    """The LU of the periodic block-tridiagonal matrix with blocks ``diagonal[i]`` at (i, i),
    ``lower[i]`` at (i, i − 1) and ``upper[i]`` at (i, i + 1), indices modulo n.

    Parameters
    ----------
    diagonal, lower, upper : ndarray, shape (n, b, b)
        The blocks (real), n ≥ 1 (for n ≤ 2 the offsets coincide and the blocks are summed).
    """

    def __init__(self, diagonal: np.ndarray, lower: np.ndarray, upper: np.ndarray):
        n, b, _ = diagonal.shape
        self.n, self.b = n, b
        if n <= 2:
            full = np.zeros((n * b, n * b))
            for i in range(n):
                for o, blk in ((0, diagonal), (-1, lower), (1, upper)):
                    j = (i + o) % n
                    full[i * b : (i + 1) * b, j * b : (j + 1) * b] += blk[i]
            self._dense = np.linalg.inv(full)
            return
        last = n - 1
        inv = np.empty_like(diagonal)
        XU = np.zeros_like(diagonal)  # D_i⁻¹ U_i
        XR: dict[int, np.ndarray] = {}  # D_i⁻¹ (border block of row i)
        BB: dict[int, np.ndarray] = {}  # the last row's block at column i
        scale_r, scale_b = np.abs(lower[0]).max(), np.abs(upper[last]).max()
        right: np.ndarray | None = lower[0].copy()  # A[0, last]
        bottom: np.ndarray | None = upper[last].copy()  # A[last, 0]
        thin_lower = [_thin(blk) for blk in lower]
        thin_upper = [_thin(blk) for blk in upper]
        d_last = diagonal[last].copy()
        d = diagonal[0].copy()
        for i in range(last):
            inv[i] = np.linalg.inv(d)
            if right is not None and np.abs(right).max() <= BORDER_DROP * scale_r:
                right = None
            if bottom is not None and np.abs(bottom).max() <= BORDER_DROP * scale_b:
                bottom = None
            if right is not None:
                XR[i] = inv[i] @ right
            if bottom is not None:
                BB[i] = bottom
                if i in XR:
                    d_last -= bottom @ XR[i]
            if i + 1 == last:
                break
            XU[i] = inv[i] @ thin_upper[i]
            d = diagonal[i + 1] - thin_lower[i + 1] @ XU[i]
            # the fill of the border: row i + 1's block in the last column, the last row's in column i + 1
            new_right = upper[i + 1].copy() if i + 1 == last - 1 else None
            if right is not None:
                fill = thin_lower[i + 1] @ XR[i]
                new_right = -fill if new_right is None else new_right - fill
            new_bottom = lower[last].copy() if i + 1 == last - 1 else None
            if bottom is not None:
                fill = bottom @ XU[i]
                new_bottom = -fill if new_bottom is None else new_bottom - fill
            right, bottom = new_right, new_bottom
        inv[last] = np.linalg.inv(d_last)
        self._inv, self._xu, self._lower = inv, XU, thin_lower
        self._rows_r = np.array(sorted(XR), dtype=int)
        self._rows_b = np.array(sorted(BB), dtype=int)
        xr = [XR[i] for i in self._rows_r] or [np.zeros((0, b))]
        bb = [BB[i] for i in self._rows_b] or [np.zeros((b, 0))]
        self._xr = np.ascontiguousarray(np.concatenate(xr, axis=0))
        self._bb = np.ascontiguousarray(np.concatenate(bb, axis=1))

    @property
    def nbytes(self) -> int:
        """Memory of the factors (bytes)."""
        if self.n <= 2:
            return int(self._dense.nbytes)
        thin = sum(
            b.data.nbytes + b.indices.nbytes + b.indptr.nbytes if sps.issparse(b) else b.nbytes
            for b in self._lower
        )
        return int(thin + sum(a.nbytes for a in (self._inv, self._xu, self._xr, self._bb)))

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """x with A x = ``rhs`` (a vector of n·b, ordered block by block)."""
        n, b = self.n, self.b
        if n <= 2:
            return self._dense @ rhs
        last = n - 1
        y = np.array(rhs, dtype=float).reshape(n, b)
        z = np.empty_like(y)
        inv, lower = self._inv, self._lower
        for i in range(last):
            z[i] = inv[i] @ y[i]
            if i + 1 < last:
                y[i + 1] -= lower[i + 1] @ z[i]
        y[last] -= self._bb @ z[self._rows_b].ravel()
        x = np.empty_like(y)
        x[last] = inv[last] @ y[last]
        z[self._rows_r] -= (self._xr @ x[last]).reshape(-1, b)
        x[last - 1] = z[last - 1]
        for i in range(last - 2, -1, -1):
            x[i] = z[i] - self._xu[i] @ x[i + 1]
        return x.ravel()
