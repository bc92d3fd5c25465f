"""Chebyshev collocation on an interval: nodes, differentiation, quadrature, coefficients.

The lowest numerical layer; used by the steady solver and the stability operator alike.
Nodes are Gauss–Lobatto points ordered from the left end (the floor, y = 0) to the right
end (y = y_max).
"""

from __future__ import annotations

import functools
from functools import cached_property

import numpy as np


@functools.lru_cache(maxsize=64)
def _reference(n: int):
    """Nodes x_j = -cos(πj/n) on [-1, 1], differentiation matrix and Clenshaw–Curtis weights."""
    j = np.arange(n + 1)
    x = -np.cos(np.pi * j / n)
    c = np.ones(n + 1)
    c[0] = c[-1] = 2.0
    c *= (-1.0) ** j
    X = x[:, None] - x[None, :]
    D = np.outer(c, 1.0 / c) / (X + np.eye(n + 1))
    D -= np.diag(D.sum(axis=1))  # negative-sum trick: exact derivative of constants
    w = _clenshaw_curtis(n)
    for a in (x, D, w):
        a.setflags(write=False)
    return x, D, w


def _clenshaw_curtis(n: int) -> np.ndarray:
    theta = np.pi * np.arange(n + 1) / n
    w = np.zeros(n + 1)
    v = np.ones(n - 1)
    if n % 2 == 0:
        w[0] = w[n] = 1.0 / (n**2 - 1)
        for k in range(1, n // 2):
            v -= 2.0 * np.cos(2 * k * theta[1:-1]) / (4 * k**2 - 1)
        v -= np.cos(n * theta[1:-1]) / (n**2 - 1)
    else:
        w[0] = w[n] = 1.0 / n**2
        for k in range(1, (n - 1) // 2 + 1):
            v -= 2.0 * np.cos(2 * k * theta[1:-1]) / (4 * k**2 - 1)
    w[1:-1] = 2.0 * v / n
    return w


class ChebyshevGrid:
    """Chebyshev–Gauss–Lobatto grid of ``n + 1`` nodes on ``[a, b]``.

    Attributes
    ----------
    y : ndarray
        Nodes, ascending from ``a`` to ``b``.
    D : ndarray
        First-derivative matrix d/dy.
    D2 : ndarray
        Second-derivative matrix.
    weights : ndarray
        Clenshaw–Curtis quadrature weights (exact for polynomials of degree ≤ n).
    """

    def __init__(self, n: int, a: float = 0.0, b: float = 1.0):
        if n < 2:
            raise ValueError(f"n = {n}: need at least 2 intervals")
        self.n, self.a, self.b = int(n), float(a), float(b)
        x, D, w = _reference(self.n)
        half = 0.5 * (self.b - self.a)
        self.y = self.a + half * (x + 1.0)
        self.D = D / half
        self.weights = w * half

    @cached_property
    def D2(self) -> np.ndarray:
        """Second-derivative matrix (built on first use: O(n³))."""
        return self.D @ self.D

    def __len__(self):
        return self.n + 1

    def integrate(self, f: np.ndarray) -> np.ndarray:
        """∫_a^b f dy (along the last axis)."""
        return f @ self.weights

    def cumulative(self, f: np.ndarray) -> np.ndarray:
        """∫_a^y f dy' at the nodes (spectral antiderivative with value 0 at ``a``)."""
        c = coefficients(f)
        n = self.n
        # antiderivative of Σ c_k T_k on [-1, 1]: standard recurrence
        C = np.zeros(n + 2, dtype=np.result_type(c, float))
        cc = np.concatenate([c, [0.0, 0.0]])
        cc0 = cc.copy()
        cc0[0] *= 2.0
        for k in range(1, n + 2):
            C[k] = (cc0[k - 1] - cc[k + 1]) / (2.0 * k)
        x = (self.y - self.a) / (0.5 * (self.b - self.a)) - 1.0
        vals = np.polynomial.chebyshev.chebval(x, C)
        vals -= vals[0]
        return vals * 0.5 * (self.b - self.a)

    def interpolate(self, f: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Evaluate the interpolant of nodal values ``f`` at points ``y`` (Clenshaw)."""
        x = (np.asarray(y) - self.a) / (0.5 * (self.b - self.a)) - 1.0
        return np.polynomial.chebyshev.chebval(x, coefficients(f))


def coefficients(f: np.ndarray) -> np.ndarray:
    """Chebyshev coefficients c_k of the interpolant of nodal values (nodes ascending in x)."""
    f = np.asarray(f)
    n = f.shape[-1] - 1
    # nodes x_j = -cos(πj/n): reversing gives the usual cos(πj/n) ordering
    g = f[..., ::-1]
    # DCT-I as the real FFT of the even extension (numpy only: scipy.fft costs ~0.3 s to import)
    ext = np.concatenate([g, g[..., -2:0:-1]], axis=-1)
    if np.iscomplexobj(ext):
        c = np.fft.fft(ext, axis=-1)[..., : n + 1] / n
    else:
        c = np.fft.rfft(ext, axis=-1).real / n
    c[..., 0] /= 2.0
    c[..., -1] /= 2.0
    return c


def tail(f: np.ndarray, m: int = 10) -> float:
    """Largest |c_k| of the highest ``m`` Chebyshev coefficients, relative to max |c_k|."""
    c = np.abs(coefficients(f))
    scale = c.max()
    return float(c[..., -m:].max() / scale) if scale > 0 else 0.0
