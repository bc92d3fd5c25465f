"""Chebyshev collocation on an interval: nodes, differentiation, quadrature, coefficients.

The lowest numerical layer; used by the steady solver and the stability operator alike.
Nodes are Gauss–Lobatto points ordered from the left end (the floor, y = 0) to the right
end (y = y_max), either linear in the computational variable x ∈ [−1, 1]
(:class:`ChebyshevGrid`) or clustered around an interior layer by a sinh map
(:class:`MappedChebyshevGrid`). Chebyshev coefficients and tails are always in x.
"""

from __future__ import annotations

import functools
import math
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


def reference_nodes(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Chebyshev–Lobatto nodes x_j = −cos(πj/n) on [−1, 1], the differentiation matrix d/dx
    there and the Clenshaw–Curtis weights (cached, read-only): what every grid of n
    intervals, mapped or not, is built from by the chain rule."""
    return _reference(n)


@functools.lru_cache(maxsize=8)
def _reference_d2(n: int) -> np.ndarray:
    """D_x @ D_x of :func:`_reference` (read-only): the O(n³) part of a mapped grid's D2,
    the same for every map of n intervals. Every flow has its own map, and a grid evicted
    from a cache (the steady solver's, a flow's) is rebuilt with its D2 when the flow is
    asked again (its tangent, its stability operators)."""
    Dx = _reference(n)[1]
    D2 = Dx @ Dx
    D2.setflags(write=False)
    return D2


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

    The nodes are y = y(x_j) for the Lobatto points x_j = −cos(πj/n) of the *computational
    variable* x ∈ [−1, 1]; here y is linear in x. Chebyshev coefficients
    (:func:`coefficients`, :func:`tail`) of nodal values are always those in x, which is
    what a mapped grid (:class:`MappedChebyshevGrid`) changes.

    Attributes
    ----------
    y : ndarray
        Nodes, ascending from ``a`` to ``b``.
    x : ndarray
        The same nodes in the computational variable x ∈ [−1, 1].
    D : ndarray
        First-derivative matrix d/dy.
    D2 : ndarray
        Second-derivative matrix.
    weights : ndarray
        Clenshaw–Curtis quadrature weights (exact for polynomials in x of degree ≤ n, times
        dy/dx).
    jacobian : ndarray
        dy/dx at the nodes.
    """

    def __init__(self, n: int, a: float = 0.0, b: float = 1.0):
        if n < 2:
            raise ValueError(f"n = {n}: need at least 2 intervals")
        self.n, self.a, self.b = int(n), float(a), float(b)
        x, D, w = _reference(self.n)
        half = 0.5 * (self.b - self.a)
        self.x = x
        self.y = self.a + half * (x + 1.0)
        self.D = D / half
        self.weights = w * half
        self.jacobian = np.full(self.n + 1, half)

    @cached_property
    def D2(self) -> np.ndarray:
        """Second-derivative matrix (built on first use: O(n³))."""
        return self.D @ self.D

    def __len__(self):
        return self.n + 1

    def to_computational(self, y) -> np.ndarray:
        """The computational variable x ∈ [−1, 1] of heights ``y``."""
        return (np.asarray(y, dtype=float) - self.a) / (0.5 * (self.b - self.a)) - 1.0

    def from_computational(self, x) -> np.ndarray:
        """Heights y of computational variables ``x`` ∈ [−1, 1] (inverse of
        :meth:`to_computational`)."""
        return self.a + 0.5 * (self.b - self.a) * (np.asarray(x, dtype=float) + 1.0)

    def integrate(self, f: np.ndarray) -> np.ndarray:
        """∫_a^b f dy (along the last axis)."""
        return f @ self.weights

    def cumulative(self, f: np.ndarray) -> np.ndarray:
        """∫_a^y f dy' at the nodes (spectral antiderivative with value 0 at ``a``)."""
        c = coefficients(np.asarray(f) * self.jacobian)
        n = self.n
        # antiderivative of Σ c_k T_k on [-1, 1]: standard recurrence
        C = np.zeros(n + 2, dtype=np.result_type(c, float))
        cc = np.concatenate([c, [0.0, 0.0]])
        cc0 = cc.copy()
        cc0[0] *= 2.0
        for k in range(1, n + 2):
            C[k] = (cc0[k - 1] - cc[k + 1]) / (2.0 * k)
        vals = np.polynomial.chebyshev.chebval(self.x, C)
        return vals - vals[0]

    def interpolate(self, f: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Evaluate the interpolant (a polynomial in x) of nodal values ``f`` at heights
        ``y``. ``f`` may stack several series along its leading axes (nodes on the last);
        the result then has shape ``f.shape[:-1] + y.shape``.

        Inside the interval by the barycentric formula for Chebyshev–Lobatto nodes
        (:func:`barycentric`; forward stable there, Higham 2004), outside it by Clenshaw's
        recurrence on the Chebyshev coefficients (the same polynomial)."""
        x = self.to_computational(y)
        return _evaluate(np.asarray(f), self.n, x)

    def _map_key(self) -> tuple:
        return (self.a, self.b)

    def with_n(self, n: int) -> ChebyshevGrid:
        """The grid of the same map with ``n`` intervals."""
        return ChebyshevGrid(n, self.a, self.b)


class MappedChebyshevGrid(ChebyshevGrid):
    """Chebyshev grid on ``[a, b]`` clustered around an interior height by a sinh map.

    y = c + ε sinh(s), with s linear in the computational variable x ∈ [−1, 1]
    (s(−1) = asinh((a − c)/ε), s(1) = asinh((b − c)/ε); Tee & Trefethen 2006, SIAM J. Sci.
    Comput. 28, 1798). Near y = c the spacing is ε (s₁ − s₀)/2 times that in x, so a layer
    of width ~ε at c is resolved by a fixed number of nodes whatever b − a; for ε ≫ b − a the
    map tends to the plain (linear) grid. Same interface as :class:`ChebyshevGrid`:
    derivative matrices d/dy, d²/dy² by the chain rule, quadrature weights w_x dy/dx,
    interpolation and Chebyshev coefficients in x.

    Parameters
    ----------
    n : int
        Number of intervals (n + 1 nodes).
    a, b : float
        The interval, a < b.
    center : float
        Height c where the nodes cluster (clipped to [a, b]).
    width : float
        Width ε > 0 of the clustered region.
    """

    def __init__(self, n: int, a: float, b: float, center: float, width: float, blend: float = 1.0):
        if n < 2:
            raise ValueError(f"n = {n}: need at least 2 intervals")
        if not (b > a):
            raise ValueError(f"[a, b] = [{a}, {b}]: need a < b")
        if not (width > 0 and np.isfinite(width)):
            raise ValueError(f"width = {width!r}: the map's width must be a positive number")
        if not (0.0 < blend <= 1.0):
            raise ValueError(f"blend = {blend!r}: the weight of the sinh map must be in (0, 1]")
        self.n, self.a, self.b = int(n), float(a), float(b)
        self.center = float(min(max(center, a), b))
        self.width = float(width)
        self.blend = float(blend)
        x, Dx, w = _reference(self.n)
        y, y1, y2 = self._map(x)
        y[0], y[-1] = self.a, self.b
        self.x = x
        self.y = y
        self.jacobian = y1
        self.D = Dx / y1[:, None]
        self._y2 = y2
        self.weights = w * y1

    def _map(self, x):
        """y(x), dy/dx, d²y/dx²: (1 − β) × linear + β × sinh map."""
        c, eps, beta = self.center, self.width, self.blend
        s0, s1 = math.asinh((self.a - c) / eps), math.asinh((self.b - c) / eps)
        ds = 0.5 * (s1 - s0)
        half = 0.5 * (self.b - self.a)
        s = s0 + ds * (np.asarray(x, dtype=float) + 1.0)
        y = (1 - beta) * (self.a + half * (x + 1.0)) + beta * (c + eps * np.sinh(s))
        y1 = (1 - beta) * half + beta * eps * np.cosh(s) * ds
        y2 = beta * eps * np.sinh(s) * ds**2
        return y, y1, y2

    @cached_property
    def D2(self) -> np.ndarray:
        """Second-derivative matrix d²/dy² (chain rule in x; built on first use, O(n²) with
        D_x² cached per n)."""
        Dx, y1 = _reference(self.n)[1], self.jacobian
        return _reference_d2(self.n) / (y1**2)[:, None] - (self._y2 / y1**3)[:, None] * Dx

    def to_computational(self, y) -> np.ndarray:
        """The computational variable x ∈ [−1, 1] of heights ``y`` (Newton on the monotone
        map, from the inverse of its sinh part)."""
        y = np.asarray(y, dtype=float)
        c, eps = self.center, self.width
        s0, s1 = math.asinh((self.a - c) / eps), math.asinh((self.b - c) / eps)
        x = 2.0 * (np.arcsinh((y - c) / eps) - s0) / (s1 - s0) - 1.0
        if self.blend < 1.0:
            for _ in range(50):
                f, f1, _ = self._map(x)
                dx = (f - y) / f1
                x = np.clip(x - dx, -1.0, 1.0)
                if np.all(np.abs(dx) < 1e-15):
                    break
        return x

    def from_computational(self, x) -> np.ndarray:
        """Heights y of computational variables ``x`` ∈ [−1, 1] (the map itself)."""
        return self._map(np.asarray(x, dtype=float))[0]

    def _map_key(self) -> tuple:
        return (self.a, self.b, self.center, self.width, self.blend)

    def with_n(self, n: int) -> MappedChebyshevGrid:
        """The grid of the same map with ``n`` intervals."""
        return MappedChebyshevGrid(n, self.a, self.b, self.center, self.width, self.blend)


#: Width of the sinh map that clusters nodes at the edge of a flowing layer, in units of the
#: density scale height T0/cos θ of the dilute top at the edge (:func:`layer_edge_map`). The
#: factor 2 is chosen from the stability operator's resolution at the paper's points
#: (:func:`chuteflow.stability.operator.layer_map`, ``benchmarks/probes/map_width.py``); the
#: steady grid uses the same map.
LAYER_MAP_WIDTH = 2.0
#: A map wider than this fraction of the domain is dropped (plain Chebyshev nodes): the layer
#: then has no sharp edge and the sinh map would only move nodes away from the floor.
LAYER_MAP_MAX = 0.5


def layer_edge_map(edge: float, T_edge: float, theta_deg: float, y_max: float) -> tuple[float, float] | None:
    """The sinh map (centre, width) of :class:`MappedChebyshevGrid` that clusters nodes at the
    edge of a flowing layer on [0, ``y_max``]: the one map of the steady grid
    (:func:`chuteflow.steady.grid.layer_grid_map`) and the stability grid
    (:func:`chuteflow.stability.operator.layer_map`), with one fallback rule.

    Above a dense layer on a slope θ the density falls with the scale height T0/cos θ of an
    isothermal atmosphere (y-momentum balance p' = −ν cos θ with p ≈ νT, paper eq. (3.5)): the
    transport coefficients change from their dense to their dilute form within a few scale
    heights of the edge, which a plain Chebyshev grid resolves only with many nodes (they
    crowd the ends instead). The map is centred at ``edge`` (a height where ν0 has fallen to
    1 % of its peak; each caller locates it) with width

        ε = :data:`LAYER_MAP_WIDTH` × ``T_edge`` / cos θ.

    Returns (``edge``, ε) in the units of ``y_max``, or None — the plain Chebyshev grid —
    where ε is not a positive number at most :data:`LAYER_MAP_MAX` × ``y_max`` (no sharp
    edge: a broad layer, or a state far from converged) or ``edge`` is not inside (0, y_max).
    """
    width = LAYER_MAP_WIDTH * T_edge / math.cos(math.radians(theta_deg))
    if not (math.isfinite(width) and 0.0 < width <= LAYER_MAP_MAX * y_max and 0.0 < edge < y_max):
        return None
    return edge, width


def barycentric(f: np.ndarray, n: int, x: np.ndarray) -> np.ndarray:
    """The interpolant of nodal values ``f`` (last axis: the n + 1 nodes x_j = −cos(πj/n))
    at points ``x`` ∈ [−1, 1], by the second (true) barycentric formula with the Lobatto
    weights (−1)^j, halved at the ends (Berrut & Trefethen 2004, SIAM Rev. 46, 501). A point
    that is a node gets its nodal value exactly. O(n m) for m points; Clenshaw on the
    coefficients costs the same operations as n passes over the m points."""
    xj = _reference(n)[0]
    w = _lobatto_weights(n)
    xs = np.asarray(x, dtype=float)
    flat = xs.reshape(-1)
    out = np.empty(f.shape[:-1] + (len(flat),), dtype=np.result_type(f, float))
    step = max(1, _BARY_BLOCK // (n + 1))  # points per block (small temporaries)
    for a in range(0, len(flat), step):
        d = flat[a : a + step, None] - xj[None, :]
        hit = d == 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            C = w / d
        rows = np.nonzero(hit.any(axis=1))[0]
        if len(rows):
            C[rows] = hit[rows]
        C /= C.sum(axis=1)[:, None]
        out[..., a : a + step] = f @ C.T
    return out.reshape(f.shape[:-1] + xs.shape)


#: Round-off of a computational variable at the interval's ends, taken as the end itself.
_ENDS = 1e-13

#: Entries (points × nodes) of one block of :func:`barycentric`: its temporaries stay below
#: glibc's mmap threshold (128 KiB), which would fault fresh pages in at every call.
_BARY_BLOCK = 12288


@functools.lru_cache(maxsize=64)
def _lobatto_weights(n: int) -> np.ndarray:
    w = (-1.0) ** np.arange(n + 1)
    w[0] *= 0.5
    w[-1] *= 0.5
    w.setflags(write=False)
    return w


def _evaluate(f: np.ndarray, n: int, x: np.ndarray) -> np.ndarray:
    """Interpolant of nodal values ``f`` at computational points ``x`` (see
    :meth:`ChebyshevGrid.interpolate`)."""
    if 0 < x.size <= 2 * (n + 1) and np.all(np.abs(x) <= 1.0 + _ENDS):
        # a few points (another grid's nodes, one height): barycentric, 3–10× faster; for
        # many points (a fine sampling) Clenshaw's n passes over them cost as little. An end
        # node of another grid can map to |x| = 1 + 2e-16 (1 of 57 sinh maps tried): it is
        # the end, not a point outside
        return barycentric(f, n, np.clip(x, -1.0, 1.0))
    c = coefficients(f)
    if c.ndim > 1:
        c = np.moveaxis(c, -1, 0)
    return np.polynomial.chebyshev.chebval(x, c, tensor=True)


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


def fd_weights(z: float, x: np.ndarray, m: int) -> np.ndarray:
    """Finite-difference weights ``w[k, j]`` of the derivatives of order k = 0 … ``m`` at
    ``z`` from values at the points ``x`` (any spacing; Fornberg 1988, Math. Comp. 51, 699):
    f^(k)(z) ≈ Σ_j w[k, j] f(x_j), exact for polynomials of degree < len(x)."""
    x = np.asarray(x, dtype=float)
    n = len(x) - 1
    w = np.zeros((m + 1, n + 1))
    w[0, 0] = 1.0
    c1, c4 = 1.0, x[0] - z
    for i in range(1, n + 1):
        mn = min(i, m)
        c2, c5, c4 = 1.0, c4, x[i] - z
        for j in range(i):
            c3 = x[i] - x[j]
            c2 *= c3
            if j == i - 1:
                for k in range(mn, 0, -1):
                    w[k, i] = c1 * (k * w[k - 1, i - 1] - c5 * w[k, i - 1]) / c2
                w[0, i] = -c1 * c5 * w[0, i - 1] / c2
            for k in range(mn, 0, -1):
                w[k, j] = (c4 * w[k, j] - k * w[k - 1, j]) / c3
            w[0, j] = c4 * w[0, j] / c3
        c1 = c2
    return w


def fd_matrices(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Second-order finite-difference matrices (d/dy, d²/dy²) on the nodes ``y`` (ascending,
    at least 4): three-point stencils inside, one-sided at the ends (three points for d/dy,
    four for d²/dy²), so both are exact for quadratics. Tridiagonal but for the end rows: the
    banded stand-in for a grid's dense Chebyshev matrices in a preconditioner (finite
    differences on the Chebyshev nodes precondition collocation uniformly in N; Orszag 1980,
    J. Comput. Phys. 37, 70)."""
    y = np.asarray(y, dtype=float)
    n = len(y)
    if n < 4:
        raise ValueError(f"{n} nodes: need at least 4")
    D = np.zeros((n, n))
    D2 = np.zeros((n, n))
    for j in range(n):
        if 0 < j < n - 1:
            idx = np.arange(j - 1, j + 2)
            w = fd_weights(y[j], y[idx], 2)
            D[j, idx], D2[j, idx] = w[1], w[2]
            continue
        idx = np.arange(4) if j == 0 else np.arange(n - 4, n)
        D2[j, idx] = fd_weights(y[j], y[idx], 2)[2]
        idx3 = idx[:3] if j == 0 else idx[1:]
        D[j, idx3] = fd_weights(y[j], y[idx3], 1)[1]
    return D, D2


def fourier_resample(f: np.ndarray, n: int) -> np.ndarray:
    """Periodic samples (…, n_old) trigonometrically interpolated onto ``n`` equispaced points
    along the last axis (the Fourier modes a grid of ``n`` points holds; the Nyquist mode of
    an even grid split between ±n_old/2)."""
    f = np.asarray(f, dtype=float)
    n_old = f.shape[-1]
    F = np.fft.rfft(f, axis=-1) / n_old
    if n_old % 2 == 0:
        F[..., -1] *= 0.5  # the Nyquist mode is shared by ±n_old/2 on the finer grid
    G = np.zeros((*f.shape[:-1], n // 2 + 1), dtype=complex)
    m = min(F.shape[-1], G.shape[-1])
    G[..., :m] = F[..., :m]
    return np.fft.irfft(G * n, n=n, axis=-1)


def fourier_evaluate(C: np.ndarray, x: np.ndarray, length: float, chunk: int = 256) -> np.ndarray:
    """The real series C_0 + 2 Re Σ_{m ≥ 1} C_m e^{i k_m x}, k_m = 2π m / ``length``, of the
    coefficients C (…, M + 1) at arbitrary points ``x``: values (…, len(x)), exact for the
    modes of C (a direct sum, in chunks of points). The points of a mapped grid
    (:mod:`chuteflow.dns.xmap`) or any other non-uniform ones."""
    C = np.asarray(C)
    x = np.asarray(x, dtype=float).ravel()
    k = 2.0 * np.pi * np.arange(C.shape[-1]) / length
    out = np.empty(C.shape[:-1] + (x.size,))
    for a in range(0, x.size, chunk):
        E = np.exp(1j * np.outer(k, x[a : a + chunk]))  # (M + 1, chunk)
        E[1:] *= 2.0
        out[..., a : a + chunk] = (C @ E).real
    return out
