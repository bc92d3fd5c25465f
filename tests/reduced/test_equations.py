"""The 1D model stated once (chuteflow.reduced.equations): every derived form equals the
hand-written form it replaced.

The reference functions below are the hand-written forms of the 1D model (§5.1.2) that the
package carried before the model was stated once: the uniform-state functions and the 2×2
linearisation of LocalCoefficients, the viscosity μ̄ = (4/3) f2(0) T̄^{3/2}/cos θ, the
finite-volume right-hand side, its exact sparse Jacobian and its closed-form Fourier symbol.
They must agree with the derived forms to round-off.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

from chuteflow.closures import ChuteModel
from chuteflow.reduced import LocalCoefficients, WaveSolver
from chuteflow.reduced import equations as eq

L = 40.0
RT = 1e-13  # round-off: the derived expressions are arranged differently


def _state(rho0=0.5, U=8.0, dU=5.0, Tbar=1.5, dTbar=-2.0, mu=0.3, dmu=0.4, theta=16.0):
    s = math.sin(math.radians(theta))
    a = rho0 * s / U
    da = (s / a - dU) * a**2 / (rho0 * s)
    return LocalCoefficients(
        theta=theta, rho0=rho0, F=0.1, dF=0.2, Tbar=Tbar, dTbar=dTbar, a=a, da=da, mu_bar=mu, dmu_bar=dmu
    )


STATES = [
    _state(),
    _state(dU=-3.0, dTbar=-10.0),
    _state(dU=0.5, dTbar=0.5),
    _state(rho0=1.3, dU=2.0, dTbar=-0.6, mu=0.05),
    _state(rho0=0.2, dU=1.0, dTbar=1.0),
]


# -- hand-written forms (reference) -------------------------------------------------------
def _uniform_by_hand(c):
    s = c.sin_theta
    U = c.rho0 * s / c.a
    dU = s / c.a - c.rho0 * s * c.da / c.a**2
    return {
        "U": U,
        "dU": dU,
        "P": c.rho0 * c.Tbar,
        "dP": c.Tbar + c.rho0 * c.dTbar,
        "q0": c.rho0 * U,
        "dq0": U + c.rho0 * dU,
    }


def _matrix_by_hand(c, k):
    k = np.asarray(k, dtype=float)
    ik = 1j * k
    M = np.empty(k.shape + (2, 2), dtype=complex)
    M[..., 0, 0] = -ik * c.U
    M[..., 0, 1] = -ik * c.rho0
    M[..., 1, 0] = (c.a * c.dU - ik * c.dP) / c.rho0
    M[..., 1, 1] = -ik * c.U - (c.a + c.mu_bar * k**2) / c.rho0
    return M


def _quadratic_by_hand(c, k):
    b = (c.a + c.mu_bar * k**2) / c.rho0
    return b, 1j * k * c.a * c.dU + k**2 * c.dP


def _kernels_by_hand(rm, rho_c, rho_f):
    sT, sa = rm._splines["Tbar"], rm._splines["a"]
    T = np.exp(sT(rho_c))
    a = np.exp(sa(rho_f))
    c = rm.mu_prefactor
    dT = T * sT(rho_c, 1)
    return dict(
        a=a,
        da=a * sa(rho_f, 1),
        P=rho_c * T,
        dP=T + rho_c * dT,
        mu=c * T * np.sqrt(T),
        dmu=1.5 * c * np.sqrt(T) * dT,
    )


def _rhs_by_hand(s, y):
    N, h = s.N, 1.0 / s.dx
    rho, m = y[:N], y[N:]
    rf = 0.5 * (rho + np.roll(rho, -1))
    k = _kernels_by_hand(s.rm, rho, rf)
    u = m / rf
    uc = 0.5 * (u + np.roll(u, 1))
    du = (u - np.roll(u, 1)) * h
    Pi = rho * uc * uc + k["P"] - k["mu"] * du
    out = np.empty_like(y)
    if s.c:
        Pi -= s.c * 0.5 * (m + np.roll(m, 1))
        flux = m - s.c * rf
    else:
        flux = m
    out[:N] = -(flux - np.roll(flux, 1)) * h
    out[N:] = -(np.roll(Pi, -1) - Pi) * h + rf * s.sin - k["a"] * u
    return out


def _jacobian_by_hand(s, y):
    N = s.N
    rho, m = y[:N], y[N:]
    rf = 0.5 * (rho + np.roll(rho, -1))
    k = _kernels_by_hand(s.rm, rho, rf)
    u = m / rf
    uc = 0.5 * (u + np.roll(u, 1))
    du = (u - np.roll(u, 1)) / s.dx
    dudr = sp.diags(-u / rf) @ s.A_cf
    dudm = sp.diags(1.0 / rf)
    G = sp.diags(2.0 * rho * uc) @ s.A_fc - sp.diags(k["mu"]) @ s.D_fc
    dPi_r = sp.diags(uc * uc + k["dP"] - k["dmu"] * du) + G @ dudr
    dPi_m = G @ dudm
    dS_r = sp.diags(s.sin - k["da"] * u) @ s.A_cf - sp.diags(k["a"]) @ dudr
    dS_m = -sp.diags(k["a"]) @ dudm
    C_rho = (s.D_fc @ s.A_cf) * s.c
    C_m = (s.D_cf @ s.A_fc) * s.c
    return sp.bmat([[C_rho, -s.D_fc], [-s.D_cf @ dPi_r + dS_r, -s.D_cf @ dPi_m + dS_m + C_m]], format="csc")


def _symbol_by_hand(s, rho0, n):
    c = s.rm.coefficients(rho0)
    n = np.asarray(n, dtype=float)
    k = 2 * np.pi * n / s.L
    C = np.cos(0.5 * k * s.dx)
    K = 2.0 * np.sin(0.5 * k * s.dx) / s.dx
    U, r, mu = c.U, c.rho0, c.mu_bar
    G = 2.0 * r * U * C - 1j * K * mu
    M = np.empty(n.shape + (2, 2), dtype=complex)
    M[..., 0, 0] = 1j * s.c * np.sin(k * s.dx) / s.dx
    M[..., 0, 1] = -1j * K
    M[..., 1, 0] = (
        -1j * K * (U * U + c.dP) + 1j * K * G * U * C / r + (s.sin - c.da * U) * C + c.a * U * C / r
    )
    M[..., 1, 1] = -1j * K * G / r - c.a / r + 1j * s.c * np.sin(k * s.dx) / s.dx
    return M


# -- derived == hand-written --------------------------------------------------------------
@pytest.mark.parametrize("c", STATES)
def test_uniform_state_and_linearisation_are_the_hand_written_forms(c):
    ref = _uniform_by_hand(c)
    for name, v in ref.items():
        assert getattr(c, name) == pytest.approx(v, rel=RT, abs=1e-15), name
    k = np.logspace(-6, 1.5, 60)
    M, Mh = c.matrix(k), _matrix_by_hand(c, k)
    assert np.abs(M - Mh).max() <= RT * np.abs(Mh).max()
    b, q = eq.dispersion_coefficients(k, c.rho0, c.U, c.sin_theta, c)
    bh, qh = _quadratic_by_hand(c, k)
    assert np.allclose(b, bh, rtol=RT, atol=0)
    assert np.abs(q - qh).max() <= RT * np.abs(qh).max()


def test_coefficients_of_the_family_are_the_hand_written_forms(rm16):
    pref = 4.0 / 3.0 * float(ChuteModel().f(0.0)["f2"][0]) / math.cos(math.radians(16.0))
    assert rm16.mu_prefactor == pytest.approx(pref, rel=RT)
    r = np.linspace(*rm16.rho_range, 40)
    T, dT = rm16.Tbar(r), rm16.Tbar(r, 1)
    assert np.allclose(rm16.mu_bar(r), pref * T**1.5, rtol=RT, atol=0)
    assert np.allclose(rm16.mu_bar(r, 1), 1.5 * pref * np.sqrt(T) * dT, rtol=RT, atol=1e-15)
    s, a, da = math.sin(math.radians(16.0)), rm16.a(r), rm16.a(r, 1)
    assert np.allclose(rm16.U(r), r * s / a, rtol=RT, atol=0)
    assert np.allclose(rm16.U(r, 1), s / a - r * s * da / a**2, rtol=RT, atol=1e-14)
    assert np.allclose(rm16.P(r, 1), T + r * dT, rtol=RT, atol=1e-14)
    for c in rm16.coefficients_at_knots:  # exact coefficients: μ̄ from the viscosity closure
        assert c.mu_bar == pytest.approx(pref * c.Tbar**1.5, rel=RT)
        assert c.dmu_bar == pytest.approx(1.5 * pref * math.sqrt(c.Tbar) * c.dTbar, rel=RT)


@pytest.mark.parametrize("frame", [0.0, 9.16])
def test_scheme_jacobian_and_symbol_are_the_hand_written_forms(rm16, state16, frame):
    rng = np.random.default_rng(3)
    s = WaveSolver(rm16, L, 48, frame_speed=frame)
    y = s.uniform(state16.rho0)
    y[: s.N] *= 1 + 0.05 * rng.standard_normal(s.N)
    y[s.N :] *= 1 + 0.05 * rng.standard_normal(s.N)
    f, fh = s.rhs(0.0, y), _rhs_by_hand(s, y)
    # the momentum rows are differences of fluxes Π/dx ~ 1e2 × the result: round-off of Π
    assert np.abs(f - fh).max() <= 1e-12 * np.abs(fh).max()
    J, Jh = s.jacobian(0.0, y).toarray(), _jacobian_by_hand(s, y).toarray()
    assert np.abs(J - Jh).max() <= RT * np.abs(Jh).max()
    n = np.arange(1, s.N // 2)
    S, Sh = s.symbol(state16.rho0, n), _symbol_by_hand(s, state16.rho0, n)
    assert np.abs(S - Sh).max() <= RT * np.abs(Sh).max()
    assert s.symbol(state16.rho0, 3).shape == (2, 2)


def test_statement_is_the_balance_law_of_section_5_1_2():
    # f_ρ = ρ̄ū, f_m = ρ̄ū² + ρ̄T̄ − μ̄ ∂xū, S = ρ̄ sinθ − a ū (= a [U − ū], U = ρ̄ sinθ/a)
    import sympy

    rho, u, ux, s = eq.RHO, eq.U, eq.UX, eq.SIN_THETA
    T, a, mu = (sympy.Function(n)(rho) for n in ("Tbar", "a", "mu_bar"))
    assert sympy.simplify(eq.MASS_FLUX - rho * u) == 0
    assert sympy.simplify(eq.MOMENTUM_FLUX - (rho * u**2 + rho * T - mu * ux)) == 0
    assert sympy.simplify(eq.SOURCE - a * (rho * s / a - u)) == 0


def test_long_wave_coefficients_of_the_paper_follow_from_the_statement():
    # disp-oned of §5.1.2: α = −i (ρ0U)' k + (ρ0/a)[(ρ0U')² − (ρ0T̄)'] k² + O(k³), the printed
    # result that LocalCoefficients.alpha1/alpha2 use, from the small root of the derived
    # quadratic λ² + bλ + c = 0 (α = λ − ikU0) expanded in k
    import sympy

    d = eq.derivation()
    b, c = d["quadratic"]
    k = eq.K
    l1, l2 = sympy.symbols("l1 l2")
    root = l1 * k + l2 * k**2
    res = sympy.expand(sympy.series((root**2 + b * root + c), k, 0, 3).removeO())
    sol = sympy.solve([res.coeff(k, 1), res.coeff(k, 2)], [l1, l2], dict=True)[0]
    alpha1, alpha2 = -sympy.I * eq.U0 + sol[l1], sol[l2]
    U, dU = d["uniform"][0], d["uniform"][1]
    a = sympy.Function("a")(eq.RHO)
    T = sympy.Function("Tbar")(eq.RHO)
    dP = sympy.diff(eq.RHO * T, eq.RHO)
    paper1 = -sympy.I * sympy.diff(eq.RHO * U, eq.RHO)
    paper2 = eq.RHO / a * ((eq.RHO * dU) ** 2 - dP)
    at = {eq.U0: U}
    assert sympy.simplify(alpha1.subs(at) - paper1) == 0
    assert sympy.simplify(alpha2.subs(at) - paper2) == 0
