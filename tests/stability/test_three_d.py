"""The three-dimensional operator (issue 10): perturbations exp(αt + i k_x x + i k_z z).

Identities checked: k_z = 0 reproduces the 2D operator and its eigenvalues and ŵ decouples;
α(k_x, −k_z) = α(k_x, k_z); at k_x = 0 the pencil is real (after ŵ → iŵ), so eigenvalues are
real or conjugate pairs; the k = 0 null vector ∂X0/∂β (Appendix B, eq:last) is annihilated;
the floor rows of ŵ are the z component of eq:bc1 in the issue's vector form
−(n·Σ)_t = η* u_s, i.e. μ0(ŵ' + i k_z v̂) = η* ŵ at y = 0. Numbers were measured with this
code at P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05).
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.longwave.theory import tangent_vector
from chuteflow.stability import StabilityOperator, null_vectors, qz
from chuteflow.stability.policy import RejectionPolicy
from chuteflow.stability.realform import real_form
from chuteflow.stability.transverse import least_stable_3d
from chuteflow.steady import steady_tangent

N = 40


@pytest.fixture(scope="module")
def ops(p1_flow):
    return StabilityOperator(p1_flow, N), StabilityOperator(p1_flow, N, three_d=True)


def _blocks(op):
    m = N + 1
    return {f: slice(i * m, (i + 1) * m) for i, f in enumerate(op.fields)}


def test_kz0_reproduces_2d_operator_and_w_decouples(ops):
    op2, op3 = ops
    b = _blocks(op3)
    keep = np.r_[b["nu"], b["u"], b["v"], b["T"]]
    for kx in (0.0, 0.01, 0.7):
        A2, A3 = op2.matrix(kx), op3.matrix(kx, 0.0)
        assert np.array_equal(A3[np.ix_(keep, keep)], A2)
        assert not A3[np.ix_(keep, np.r_[b["w"]])].any()
        assert not A3[np.ix_(np.r_[b["w"]], keep)].any()
    assert np.array_equal(op3.B[np.ix_(keep, keep)], op2.B)


def test_kz0_eigenvalues_are_the_2d_ones(ops):
    """Every 2D eigenvalue is one of the 3D pencil's at k_z = 0 (the extra ones are ŵ's).
    QZ of the two pencils differs by round-off in the clustered continuum: measured 5e-11
    relative."""
    op2, op3 = ops
    w2, _ = qz(*op2.pencil(0.01).equilibrated(), vectors=False)
    w3, _ = qz(*op3.pencil(0.01, 0.0).equilibrated(), vectors=False)
    assert len(w3) > len(w2)
    for a in w2:
        assert np.abs(w3 - a).min() <= 1e-9 * max(1.0, abs(a))


def test_alpha_even_in_kz(ops, p1_flow):
    """A(k_x, −k_z) = S A(k_x, k_z) S with S = −1 on ŵ (z → −z), hence α(k_x, −k_z) = α(k_x, k_z)."""
    _, op3 = ops
    s = np.ones(op3.size)
    s[_blocks(op3)["w"]] = -1.0
    for kx, kz in ((0.0, 0.3), (0.02, 0.05), (1.0, 2.0)):
        Ap, Am = op3.matrix(kx, kz), op3.matrix(kx, -kz)
        assert np.array_equal(Am, s[:, None] * Ap * s[None, :])
    policy = RejectionPolicy(n_start=48, n_max=60)
    a = least_stable_3d(p1_flow, 0.02, 0.05, policy=policy).alpha
    b = least_stable_3d(p1_flow, 0.02, -0.05, policy=policy).alpha
    assert abs(a - b) <= 1e-10 * abs(a)


def test_kx0_problem_is_real(ops):
    """At k_x = 0 every (ik_z)^odd term couples ŵ to another field, so ŵ → iŵ makes the pencil
    real: eigenvalues real or in conjugate pairs."""
    _, op3 = ops
    p = op3.pencil(0.0, 0.4)
    A, B, _ = real_form(p)
    assert A.dtype == float
    w, _ = qz(*p.equilibrated(), vectors=False)
    w = w[np.abs(w) < 1e4]
    for a in w:
        assert np.abs(w - np.conj(a)).min() <= 1e-8 * max(1.0, abs(a))


def test_k0_null_vector_is_annihilated(ops, p1_flow):
    """A(0, 0) ∂X0/∂β = 0 (Appendix B): the relative residual is the same as in 2D (5.8e-11
    at N = 40, set by the steady family's ν_top); the computed null vector has ŵ = 0."""
    op2, op3 = ops
    tg = steady_tangent(p1_flow)
    V3, V2 = tangent_vector(op3, tg), tangent_vector(op2, tg)
    A3, A2 = op3.matrix(0.0, 0.0), op2.matrix(0.0)
    r3 = np.abs(A3 @ V3).max() / (np.abs(A3).max() * np.abs(V3).max())
    r2 = np.abs(A2 @ V2).max() / (np.abs(A2).max() * np.abs(V2).max())
    assert r3 < 1e-9
    assert r3 == pytest.approx(r2, rel=1e-3)
    nv = null_vectors(op3)
    assert abs(nv.alpha0) < 1e-8
    assert np.abs(op3.pencil(0.0, 0.0).split(nv.right)["w"]).max() < 1e-12


def test_floor_rows_of_w_are_the_spanwise_stress_balance(ops, p1_flow):
    """Row of ŵ at y = 0, divided by μ0(0): ŵ'(0) − (η*/μ0) ŵ(0) + i k_z v̂(0) = 0, from
    −Σ_yz = η* w with Σ_yz = −μ(∂_y w + ∂_z v); no ν̂, û, T̂ terms (w0 = Σ_yz0 = 0). The floor
    energy row has no ŵ term (u_s·Σ·n is linear in w only through w0 Σ_zy0 = 0)."""
    _, op3 = ops
    b = _blocks(op3)
    r = b["w"].start
    part = p1_flow.model.evaluate(op3.base["nu"], op3.base["T"])
    mu0 = part["mu"][(0, 0)][0]
    eta0 = np.broadcast_to(part["eta_star"][(0, 0)], op3.base["nu"].shape)[0]
    expect = op3.grid.D[0].copy()
    expect[0] -= eta0 / mu0
    P00, P01 = op3.pieces[(0, 0)], op3.pieces[(0, 1)]
    assert np.allclose(P00[r, b["w"]], expect, rtol=1e-12, atol=1e-12 * np.abs(expect).max())
    e0 = np.zeros(N + 1)
    e0[0] = 1.0
    assert np.allclose(P01[r, b["v"]], e0, rtol=1e-12, atol=1e-14)
    for key, P in op3.pieces.items():
        for f in ("nu", "u", "T"):
            assert not P[r, b[f]].any(), (key, f)
        if key != (0, 1):
            assert not P[r, b["v"]].any(), key
        assert not P[b["T"].start, b["w"]].any(), key
    assert not op3.K[r, :].any()
    # top: ŵ' + |k| ŵ = 0
    top = b["w"].stop - 1
    assert np.array_equal(op3.K[top, b["w"]], e0[::-1])
