"""The stability operator against Appendix A, and its assembly against the raw equations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.equations import compiled_equations
from chuteflow.errors import ParameterError
from chuteflow.spectral import ChebyshevGrid, MappedChebyshevGrid
from chuteflow.stability import OperatorCache, StabilityOperator, least_stable
from chuteflow.stability.operator import base_on_grid

from .conftest import P1


def appendix_a(flow, y):
    """Appendix A (eq:leqnu … eq:leqT) transcribed literally, in the paper's notation.

    Returns {equation: {(field, a, b, c): coefficient}} for the term
    coefficient × ∂_t^a ∂_x^b ∂_y^c acting on field₁. ξ = ζ − 2μ/3; subscripts ν, T are
    partial derivatives at (ν0, T0); a subscript y is the total derivative d/dy along the
    steady profile, e.g. μ_{ν,y} = μ_νν ν0' + μ_νT T0'.
    """
    b = base_on_grid(flow, y)
    P = flow.model.evaluate(b["nu"], b["T"])
    th = math.radians(flow.theta)
    sin, cos = math.sin(th), math.cos(th)
    nu0, nu0y, u0, u0y, u0yy = b["nu"], b["nu_y"], b["u"], b["u_y"], b["u_yy"]
    T0y, T0yy = b["T_y"], b["T_yy"]

    def F(name, i=0, j=0):
        return P[name][(i, j)]

    def Fy(name, i=0, j=0):  # d/dy of ∂^i_ν ∂^j_T F along the profile
        return F(name, i + 1, j) * nu0y + F(name, i, j + 1) * T0y

    p, mu, kap = F("p"), F("mu"), F("kappa")
    xi = F("zeta") - 2 * mu / 3
    xi_y = Fy("zeta") - 2 * Fy("mu") / 3
    mu_y, kap_y = Fy("mu"), Fy("kappa")
    one = np.ones_like(nu0)
    return {
        # eq:leqnu
        "mass": {
            ("nu", 1, 0, 0): one,
            ("nu", 0, 1, 0): u0,
            ("u", 0, 1, 0): nu0,
            ("v", 0, 0, 0): nu0y,
            ("v", 0, 0, 1): nu0,
        },
        # x-momentum
        "xmom": {
            ("nu", 0, 0, 0): sin + u0yy * F("mu", 1, 0) + u0y * Fy("mu", 1, 0),
            ("nu", 0, 1, 0): -F("p", 1, 0),
            ("nu", 0, 0, 1): u0y * F("mu", 1, 0),
            ("u", 1, 0, 0): -nu0,
            ("u", 0, 1, 0): -nu0 * u0,
            ("u", 0, 2, 0): xi + 2 * mu,
            ("u", 0, 0, 1): mu_y,
            ("u", 0, 0, 2): mu,
            ("v", 0, 0, 0): -nu0 * u0y,
            ("v", 0, 1, 0): mu_y,
            ("v", 0, 1, 1): xi + mu,
            ("T", 0, 1, 0): -F("p", 0, 1),
            ("T", 0, 0, 0): u0yy * F("mu", 0, 1) + u0y * Fy("mu", 0, 1),
            ("T", 0, 0, 1): u0y * F("mu", 0, 1),
        },
        # y-momentum
        "ymom": {
            ("nu", 0, 0, 0): -cos - Fy("p", 1, 0),
            ("nu", 0, 0, 1): -F("p", 1, 0),
            ("nu", 0, 1, 0): u0y * F("mu", 1, 0),
            ("u", 0, 1, 0): xi_y,
            ("u", 0, 1, 1): xi + mu,
            ("v", 1, 0, 0): -nu0,
            ("v", 0, 1, 0): -nu0 * u0,
            ("v", 0, 0, 1): xi_y + 2 * mu_y,
            ("v", 0, 0, 2): xi + 2 * mu,
            ("v", 0, 2, 0): mu,
            ("T", 0, 0, 0): -Fy("p", 0, 1),
            ("T", 0, 0, 1): -F("p", 0, 1),
            ("T", 0, 1, 0): u0y * F("mu", 0, 1),
        },
        # eq:leqT
        "energy": {
            ("nu", 0, 0, 0): Fy("kappa", 1, 0) * T0y
            + F("kappa", 1, 0) * T0yy
            - F("Gamma", 1, 0)
            + u0y**2 * F("mu", 1, 0),
            ("nu", 0, 0, 1): F("kappa", 1, 0) * T0y,
            ("u", 0, 1, 0): -p,
            ("u", 0, 0, 1): 2 * mu * u0y,
            ("v", 0, 0, 0): -1.5 * nu0 * T0y,
            ("v", 0, 0, 1): -p,
            ("v", 0, 1, 0): 2 * mu * u0y,
            ("T", 1, 0, 0): -1.5 * nu0,
            ("T", 0, 1, 0): -1.5 * nu0 * u0,
            ("T", 0, 2, 0): kap,
            ("T", 0, 0, 1): kap_y + F("kappa", 0, 1) * T0y,
            ("T", 0, 0, 2): kap,
            ("T", 0, 0, 0): Fy("kappa", 0, 1) * T0y
            + F("kappa", 0, 1) * T0yy
            - F("Gamma", 0, 1)
            + u0y**2 * F("mu", 0, 1),
        },
    }


def derived(flow, y, name):
    """{(field, a, b, c): coefficient} of one compiled equation (2D terms)."""
    b = base_on_grid(flow, y)
    P = flow.model.evaluate(b["nu"], b["T"])
    th = math.radians(flow.theta)
    ce = compiled_equations()[name]
    _, coefs = ce.evaluate(b, P, math.sin(th), math.cos(th))
    return {
        (t.field, t.a, t.b, t.c): np.broadcast_to(c, y.shape)
        for t, c in zip(ce.terms, coefs)
        if not t.d and t.field != "w"
    }


# the paper writes eq:leqnu as ∂_t ν1 + … = 0; the derived residual is −∂_t ν − ∇·(νu)
SIGN = {"mass": -1.0, "xmom": 1.0, "ymom": 1.0, "energy": 1.0}


@pytest.mark.parametrize("name", ["mass", "xmom", "ymom", "energy"])
def test_bulk_equations_agree_with_appendix_a(p1_flow, name):
    """Every coefficient of eq:leqnu … eq:leqT equals the derived one to round-off."""
    y = ChebyshevGrid(48, 0.0, p1_flow.y_max).y
    paper = appendix_a(p1_flow, y)[name]
    ours = {k: SIGN[name] * v for k, v in derived(p1_flow, y, name).items()}
    assert set(paper) <= set(ours), f"terms missing: {set(paper) - set(ours)}"
    # the derived energy equation has the κ_h∇ν heat flux's terms (ν̂_xx, ν̂_yy, and κ_h's
    # partials), which the paper drops: exactly zero for its closure
    extra = set(ours) - set(paper)
    assert extra == ({("nu", 0, 2, 0), ("nu", 0, 0, 2)} if name == "energy" else set())
    for key in extra:
        assert not np.any(ours[key]), key
    for key in paper:
        scale = np.abs(paper[key]).max()
        # products of O(1) partials: a few ulps of the largest value
        assert np.abs(paper[key] - ours[key]).max() <= 1e-13 * scale, key


def test_floor_conditions_agree_with_eq_bc0u_and_eq_bc0T(p1_flow):
    """eq:bc0u and eq:bc0T from the derived floor rows.

    The paper's forms use the steady floor conditions (u0' = φ f7 u0 and eq:dT0b for T0')
    to simplify, and drop μ ∂_x v1 (zero since v̂(0) = 0). So the derived eq:bc1 row divided
    by μ0, and (eq:bc2 row − u0 × eq:bc1 row) divided by κ0, must equal them up to multiples
    of the steady floor residuals, which are measured here (≲ 1e-10).
    """
    y = np.array([0.0])
    b = base_on_grid(p1_flow, y)
    P = p1_flow.model.evaluate(b["nu"], b["T"])
    m = p1_flow.model
    f = m.f(b["nu"])
    f6, f6n, f7, f7n = (
        float(f["f6"][0][0]),
        float(f["f6"][1][0]),
        float(f["f7"][0][0]),
        float(f["f7"][1][0]),
    )
    phi, Phi = m.roughness, m.wall_loss
    u0, T0, u0y, T0y = (float(b[q][0]) for q in ("u", "T", "u_y", "T_y"))
    mu0, kap0 = float(P["mu"][(0, 0)][0]), float(P["kappa"][(0, 0)][0])
    assert abs(u0y - phi * f7 * u0) < 1e-9 * abs(u0y)
    assert abs(T0y - (0.5 * Phi * f6 * T0 - phi * f6 * u0**2 / 3)) < 1e-9 * T0

    def row(name):
        return {k: float(np.asarray(v).reshape(-1)[0]) for k, v in derived(p1_flow, y, name).items()}

    fx, fe = row("floor_x"), row("floor_energy")
    # eq:bc0u: ∂_y u1 = φ [u0 f7,ν ν1 + f7 u1]
    ours = {k: v / mu0 for k, v in fx.items()}
    paper = {
        ("u", 0, 0, 1): 1.0,
        ("nu", 0, 0, 0): -phi * u0 * f7n,
        ("u", 0, 0, 0): -phi * f7,
        ("T", 0, 0, 0): 0.0,
    }
    assert ours.pop(("v", 0, 1, 0)) == pytest.approx(1.0)  # μ ∂_x v1 / μ, with v̂(0) = 0
    assert set(ours) == set(paper)
    for key, want in paper.items():
        assert ours[key] == pytest.approx(want, rel=1e-8, abs=1e-10), key
    # eq:bc0T: ∂_y T1 = −f6,ν [φu0²/3 − ΦT0/2] ν1 − f6 [2φu0 u1/3 − Φ T1/2]
    comb = {k: (fe.get(k, 0.0) - u0 * fx.get(k, 0.0)) / kap0 for k in set(fe) | set(fx)}
    # −κ_h ∂_y ν1 of the heat flux q = −κ∇T − κ_h∇ν, which the paper drops: zero for its closure
    assert comb.pop(("nu", 0, 0, 1)) == 0.0
    paper = {
        ("T", 0, 0, 1): 1.0,
        ("nu", 0, 0, 0): f6n * (phi * u0**2 / 3 - 0.5 * Phi * T0),
        ("u", 0, 0, 0): 2 * phi * f6 * u0 / 3,
        ("T", 0, 0, 0): -0.5 * Phi * f6,
        ("u", 0, 0, 1): 0.0,
        ("v", 0, 1, 0): 0.0,
    }
    assert set(comb) == set(paper)
    for key, want in paper.items():
        assert comb[key] == pytest.approx(want, rel=1e-8, abs=1e-10), key


@pytest.mark.parametrize("mapped", [True, False])
def test_pencil_solves_the_raw_linearised_equations(p1_flow, mapped):
    """An eigenvector of the assembled pencil satisfies the unscaled compiled equations at
    every interior node, and each boundary condition of §4.1, to round-off: this checks the
    row scaling, the equilibration, the block layout and the boundary rows at once, on the
    default sinh-mapped grid and on the plain Chebyshev grid."""
    k = 2e-3
    mode = least_stable(p1_flow, k, n=64, cache=OperatorCache(2, mapped=mapped))
    y = mode.y
    g = mode.grid
    assert isinstance(g, MappedChebyshevGrid) == mapped
    if not mapped:
        assert np.allclose(g.y, ChebyshevGrid(len(y) - 1, 0.0, p1_flow.y_max).y, rtol=1e-15, atol=1e-13)
    b = base_on_grid(p1_flow, y)
    P = p1_flow.model.evaluate(b["nu"], b["T"])
    th = math.radians(p1_flow.theta)
    D = (np.eye(len(y)), g.D, g.D2)
    F = mode.fields
    for name in ("mass", "xmom", "ymom", "energy", "floor_x", "floor_energy"):
        ce = compiled_equations()[name]
        _, coefs = ce.evaluate(b, P, math.sin(th), math.cos(th))
        total = np.zeros(len(y), complex)
        size = np.zeros(len(y))
        for t, c in zip(ce.terms, coefs):
            if t.field == "w" or t.d:
                continue
            term = np.broadcast_to(c, y.shape) * mode.alpha**t.a * (1j * k) ** t.b * (D[t.c] @ F[t.field])
            total += term
            size = np.maximum(size, np.abs(term))
        where = slice(1, -1) if name in ("mass", "xmom", "ymom", "energy") else slice(0, 1)
        assert (np.abs(total[where]) <= 1e-8 * size[where].max()).all(), name
    # y-momentum at the floor (extra condition); top conditions of §4.1
    cos = math.cos(th)
    # floor_v: a row with coefficient 1 in a pencil of norm ~1e4 carries a normwise
    # backward error ~1e-16 × 1e4 of the eigen-solver
    assert abs(F["v"][0]) < 1e-10 * np.abs(F["v"]).max()
    top = {f: (g.D @ F[f])[-1] for f in F}
    for f in ("u", "v", "T"):
        assert abs(top[f] + k * F[f][-1]) < 1e-9 * np.abs(g.D @ F[f]).max()
    assert abs(top["nu"] + cos / b["T"][-1] * F["nu"][-1]) < 1e-9 * np.abs(g.D @ F["nu"]).max()


def test_k_expansion_pieces_rebuild_the_operator(p1_flow):
    op = StabilityOperator(p1_flow, 40)
    A0, A1, A2 = op.series()
    assert np.isrealobj(A0)
    for k in (0.0, 3e-3, 0.2):
        A = op.matrix(k)
        assert np.allclose(A0 + 1j * k * A1 + (1j * k) ** 2 * A2, A, rtol=0, atol=1e-12 * np.abs(A).max())
    B = np.diag(op.B)
    m = op.n + 1
    assert np.count_nonzero(op.B - np.diag(B)) == 0  # diagonal
    boundary = np.zeros(op.size, bool)
    boundary[0::m] = boundary[m - 1 :: m] = True
    assert (B[boundary] == 0).all()
    assert (B[~boundary] > 0).all()
    assert np.allclose(B[1 : m - 1], 1.0)  # mass rows: ∂_t ν̂ with coefficient 1


def test_series_products_are_the_series_times_a_vector(p1_flow):
    """series_products (the long-wave theory's P1 x, P2 x from the real pieces and K's
    entries) equals i A1 x and −A2 x of series() to round-off, for real and complex x."""
    op = StabilityOperator(p1_flow, 40, mapped=True)
    A0, A1, A2 = op.series()
    B0, p1, p2 = op.series_products()
    assert np.array_equal(A0, B0)
    rng = np.random.default_rng(7)
    for x in (rng.standard_normal(op.size), rng.standard_normal(op.size) + 1j * rng.standard_normal(op.size)):
        for P, p in ((1j * A1, p1), (-A2, p2)):
            ref = P @ x
            assert np.abs(p(x) - ref).max() <= 1e-14 * np.abs(P).sum(axis=1).max() * np.abs(x).max()


def test_three_dimensional_operator_reduces_at_kz_zero(p1_flow):
    """With ŵ and z-momentum added, kz = 0 leaves the 2D eigenvalue unchanged (same mapped
    grid as the solvers' 2D operators); an oblique
    wavevector is accepted (3D perturbations need no rewrite)."""
    k = 2e-3
    two = least_stable(p1_flow, k, n=64)
    op3 = StabilityOperator(p1_flow, 64, three_d=True, mapped=True)  # the grid of least_stable
    from chuteflow.stability.modes import nearest_eigenpair

    a3, _ = nearest_eigenpair(op3.pencil(k, 0.0), two.alpha)
    assert abs(a3 - two.alpha) < 1e-10
    a_obl, _ = nearest_eigenpair(op3.pencil(k, 1e-4), two.alpha)
    assert abs(a_obl - two.alpha) < 1e-4  # continuous in kz


def test_operator_rejects_bad_input(p1_flow):
    with pytest.raises(ParameterError, match="n = 4"):
        StabilityOperator(p1_flow, 4)
    op = StabilityOperator(p1_flow, 24)
    with pytest.raises(ParameterError, match="k = -1"):
        op.matrix(-1.0)
    with pytest.raises(ParameterError, match="three_d"):
        op.matrix(1e-3, 1e-3)
    with pytest.raises(ParameterError, match="SteadyFlow"):
        StabilityOperator(object(), 40)


def test_p1_reference_values(p1_flow):
    """Guard that the shared fixture is the flow the checkpoints refer to (steady-stage
    reference values; the steady solver's own tests pin them tighter)."""
    assert P1 == (16.0, 0.05)
    assert p1_flow.u_floor == pytest.approx(8.194533212, rel=1e-8)
    assert p1_flow.rho_bar == pytest.approx(0.26388215, rel=1e-6)
