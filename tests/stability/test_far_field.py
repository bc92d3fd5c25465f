"""The operator's top rows derived from :func:`chuteflow.equations.far_field_conditions`
against the hand-written rows they replace, and eigenvalues unchanged.

Before the derivation, the operator wrote the §4.1 top conditions (eq. (4.5):
û' = −kû, v̂' = −kv̂, T̂' = −kT̂, and ν̂' = −(cos θ/T0) ν̂) into its matrices by hand;
:func:`old_top_rows` keeps that code as the reference.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.equations import TOP_OF
from chuteflow.stability import (
    OperatorCache,
    RejectionPolicy,
    StabilityOperator,
    equation_terms,
    least_stable,
)
from chuteflow.stability.modes import nearest_eigenpair


def old_top_rows(op):
    """(pieces[(0, 0)] top rows, K) as the operator wrote them by hand (commit f630553)."""
    m, M = op.n + 1, op.size
    g = op.grid
    cos = math.cos(math.radians(op.flow.theta))
    P = np.zeros((M, M))
    K = np.zeros((M, M))
    col = {f: slice(i * m, (i + 1) * m) for i, f in enumerate(op.fields)}
    for i, f in enumerate(op.fields):
        top = i * m + m - 1
        P[top, col[f]] = g.D[-1]
        if f == "nu":  # ν̂ ∝ ν0 in the isothermal dilute top: ν̂' = −(cos θ/T0) ν̂
            P[top, top] += cos / op.base["T"][-1]
        else:
            K[top, top] = 1.0
    return P, K


@pytest.mark.parametrize("three_d", [False, True])
def test_top_rows_equal_hand_written(p1_flow, three_d):
    """Bit for bit: the derived coefficients are 1, |k| and cos θ/T0 exactly as written."""
    op = StabilityOperator(p1_flow, 40, three_d=three_d)
    m = op.n + 1
    tops = [i * m + m - 1 for i in range(len(op.fields))]
    P, K = old_top_rows(op)
    assert np.array_equal(op.pieces[(0, 0)][tops], P[tops])
    for key, piece in op.pieces.items():
        if key != (0, 0):
            assert not piece[tops].any(), key
    assert np.array_equal(op.K, K)  # K holds nothing but the top conditions
    assert np.count_nonzero(op.K) == len(op.fields) - 1


def _hand_written_operator(op):
    """A copy of ``op`` whose top rows are rebuilt by :func:`old_top_rows`."""
    P, K = old_top_rows(op)
    m = op.n + 1
    tops = [i * m + m - 1 for i in range(len(op.fields))]
    old = StabilityOperator.__new__(StabilityOperator)
    old.__dict__.update(op.__dict__)
    old.pieces = {key: piece.copy() for key, piece in op.pieces.items()}
    for piece in old.pieces.values():
        piece[tops] = 0.0
    old.pieces[(0, 0)][tops] = P[tops]
    nz = np.nonzero(K)
    r, c = op.row_eq[:, None], op.col_eq[None, :]
    old._pieces_eq = {key: piece * r * c for key, piece in old.pieces.items()}
    old._K_eq = (nz[0], nz[1], (K * r * c)[nz])
    old._K_sparse = (nz[0], nz[1], K[nz])
    return old


@pytest.mark.parametrize(("kx", "kz"), [(2e-3, 0.0), (0.02, 0.0), (2e-3, 1e-3), (0.0, 5e-3)])
def test_eigenvalues_unchanged(p1_flow, kx, kz):
    """The least-stable eigenvalue of the derived and of the hand-written operator agree to
    round-off, in 2D and for oblique wavevectors (|k| = √(k_x² + k_z²))."""
    op = StabilityOperator(p1_flow, 64, three_d=True)
    old = _hand_written_operator(op)
    for eq in (False, True):
        assert np.array_equal(op.matrix(kx, kz, equilibrated=eq), old.matrix(kx, kz, equilibrated=eq))
    guess = -7.5j * math.hypot(kx, kz)  # the branch's phase velocity ≈ 7.5 (P1)
    a_new, _ = nearest_eigenpair(op.pencil(kx, kz), guess)
    a_old, _ = nearest_eigenpair(old.pencil(kx, kz), guess)
    assert abs(a_new - a_old) <= 1e-12 * max(abs(a_old), 1e-3)


def test_eigenvalues_pinned_before_derivation(p1_flow):
    """α of P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05) at adaptive N, as computed with the
    hand-written top rows and steady x-momentum rows (commit f630553) on the plain Chebyshev
    grid; the derivation moves them by round-off only (measured ≤ 3e-12). The same
    discretisation and ladder (from N = 80) are used here; the default mapped grid
    differs from it by the plain grid's discretisation error at N = 80 (~2e-10)."""
    plain, old_ladder = OperatorCache(mapped=False), RejectionPolicy(n_start=80)
    before = {
        1e-3: 0.0009447314691881007 - 0.007047900698229443j,
        2e-3: 0.0011789671835718402 - 0.014999339430787921j,
        2e-2: -0.007043233311927519 - 0.15526975574875104j,
    }
    for k, alpha in before.items():
        assert abs(least_stable(p1_flow, k, policy=old_ladder, cache=plain).alpha - alpha) < 1e-10, k


def test_equation_terms_solve_the_mass_balance(p1_flow):
    """The terms of the derived mass balance applied to an eigenmode sum to zero at the
    interior nodes, and the top condition's terms vanish at y_max."""
    mode = least_stable(p1_flow, 2e-3, n=64)
    terms = equation_terms(p1_flow, "mass", mode.fields, mode.k, mode.kz, mode.alpha)
    total = sum(v for _, v in terms)
    size = np.max([np.abs(v) for _, v in terms], axis=0)
    assert (np.abs(total[1:-1]) <= 1e-8 * size[1:-1].max()).all()
    for f in ("nu", "u", "v", "T"):
        terms = equation_terms(p1_flow, TOP_OF[f], mode.fields, mode.k)
        top = sum(v for _, v in terms)[-1]
        # as in test_operator: relative to the largest derivative term over the layer
        scale = max(np.abs(v).max() for t, v in terms if t.c)
        assert abs(top) <= 1e-9 * scale, f
