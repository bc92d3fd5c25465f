"""The first-order cooling rate ζ_U ∇·u of Garzó & Dufty (1999) (energy sink Γ + Γ_U ∇·u,
Γ_U = (3/2) ν T ζ_U; chuteflow.closures.garzo_dufty): where the one statement in
chuteflow.equations puts it, its limits, and the identities of the stability operator with
it (those of tests/stability/test_three_d.py). Its values against MFiX's
CALC_GD_99_ENERGY_DISSIPATION_SS are in test_garzo_dufty_mfix.py.

With Γ_U = 0 (``lun``, ``lun_full``) every number is unchanged bit for bit: checked when the
term was added (2026-12-05) at P1 (θ = 16°, ν0(0) = 0.05) for h, least_stable at k = 0.002,
0.05 and (k_x, k_z) = (0.05, 0.03), the 3D operator's arrays (N = 60) and the DNS residuals;
here the energy coefficients are checked to carry nothing of it.
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow import ChuteModel, solve_steady
from chuteflow.equations import compiled_equations
from chuteflow.longwave.theory import tangent_vector
from chuteflow.stability import StabilityOperator
from chuteflow.steady import steady_tangent

NAMES = ("nu", "nu_y", "nu_yy", "u", "u_y", "u_yy", "T", "T_y", "T_yy")
VALUES = (0.3, -0.02, 0.003, 5.0, 0.2, -0.01, 2.0, -0.05, 0.004)
#: ∇·u = u_x + v_y + w_z: the jets (field, a, b, c, d) of its terms
DIV = (("u", 0, 1, 0, 0), ("v", 0, 0, 1, 0), ("w", 0, 0, 0, 1))


def _energy(part):
    base = {b: np.array([v]) for b, v in zip(NAMES, VALUES)}
    ce = compiled_equations()["energy"]
    res, coefs = ce.evaluate(base, part, 0.27, 0.96)
    return float(np.ravel(res)[0]), {
        (t.field, t.a, t.b, t.c, t.d): float(np.ravel(c)[0]) for t, c in zip(ce.terms, coefs)
    }


@pytest.mark.parametrize("transport", ["lun", "lun_full", "garzo_dufty", "garzo_dufty_mfix"])
def test_energy_equation_carries_gamma_u(transport):
    """−Γ_U ∇·u: the energy coefficients of u_x, v_y, w_z move by −Γ_U and nothing else
    moves (the residual at a state uniform along the slope has ∇·u = 0)."""
    nu, T = np.array([VALUES[0]]), np.array([VALUES[6]])
    part = ChuteModel(transport=transport).evaluate(nu, T)
    gu = float(part["Gamma_U"][(0, 0)][0])
    assert (gu == 0.0) == (transport in ("lun", "lun_full"))
    without = dict(part, Gamma_U={o: np.zeros_like(v) for o, v in part["Gamma_U"].items()})
    r1, c1 = _energy(part)
    r0, c0 = _energy(without)
    assert r1 == r0
    assert set(c1) == set(c0)
    for key in c1:
        want = c0[key] - gu if key in DIV else c0[key]
        assert c1[key] == pytest.approx(want, rel=1e-14, abs=1e-300), key


def test_gamma_u_limits():
    """ζ_U = 0 for elastic particles (e_p = 1: no cooling), ζ_U = O(ν) as ν → 0 (it comes
    from collisions: ζ_10 = −2(1 − e_p²)νχ dominates), ζ_U < 0 (compression, ∇·u < 0,
    raises the cooling)."""
    nu = np.array([1e-6, 1e-4, 0.05, 0.3])
    T = np.ones_like(nu)
    el = ChuteModel(restitution=1.0, transport="garzo_dufty").evaluate(nu, T)["Gamma_U"][(0, 0)]
    assert np.all(el == 0.0)
    for e in (0.5, 0.7, 0.9):
        gu = ChuteModel(restitution=e, transport="garzo_dufty").evaluate(nu, T)["Gamma_U"][(0, 0)]
        zeta_u = gu / (1.5 * nu * T)
        assert np.all(zeta_u < 0)
        # ζ_U/ν → −2(1 − e²) + ζ_11/ν: within 2 % of ζ_10/ν at ν = 1e-6 (ζ_11 ~ 1 % of ζ_U)
        assert zeta_u[0] / nu[0] == pytest.approx(-2 * (1 - e**2), rel=2e-2)
        assert zeta_u[1] / nu[1] == pytest.approx(zeta_u[0] / nu[0], rel=1e-3)


@pytest.fixture(scope="module")
def dense():
    """garzo_dufty has steady flows only where dense (docs/closures.md): θ = 16°, ν0(0) = 0.2."""
    return solve_steady(theta=16.0, nu0=0.2, model=ChuteModel(transport="garzo_dufty"))


def test_operator_identities_with_gamma_u(dense):
    """k_z = 0 is the 2D operator, α even in k_z, and A(0, 0) ∂X0/∂β = 0 (Appendix B) with
    κ_h ≠ 0 and Γ_U ≠ 0. The null-vector residual (relative) converges spectrally with N:
    1.6e-7, 2.6e-9, 3.7e-11 at N = 40, 60, 80 (lun at the same point: 4.5e-6, 4.5e-8,
    6.2e-10), so N = 80 and < 1e-9."""
    n = 80
    op2, op3 = StabilityOperator(dense, n), StabilityOperator(dense, n, three_d=True)
    m = n + 1
    b = {f: slice(i * m, (i + 1) * m) for i, f in enumerate(op3.fields)}
    keep = np.r_[b["nu"], b["u"], b["v"], b["T"]]
    for kx in (0.0, 0.01, 0.7):
        assert np.array_equal(op3.matrix(kx, 0.0)[np.ix_(keep, keep)], op2.matrix(kx))
    s = np.ones(op3.size)
    s[b["w"]] = -1.0
    for kx, kz in ((0.0, 0.3), (0.02, 0.05)):
        assert np.array_equal(op3.matrix(kx, -kz), s[:, None] * op3.matrix(kx, kz) * s[None, :])
    tg = steady_tangent(dense)
    for op, A in ((op2, op2.matrix(0.0)), (op3, op3.matrix(0.0, 0.0))):
        V = tangent_vector(op, tg)
        assert np.abs(A @ V).max() / (np.abs(A).max() * np.abs(V).max()) < 1e-9
