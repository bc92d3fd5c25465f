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
