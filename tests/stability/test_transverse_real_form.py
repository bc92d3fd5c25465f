"""The real-arithmetic pieces of the transverse path (issue 10, performance) against the
complex computations they replace, at P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05).

- A'(k_z) from the operator's pieces equals the real form of the assembled complex pencil
  (:func:`real_form`) to round-off: the same sums of the same real pieces.
- Shift-invert on the real form (real LU for a real shift) finds the eigenpair that
  :func:`nearest_eigenpair` finds on the complex pencil: |Δα| within the inverse iteration's
  tolerance 1e-7 |α − σ| plus the round-off floor 1e-12 (1 + |α|) of a shift-invert solve
  here, and parallel eigenvectors.
- The seeding eigenproblem of (A' − σB')⁻¹B' keeps the same seeds as the dense QZ:
  eigenvalues to 1e-10 relative plus the round-off floor 1e-12 (next to the continuum,
  |α| ~ 1e-5, they differ by up to 2.5e-13), tails to 1e-4 relative (measured ≤ 1e-6 over
  k_z = 0.003–3 at P1, T2 and P3).
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.stability import stability_operator
from chuteflow.stability.modes import nearest_eigenpair, tails
from chuteflow.stability.realform import (
    _nearest_kx0,
    _real_pencil,
    _seed_spectrum,
    pencil_qz,
    real_form,
)
from chuteflow.stability.transverse_tracking import DEFAULT_TRANSVERSE

SEED_N = DEFAULT_TRANSVERSE.seed_n


@pytest.mark.parametrize("n", [48, 80])
@pytest.mark.parametrize("kz", [0.0, 1e-5, 3e-3, 0.38, 3.0])
def test_real_pieces_equal_the_assembled_real_form(p1_flow, n, kz):
    op = stability_operator(p1_flow, n, True)
    A, B, s = real_form(op.pencil(0.0, kz))
    _, Ar, bd, s2 = _real_pencil(op, kz)
    assert np.abs(Ar - A).max() <= 1e-14 * np.abs(A).max()
    assert np.array_equal(bd, np.diag(B))
    assert np.array_equal(s, s2)


@pytest.mark.parametrize(
    ("kz", "sigma"),
    [
        (0.38, -1.5945799697675749),  # real mode, real shift: the real LU
        (0.0104, -0.2839082231762314 + 0.517681657874008j),  # complex pair, complex LU
    ],
)
def test_real_form_shift_invert_finds_the_same_eigenpair(p1_flow, kz, sigma):
    op = stability_operator(p1_flow, 80, True)
    pencil = op.pencil(0.0, kz)
    shift = sigma * (1 + 1e-4)
    a_ref, w_ref = nearest_eigenpair(pencil, shift)
    a, w, p = _nearest_kx0(op, kz, shift, v0=w_ref)
    assert p.n == 80
    assert p.kz == kz
    # both settle to the inverse iteration's tolerance 1e-7 |α − σ| (ShiftInvert.iterate)
    tol = 1e-7 * abs(a_ref - shift) + 1e-12 * (1 + abs(a_ref))
    assert abs(a - a_ref) <= tol
    cos = abs(np.vdot(w, w_ref)) / (np.linalg.norm(w) * np.linalg.norm(w_ref))
    assert cos == pytest.approx(1.0, abs=1e-8)
    # and from a random start (no v0): the same eigenvalue
    a2, _, _ = _nearest_kx0(op, kz, shift)
    assert abs(a2 - a_ref) <= tol


@pytest.mark.parametrize("kz", [0.0037, 0.03, 0.38, 3.0])
def test_seed_spectrum_keeps_the_qz_seeds(p1_flow, kz):
    op = stability_operator(p1_flow, SEED_N, True)
    p = op.pencil(0.0, kz)
    w, V = pencil_qz(p, True)
    w2, V2 = _seed_spectrum(op, kz, DEFAULT_TRANSVERSE.seed_shift)
    t, t2 = tails(p, V, 10), tails(p, V2, 10)
    a = np.nonzero((t < 1e-4) & (w.imag >= 0) & (np.abs(w) > 1e-5))[0][:4]
    b = np.nonzero((t2 < 1e-4) & (w2.imag >= 0) & (np.abs(w2) > 1e-5))[0][:4]
    assert len(a) == len(b) > 0
    assert np.all(np.abs(w2[b] - w[a]) <= 1e-10 * np.abs(w[a]) + 1e-12)
    assert np.all(np.abs(t2[b] - t[a]) <= 1e-4 * t[a])
