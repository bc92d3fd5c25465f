"""Collocation sanity check of the Chebyshev layer and the generic eigen-solvers.

Orr–Sommerfeld equation of plane Poiseuille flow U = 1 − y² at Re = 10⁴, α = 1:
Orszag (1971, J. Fluid Mech. 50, 689) gives the least-stable eigenvalue
c = 0.23752649 + 0.00373967i to the eight digits printed there.
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.spectral import ChebyshevGrid
from chuteflow.stability.eigen import ShiftInvert, qz

ORSZAG = 0.23752649 + 0.00373967j


def orr_sommerfeld(n: int, re: float = 1e4, a: float = 1.0):
    """Pencil A v = c B v of (D² − a²)² v − i a Re [(U − c)(D² − a²) v − U'' v] = 0 with
    v = v' = 0 at y = ±1, collocated on the interior nodes; boundary rows have B = 0."""
    g = ChebyshevGrid(n, -1.0, 1.0)
    D, D2 = g.D, g.D2
    D4 = D2 @ D2
    eye = np.eye(n + 1)
    U, U2 = 1.0 - g.y**2, -2.0 * np.ones(n + 1)
    L = D2 - a * a * eye
    A = (D4 - 2 * a * a * D2 + a**4 * eye) - 1j * a * re * (U[:, None] * L - np.diag(U2))
    B = -1j * a * re * L
    A[0], A[-1], A[1], A[-2] = eye[0], eye[-1], D[0], D[-1]
    B[[0, 1, -2, -1]] = 0.0
    # rows divided by their largest entry: D⁴ reaches ~N⁸, and QZ/LU are normwise stable
    r = 1.0 / np.abs(A).max(axis=1)
    return (A * r[:, None]).astype(complex), (B * r[:, None]).astype(complex)


def least_stable_c(c):
    # boundary rows make B singular: their infinite eigenvalues come out of QZ as huge
    # finite numbers; physical phase speeds lie within the range of U, [0, 1]
    c = c[np.abs(c) < 2.0]
    return c[np.argmax(c.imag)]


def test_orszag_qz_converges_to_eight_digits():
    found = []
    for n in (80, 100):
        c, _ = qz(*orr_sommerfeld(n), vectors=False)
        found.append(least_stable_c(c))
    # both resolutions agree far below Orszag's last digit: the value is converged
    assert abs(found[0] - found[1]) < 1e-10
    assert abs(found[1] - ORSZAG) < 1e-8


def test_shift_invert_matches_qz_on_orr_sommerfeld():
    A, B = orr_sommerfeld(100)
    c_qz, _ = qz(A, B, vectors=False)
    ref = least_stable_c(c_qz)
    c, V = ShiftInvert(A, B, 0.24 + 0.0j).nearest(1)
    assert abs(c[0] - ref) < 1e-10
    assert np.linalg.norm(A @ V[:, 0] - c[0] * (B @ V[:, 0])) < 1e-8 * np.abs(A).max()


@pytest.mark.parametrize("n", [16, 40])
def test_chebyshev_derivative_of_polynomial_exact(n):
    g = ChebyshevGrid(n, 0.0, 3.0)
    p = np.polynomial.Polynomial([0.3, -1.0, 0.5, 0.25, -0.1])
    assert np.allclose(g.D @ p(g.y), p.deriv()(g.y), atol=1e-11)
    assert np.allclose(g.D2 @ p(g.y), p.deriv(2)(g.y), atol=1e-10)


# -- the sinh-mapped grid ------------------------------------------------------------------
@pytest.mark.parametrize("blend", [1.0, 0.5])
def test_mapped_grid_calculus_is_exact_to_round_off(blend):
    """d/dy, d²/dy², ∫, ∫_a^y and interpolation of a function resolved on the mapped grid
    (analytic identities; a Gaussian layer of width 0.3 at y = 3 needs the clustering)."""
    from chuteflow.spectral import MappedChebyshevGrid

    g = MappedChebyshevGrid(120, 0.0, 10.0, 3.0, 0.6, blend)
    f = lambda y: np.exp(-((y - 3.0) ** 2) / 0.18) + np.sin(y)  # noqa: E731
    df = -2 * (g.y - 3.0) / 0.18 * np.exp(-((g.y - 3.0) ** 2) / 0.18) + np.cos(g.y)
    d2f = ((2 * (g.y - 3.0) / 0.18) ** 2 - 2 / 0.18) * np.exp(-((g.y - 3.0) ** 2) / 0.18) - np.sin(g.y)
    from math import erf, pi, sqrt

    total = sqrt(pi * 0.18) / 2 * (erf(7 / sqrt(0.18)) + erf(3 / sqrt(0.18))) + 1 - np.cos(10.0)
    assert g.y[0] == 0.0
    assert g.y[-1] == 10.0
    assert (np.diff(g.y) > 0).all()
    assert np.abs(g.D @ f(g.y) - df).max() < 1e-9 * np.abs(df).max()
    assert np.abs(g.D2 @ f(g.y) - d2f).max() < 1e-7 * np.abs(d2f).max()
    assert abs(g.integrate(f(g.y)) - total) < 1e-12
    assert abs(g.cumulative(f(g.y))[-1] - total) < 1e-12
    yq = np.linspace(0.0, 10.0, 23)
    assert np.abs(g.interpolate(f(g.y), yq) - f(yq)).max() < 1e-10
    # the computational variable: its nodes are the Lobatto points, and it inverts the map
    assert np.allclose(g.to_computational(g.y), g.x, atol=1e-13)


