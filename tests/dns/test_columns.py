"""Tests of the column preconditioner of the nonlinear phase (docs/dns.md, *Solver*).

References: the per-mode linearisation :meth:`Discretisation.linear_blocks` (built from
:func:`chuteflow.equations.compiled_equations`, itself checked against the finite-difference
Jacobian in test_dns.py) for the coefficients, the algebraic identity P⁻¹ P = 1 for the
factorisations (the periodic block-tridiagonal LU against a dense solve), and the step of the
x-mean preconditioner for the Newton solution.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sps

from chuteflow.closures import ChuteModel
from chuteflow.dns import Discretisation, Stepper, cyclic
from chuteflow.dns.columns import ColumnPreconditioner, column_blocks, column_coefficients, column_matrix
from chuteflow.dns.cyclic import CyclicBlockLU
from chuteflow.dns.discretisation import BDF2
from chuteflow.dns.stepper import NewtonSettings
from chuteflow.steady import solve_steady

MODEL = ChuteModel(roughness=0.05)


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, MODEL)


def _steady(d, flow):
    p = flow.profiles(d.grid.y)
    C = np.zeros(d.shape, complex)
    C[0, :, 0], C[1, :, 0], C[3, :, 0] = np.log(p["nu"]), p["u"], p["T"]
    return C


def _wave(d, flow, amplitude):
    """The steady flow with a density wave in modes 1 and 2 (and its small velocity)."""
    C = _steady(d, flow)
    C[0, :, 1] += amplitude * (1 + 0.5j)
    C[0, :, 2] += 0.3 * amplitude * (0.2 - 1j)
    C[2, 1:, 1] += 0.1 * amplitude * d.grid.y[1:] / d.y_max
    return C


def test_column_matrix_at_uniform_state_is_the_mode_jacobian(p1):
    """At an x-independent state the column matrix with exact y-derivatives is diagonal in
    the modes, and its block of mode m is the per-mode Jacobian (linear_blocks) with
    ik → i sin(kh)/h and (ik)² → −(2 − 2cos kh)/h² (central differences), |k| of the top rows
    by its circulant's three middle diagonals, h_0 + 2 h_1 cos kh."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 20, 2, frame=7.8)
    C = _steady(d, p1)
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    dt = 3.0
    coefs = column_coefficients(d, C, hist, dt, BDF2)
    J = column_matrix(d, coefs, y="chebyshev", x="central")
    P = ColumnPreconditioner(d, column_blocks(d, coefs, y="chebyshev", x="central"), "cyclic")
    blocks = d.linear_blocks(C)
    m, nx = d.n + 1, 2 * d.modes + 1
    h = d.length / nx
    circ = np.fft.irfft(np.abs(d.k), n=nx)
    for mode in (1, 2):
        k = d.k[mode]
        d1 = 1j * math.sin(k * h) / h
        d2 = -(2 - 2 * math.cos(k * h)) / h**2
        ref = (
            blocks["K"] * (circ[0] + 2 * circ[1] * math.cos(k * h))
            + blocks["Bt"] * (1.5 / dt - d.frame * d1)
            + blocks["pieces"].get(0, 0)
            + d1 * blocks["pieces"].get(1, 0)
            + d2 * blocks["pieces"].get(2, 0)
        )
        for j in range(0, 4 * m, 5):
            V = np.zeros(d.shape, complex)
            V[j // m, j % m, mode] = 1.0
            out = P.to_modes(J @ P.to_points(V))
            # nothing leaks into the other modes
            others = np.delete(out, mode, axis=-1)
            scale = np.abs(ref[:, j]).max()
            assert np.abs(others).max() <= 1e-9 * scale
            # one-sided differences of step 1e-7 × max|jet| in the coefficients; the density
            # top row drops the O(ν(y_max)) term of the linear problem's condition (test_dns)
            assert np.abs(out[:, :, mode].ravel() - ref[:, j]).max() <= 1e-5 * scale + 1e-6, (mode, j)


def test_upwind_transport_is_the_central_matrix_plus_its_dissipation(p1):
    """``x="upwind"`` (the default) adds to the central matrix, in each row's transport of its
    own field a ∂_x f, the dissipation that makes it (f_i − f_{i∓1})/h from upstream: on mode
    m at an x-independent state, sign(τ) |a| (1 − cos kh)/h on the diagonal of that field's
    rows, τ the row's coefficient of ∂_t f. The time coefficients are checked against the
    per-mode linearisation's (linear_blocks' Bt, built from the compiled equations: an
    independent derivation), nonzero in the bulk rows and zero in the wall rows; the
    dissipation is nowhere else (the other fields, the top conditions of u, v, T)."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 20, 2, frame=7.8)
    C = _steady(d, p1)
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    coefs = column_coefficients(d, C, hist, 3.0, BDF2)
    m, nx = d.n + 1, 2 * d.modes + 1
    h = d.length / nx
    Bt = np.diag(d.linear_blocks(C)["Bt"]).reshape(4, m)
    for r, f in enumerate(("s", "u", "v", "T")):
        tau = coefs[f + "_t"][r]  # (m, nx), x-independent here
        assert np.allclose(tau, tau[:, :1], rtol=0, atol=1e-9 * np.abs(tau).max())
        bulk = slice(1, m - 1)
        assert np.allclose(tau[bulk, 0], Bt[r, bulk], rtol=1e-5, atol=1e-9 * np.abs(Bt[r]).max()), f
        assert abs(tau[0, 0]) <= 1e-8 * np.abs(tau).max()  # the wall rows: conditions
    up = column_matrix(d, coefs, y="chebyshev", x="upwind")
    central = column_matrix(d, coefs, y="chebyshev", x="central")
    P = ColumnPreconditioner(d, column_blocks(d, coefs, x="central"), "cyclic")
    for mode in (1, 2):
        k = d.k[mode]
        for r, f in enumerate(("s", "u", "v", "T")):
            a, tau = coefs[f + "_x"][r][:, 0], coefs[f + "_t"][r][:, 0]
            big = np.abs(tau).max()
            side = np.where(np.abs(tau) > 1e-8 * big, np.sign(tau), 0.0)
            expect = side * np.abs(a) * (1 - math.cos(k * h)) / h
            if r > 0:
                expect[-1] = 0.0  # the top rows of u, v, T
            for j in (0, 1, m // 2, m - 2, m - 1):
                V = np.zeros(d.shape, complex)
                V[r, j, mode] = 1.0
                diff = P.to_modes((up - central) @ P.to_points(V))
                want = np.zeros(d.shape, complex)
                want[r, j, mode] = expect[j]
                scale = max(abs(expect).max(), 1e-300)
                assert np.abs(diff - want).max() <= 1e-9 * scale, (mode, f, j)
    with pytest.raises(ValueError, match="column_x = 'spectral'"):
        NewtonSettings(column_x="spectral")
    with pytest.raises(ValueError, match="needs the coefficients of s_t"):
        column_blocks(d, {k: v for k, v in coefs.items() if not k.endswith("_t")})


@pytest.mark.parametrize(("order", "y"), [(2, "fd"), (2, "chebyshev"), (4, "fd")])
def test_column_preconditioner_is_the_inverse_of_its_matrix(p1, order, y):
    """apply(R) solves the assembled matrix exactly (to round-off) at a finite-amplitude state:
    by the periodic block-tridiagonal LU (order 2) and by the sparse LU (order 4)."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 16, 4, frame=7.8)
    C = _wave(d, p1, 0.2)
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    P = ColumnPreconditioner.build(d, C, hist, 4.0, BDF2, order, y)
    assert isinstance(P._lu, CyclicBlockLU) == (order == 2 and y == "chebyshev")
    J = column_matrix(d, column_coefficients(d, C, hist, 4.0, BDF2), order, y)
    rng = np.random.default_rng(1)
    R = rng.normal(size=d.shape) + 1j * rng.normal(size=d.shape)
    R[..., 0] = R[..., 0].real
    x = P.apply(R)
    lhs = J @ P.to_points(x)
    rhs = P.to_points(R)
    assert np.abs(lhs - rhs).max() <= 1e-9 * np.abs(rhs).max()
    assert P.nbytes > 0
    # and the points ↔ modes maps are inverse to each other
    assert np.allclose(P.to_modes(P.to_points(R)), R, rtol=0, atol=1e-13)


def test_the_column_matrix_in_y_is_the_finite_difference_one(p1):
    """``y="fd"`` replaces the Chebyshev matrices by fd_matrices and nothing else: the two
    matrices differ by the coefficients times (D_fd − D) — checked on a field quadratic in y,
    where both derivatives are exact, so the two matrices agree on it to round-off — and
    the finite-difference matrix is sparse in y (a banded block per x point)."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 20, 3, frame=7.8)
    C = _wave(d, p1, 0.2)
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    coefs = column_coefficients(d, C, hist, 4.0, BDF2)
    fd, cheb = column_matrix(d, coefs, y="fd"), column_matrix(d, coefs, y="chebyshev")
    y = d.grid.y
    V = np.zeros(d.shape, complex)
    V[1, :, 1] = 0.3 - 0.1 * y + 0.02 * y**2  # u, mode 1: a quadratic in y
    V[3, :, 0] = 1.0 + 0.05 * y**2  # T, mode 0
    P = ColumnPreconditioner(d, column_blocks(d, coefs, y="chebyshev"))
    a, b = fd @ P.to_points(V), cheb @ P.to_points(V)
    assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    assert fd.nnz < 0.3 * cheb.nnz
    with pytest.raises(ValueError, match="column_y"):
        NewtonSettings(column_y="spline")


def test_the_two_factorisations_give_the_same_correction(p1):
    """The block-tridiagonal and the sparse LU of the same blocks (finite differences in y,
    a ±20 % wave) apply the same inverse to round-off; a wrong choice is a one-line error."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 16, 4, frame=7.8)
    C = _wave(d, p1, 0.2)
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    blocks = column_blocks(d, column_coefficients(d, C, hist, 4.0, BDF2))
    R = np.random.default_rng(2).normal(size=d.shape) + 0j
    a = ColumnPreconditioner(d, blocks, "cyclic").apply(R)
    b = ColumnPreconditioner(d, blocks, "sparse").apply(R)
    assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max()
    with pytest.raises(ValueError, match="factorisation = 'lu'"):
        ColumnPreconditioner(d, blocks, "lu")
    with pytest.raises(ValueError, match="three blocks per point"):
        ColumnPreconditioner(d, column_blocks(d, column_coefficients(d, C, hist, 4.0, BDF2), 4), "cyclic")


def _cyclic(rng, n, b, coupling, sparse=False):
    """Random periodic block-tridiagonal blocks, diagonally dominant, and the dense matrix;
    ``sparse``: couplings as the columns' (the diagonal, a dense sub-block and a dense row:
    a quarter nonzero at b = 16)."""
    D = rng.normal(size=(n, b, b)) + 4 * b**0.5 * np.eye(b)
    lower, upper = coupling * rng.normal(size=(2, n, b, b))
    if sparse:
        keep = np.eye(b, dtype=bool)
        keep[: b // 4, b // 2 :] = True
        keep[b // 2, :] = True  # a dense row, as the top conditions
        lower, upper = lower * keep, upper * keep
    A = np.zeros((n * b, n * b))
    for i in range(n):
        for o, blk in ((0, D), (-1, lower), (1, upper)):
            j = (i + o) % n
            A[i * b : (i + 1) * b, j * b : (j + 1) * b] += blk[i]
    return D, lower, upper, A


@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 40])
def test_cyclic_block_lu_solves_the_periodic_matrix(n, sparse):
    """CyclicBlockLU against a dense solve (LAPACK): every n from the degenerate ones (the
    offsets coincide for n ≤ 2) to one long enough that the border's fill is dropped; with
    couplings dense and sparse (kept in CSR form below ``cyclic.SPARSE_BELOW``)."""
    rng = np.random.default_rng(n)
    b = 16 if sparse else 6
    D, lower, upper, A = _cyclic(rng, n, b, 1.0, sparse)
    lu = CyclicBlockLU(D, lower, upper)
    if n > 2:
        assert all(sps.issparse(blk) == sparse for blk in lu._lower)
    rhs = rng.normal(size=n * b)
    x = lu.solve(rhs)
    assert np.abs(x - np.linalg.solve(A, rhs)).max() <= 1e-12 * np.abs(x).max()
    assert lu.nbytes > 0


def test_cyclic_block_lu_drops_only_negligible_border_blocks(monkeypatch):
    """The periodic corner's fill decays along x; blocks below BORDER_DROP of the largest are
    dropped (fewer kept than there are rows), and the solve moves by less than BORDER_DROP
    relative to keeping them all."""
    rng = np.random.default_rng(3)
    D, lower, upper, A = _cyclic(rng, 60, 5, 0.5)
    rhs = rng.normal(size=60 * 5)
    lu = CyclicBlockLU(D, lower, upper)
    assert 2 <= len(lu._rows_r) < 59
    assert 2 <= len(lu._rows_b) < 59
    drop = cyclic.BORDER_DROP
    monkeypatch.setattr(cyclic, "BORDER_DROP", 0.0)
    full = CyclicBlockLU(D, lower, upper)
    assert len(full._rows_r) == 59
    x, y = lu.solve(rhs), full.solve(rhs)
    assert np.abs(y - np.linalg.solve(A, rhs)).max() <= 1e-13 * np.abs(y).max()
    assert np.abs(x - y).max() <= drop * np.abs(y).max()


def test_bad_column_settings_name_the_parameter_and_the_choices():
    """A one-line error naming the parameter and what it may be (the guide's bad input)."""
    with pytest.raises(ValueError, match=r"column_order = 3: choose 2 or 4 \(the order"):
        NewtonSettings(column_order=3)
    assert NewtonSettings().columns_nx_limit == 257
    assert NewtonSettings(column_y="fd").columns_nx_limit == 257
    assert NewtonSettings(columns_max_nx=65).columns_nx_limit == 65


@pytest.mark.parametrize("column_y", ["fd", "chebyshev"])
def test_newton_with_columns_reaches_the_same_steps(p1, column_y):
    """Three BDF2 steps at a ±20 % wave: the column (y-derivatives either way) and the x-mean
    preconditioners give the same solution to the Newton tolerance (max-norm of the scaled
    residual 1e-10)."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 24, 6, frame=7.8)
    C0 = _wave(d, p1, 0.1)
    out = {}
    for name in ("mean", "columns"):
        st = Stepper(d, NewtonSettings(preconditioner=name, column_y=column_y))
        C, hist_first = C0.copy(), True
        hist = (st.physical(C), st.physical(C))
        krylov = []
        for _ in range(3):
            C_new, info = st.step(C, hist, 4.0, first=hist_first)
            assert info.residual < 1e-10
            krylov.append(info.krylov)
            hist = (st.physical(C_new), hist[0])
            C, hist_first = C_new, False
        out[name] = (C, krylov)
    diff = np.abs(out["mean"][0] - out["columns"][0]).max()
    # the residual's tolerance 1e-10 on rows of unit scale: solutions agree to ~1e-9
    assert diff <= 1e-8, diff
    assert np.abs(out["mean"][0] - C0).max() > 1e-4  # the steps did move the wave


def test_auto_switches_to_columns(p1):
    """``"auto"`` starts with the x-mean preconditioner and changes to the columns once a
    GMRES solve needs more than ``switch_krylov`` iterations."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 24, 6, frame=7.8)
    C = _wave(d, p1, 0.1)
    st = Stepper(d, NewtonSettings(switch_krylov=0))
    assert not st.columns
    hist = (st.physical(C), st.physical(C))
    st.step(C, hist, 4.0, first=True)
    assert st.columns
    with pytest.raises(ValueError, match="preconditioner"):
        NewtonSettings(preconditioner="ilu")


def test_a_grid_too_fine_for_the_columns_takes_the_coupled_blocks(p1):
    """``NewtonSettings.columns_max_nx``: the column factors grow with nx (the block LU of
    the Chebyshev blocks at P5's mapped bore, N = 96: 0.66 GB at nx = 129, 1.28 GB at 257;
    the general sparse LU of the same matrix filled 2.2 GB at 129, and a run refined to 513
    on it was killed at 24 GB); the default limit is 257. On a finer grid ``"auto"`` goes
    over to the coupled blocks where it would take the columns, ``"columns"`` starts with
    them, and the coupled blocks stay; the step still converges."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 24, 6, frame=7.8)  # nx = 13
    C = _wave(d, p1, 0.1)
    st = Stepper(d, NewtonSettings(switch_krylov=0, columns_max_nx=11))
    assert not st.columns_fit
    hist = (st.physical(C), st.physical(C))
    _, info = st.step(C, hist, 4.0, first=True)
    assert st.kind == "coupled"
    assert info.residual < 1e-10
    assert Stepper(d, NewtonSettings(preconditioner="columns", columns_max_nx=11)).kind == "coupled"
    assert Stepper(d, NewtonSettings(preconditioner="columns", columns_max_nx=13)).kind == "columns"
    coupled = NewtonSettings(preconditioner="coupled", coupled_krylov=0, switch_krylov=0, columns_max_nx=11)
    st = Stepper(d, coupled)
    st.step(C, hist, 4.0, first=True)
    assert st.kind == "coupled"
    assert NewtonSettings().columns_nx_limit == 257
    assert NewtonSettings(column_y="fd", columns_max_nx=65).columns_nx_limit == 65
    with pytest.raises(ValueError, match="columns_max_nx"):
        NewtonSettings(columns_max_nx=0)