def test_mapped_grid_clusters_at_the_centre_and_tends_to_the_plain_grid():
    from chuteflow.spectral import MappedChebyshevGrid

    g = MappedChebyshevGrid(64, 0.0, 40.0, 10.0, 0.5)
    h = np.diff(g.y)
    j = int(np.argmin(np.abs(g.y[:-1] - 10.0)))
    assert h[j] < 0.2 * np.diff(ChebyshevGrid(64, 0.0, 40.0).y)[j]
    wide = MappedChebyshevGrid(64, 0.0, 40.0, 10.0, 1e6)
    assert np.allclose(wide.y, ChebyshevGrid(64, 0.0, 40.0).y, atol=1e-6)
    assert wide.with_n(32).n == 32
    assert wide.with_n(32).width == 1e6
    with pytest.raises(ValueError, match="width"):
        MappedChebyshevGrid(64, 0.0, 40.0, 10.0, 0.0)


# -- interpolation: barycentric inside the interval, Clenshaw outside ----------------------
@pytest.mark.parametrize("n", [8, 64, 145])
def test_barycentric_interpolation_is_the_interpolating_polynomial(n):
    """The barycentric formula (few points) and Clenshaw's recurrence on the coefficients
    (many points, or outside [−1, 1]) give the same polynomial: a random polynomial of degree
    n is reproduced to round-off by both, nodes exactly, stacked and complex series alike."""
    from chuteflow.spectral import _evaluate, barycentric, coefficients

    rng = np.random.default_rng(n)
    c = rng.standard_normal((2, n + 1)) / (1.0 + np.arange(n + 1))
    xj = -np.cos(np.pi * np.arange(n + 1) / n)
    f = np.polynomial.chebyshev.chebval(xj, c.T, tensor=True)
    assert np.allclose(coefficients(f), c, atol=1e-13)
    x = np.concatenate([rng.uniform(-1.0, 1.0, n), xj[[0, n // 3, n]]])
    exact = np.polynomial.chebyshev.chebval(x, c.T, tensor=True)
    b = barycentric(f, n, x)
    assert b.shape == (2, len(x))
    assert np.abs(b - exact).max() < 1e-13 * np.abs(f).max() * n
    assert (b[:, -3:] == f[:, [0, n // 3, n]]).all()  # at a node: the nodal value itself
    z = barycentric(f[0] + 1j * f[1], n, x[:5])
    assert np.allclose(z, exact[0, :5] + 1j * exact[1, :5], rtol=0, atol=1e-12)
    # many points, and points outside [−1, 1]: Clenshaw, the same polynomial
    for xs in (np.linspace(-1.0, 1.0, 8 * n + 1), np.array([-1.0, 0.3, 1.0 + 1e-9])):
        out = _evaluate(f, n, xs)
        assert np.abs(out - np.polynomial.chebyshev.chebval(xs, c.T, tensor=True)).max() < 1e-12 * n
    # a scalar height gives a scalar per series
    g = ChebyshevGrid(n, 0.0, 2.0)
    assert g.interpolate(f[0], np.array(0.7)).shape == ()


def test_end_nodes_off_by_round_off_are_the_ends():
    """Another grid's end node that maps to |x| = 1 + O(eps) is interpolated as the end
    (the nodal value, by the barycentric formula), not sent to Clenshaw as a point outside."""
    from unittest import mock

    from chuteflow import spectral

    f = np.sin(np.arange(65.0))
    x = np.array([-1.0 - 2e-16, 0.25, 1.0 + 2.2e-16])
    with mock.patch.object(spectral, "barycentric", wraps=spectral.barycentric) as bary:
        out = spectral._evaluate(f, 64, x)
    assert bary.call_count == 1
    assert out[0] == f[0]
    assert out[-1] == f[-1]


def test_fd_weights_are_exact_for_polynomials_below_their_degree():
    """Fornberg's weights from four uneven points: the derivatives of orders 0–2 of a cubic
    exactly (to round-off), at a point inside and at an end (an analytic identity)."""
    from chuteflow.spectral import fd_weights

    x = np.array([0.0, 0.3, 0.45, 1.1])
    p = np.polynomial.Polynomial([0.7, -1.3, 2.1, 0.9])
    for z in (0.3, 0.0, 1.1):
        w = fd_weights(z, x, 2)
        for k in range(3):
            assert w[k] @ p(x) == pytest.approx(p.deriv(k)(z), abs=1e-12)


def test_fd_matrices_on_chebyshev_nodes_are_second_order():
    """fd_matrices: exact for quadratics on any nodes; on Chebyshev nodes the error for sin(3y)
    falls as N⁻² (ratio ≈ 4 at every doubling of N, both matrices) — the order of the
    three-point stencils."""
    from chuteflow.spectral import fd_matrices

    g = ChebyshevGrid(16, 0.0, 2.0)
    D, D2 = fd_matrices(g.y)
    q = 1.0 - 0.5 * g.y + 0.75 * g.y**2
    assert np.abs(D @ q - (-0.5 + 1.5 * g.y)).max() < 1e-11
    assert np.abs(D2 @ q - 1.5).max() < 1e-10
    errs = []
    for n in (32, 64, 128):
        y = ChebyshevGrid(n, 0.0, 2.0).y
        D, D2 = fd_matrices(y)
        errs.append(
            (
                np.abs(D @ np.sin(3 * y) - 3 * np.cos(3 * y)).max(),
                np.abs(D2 @ np.sin(3 * y) + 9 * np.sin(3 * y)).max(),
            )
        )
    for (a1, a2), (b1, b2) in zip(errs, errs[1:]):
        assert 3.0 < a1 / b1 < 5.0
        assert 3.0 < a2 / b2 < 5.0
    with pytest.raises(ValueError, match="at least 4"):
        fd_matrices(np.array([0.0, 1.0, 2.0]))
