"""Transport closures lun, lun_full, lun_mfix, garzo_dufty; Ma–Ahmadi g0; presets.

The reference values are independent numpy transcriptions of the published formulas (not
the package's sympy): Garzó & Dufty, Phys. Rev. E 59, 5895 (1999), §VII, d = 3 (the forms
in the docstring of chuteflow.closures.garzo_dufty); the elastic Enskog coefficients of
Chapman & Cowling (first approximation, bρ = 4ν); the dilute (Boltzmann) inelastic values
of Brey, Dufty, Kim & Santos, Phys. Rev. E 58, 4638 (1998); the paper's Table 1 (Lun et
al. 1984); Ma & Ahmadi (1986) g0. (The Garzó–Dufty reference was corrected on
2026-12-04 to MFiX's GT_PDE_GD, see test_garzo_dufty_mfix.py: ν_κ*, κ_k*, κ*, μ_k*.)
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import TRANSPORTS, ChuteModel
from chuteflow.errors import ParameterError

SQPI = math.sqrt(math.pi)
NUS = np.array([1e-3, 0.05, 0.2, 0.35, 0.5])
ES = (0.5, 0.7, 0.9, 0.99)


def cs(nu):
    """Carnahan–Starling g0 and dg0/dν."""
    g = (2 - nu) / (2 * (1 - nu) ** 3)
    dg = (5 - 2 * nu) / (2 * (1 - nu) ** 4)
    return g, dg


def gd_reference(nu, a, g, dg):
    """Garzó & Dufty (1999) §VII, d = 3, written out in numpy."""
    a2 = 16 * (1 - a) * (1 - 2 * a**2) / (81 - 17 * a + 30 * a**2 * (1 - a))
    c = 2 * a2
    zeta = 5 / 12 * g * (1 - a**2) * (1 + 3 / 16 * a2)
    nu_eta = g * (1 - 0.25 * (1 - a) ** 2) * (1 - a2 / 32)
    gamma = 128 / (5 * math.pi) * nu**2 * g * (1 + a) * (1 - a2 / 16)
    eta_k = (1 - 0.4 * (1 + a) * (1 - 3 * a) * nu * g) / (nu_eta - zeta / 2)
    eta = eta_k * (1 + 0.8 * nu * g * (1 + a)) + 0.6 * gamma
    nu_k = (1 + a) / 3 * g * (1 + 33 / 16 * (1 - a) + (19 - 3 * a) / 1024 * c)
    p_star = 1 + 2 * (1 + a) * nu * g
    ckk = (1 + a) / 2 - 5 / (3 * (1 + a))
    kap_k = (
        2
        / 3
        * (1 + (1 + p_star) * c / 2 + 0.6 * nu * g * (1 + a) ** 2 * (2 * a - 1 + ckk * c))
        / (nu_k - 2 * zeta)
    )
    kap = kap_k * (1 + 1.2 * nu * g * (1 + a)) + 256 / (25 * math.pi) * nu**2 * g * (1 + a) * (1 + 7 / 32 * c)
    dl = nu * dg / g
    dlp = nu * 2 * (1 + a) * (g + nu * dg) / p_star
    mu_k = (
        2
        * (
            zeta * kap_k * (1 + dl)
            + p_star / 3 * (1 + dlp) * c
            - 0.8 * nu * g * (1 + a) * (1 + dl / 2) * (a * (1 - a) + (4 / 3 + a * (1 - a)) * c / 4)
        )
        / (2 * nu_k - 3 * zeta)
    )
    mu = mu_k * (1 + 1.2 * nu * g * (1 + a))
    return {"a2": a2, "zeta": zeta, "eta": eta, "lambda": gamma, "kappa": kap, "mu": mu}


def gd_dimensional(nu, T, a):
    """The chuteflow-unit transport functions of garzo_dufty with CS g0 (module docstring)."""
    g, dg = cs(nu)
    r = gd_reference(nu, a, g, dg)
    return {
        "p": nu * (1 + 2 * (1 + a) * nu * g) * T,
        "mu": 5 * SQPI / 96 * r["eta"] * np.sqrt(T),
        "zeta": 5 * SQPI / 96 * r["lambda"] * np.sqrt(T),
        "kappa": 25 * SQPI / 128 * r["kappa"] * np.sqrt(T),
        "Gamma": 144 / (5 * SQPI) * r["zeta"] * nu**2 * T**1.5,
        "kappa_h": 25 * SQPI / 128 * r["mu"] / nu * T**1.5,
    }


def lun_f(nu, e, g):
    """Table 1 f2, f3, f4 (η = (1 + e)/2)."""
    eta = (1 + e) / 2
    f2 = (
        5
        * SQPI
        / (96 * eta * (2 - eta))
        * (1 + 1.6 * eta * nu * g)
        * (1 / g + 1.6 * eta * (3 * eta - 2) * nu)
        + 8 / (5 * SQPI) * eta * nu**2 * g
    )
    f3 = 8 / (3 * SQPI) * eta * nu**2 * g
    f4 = (
        25
        * SQPI
        / (16 * eta * (41 - 33 * eta))
        * (1 + 2.4 * eta * nu * g)
        * (1 / g + 2.4 * eta**2 * (4 * eta - 3) * nu)
        + 4 / SQPI * eta * nu**2 * g
    )
    return f2, f3, f4


@pytest.mark.parametrize("e", ES)
def test_garzo_dufty_values_and_first_derivatives(e):
    """Values and ∂/∂ν, ∂/∂T against the numpy transcription (derivatives by the complex
    step f'(x) = Im f(x + ih)/h, h = 1e-30: exact to round-off)."""
    model = ChuteModel(restitution=e, transport="garzo_dufty", radial="carnahan_starling")
    T = np.full_like(NUS, 1.7)
    ev = model.evaluate(NUS, T)
    ref = gd_dimensional(NUS, T, e)
    h = 1e-30
    for name in ("p", "mu", "zeta", "kappa", "Gamma", "kappa_h"):
        np.testing.assert_allclose(ev[name][(0, 0)], ref[name], rtol=1e-12, err_msg=name)
        d_nu = gd_dimensional(NUS + 1j * h, T + 0j, e)[name].imag / h
        d_T = gd_dimensional(NUS + 0j, T + 1j * h, e)[name].imag / h
        np.testing.assert_allclose(ev[name][(1, 0)], d_nu, rtol=1e-11, atol=1e-14, err_msg=name)
        np.testing.assert_allclose(ev[name][(0, 1)], d_T, rtol=1e-11, atol=1e-14, err_msg=name)


def test_garzo_dufty_elastic_limit_is_enskog():
    """e_p = 1: Chapman–Cowling's Enskog coefficients (first approximation, bρ = 4ν):
    η/η0 = 1/χ + 4/5 bρ + 4/25 (1 + 12/π)(bρ)² χ, κ/κ0 = 1/χ + 6/5 bρ + 9/25 (1 + 32/(9π))(bρ)² χ,
    bulk viscosity 16/(5π) (bρ)² χ η0; μ = 0; and the Lun functions of Table 1 at e_p = 1."""
    model = ChuteModel(restitution=1.0, transport="garzo_dufty", radial="carnahan_starling")
    ev = model.evaluate(NUS, np.ones_like(NUS))
    g, _ = cs(NUS)
    b = 4 * NUS
    eta0, kap0 = 5 * SQPI / 96, 25 * SQPI / 128
    np.testing.assert_allclose(
        ev["mu"][(0, 0)], eta0 * (1 / g + 0.8 * b + 4 / 25 * (1 + 12 / math.pi) * b**2 * g), rtol=1e-13
    )
    np.testing.assert_allclose(
        ev["kappa"][(0, 0)],
        kap0 * (1 / g + 1.2 * b + 9 / 25 * (1 + 32 / (9 * math.pi)) * b**2 * g),
        rtol=1e-13,
    )
    np.testing.assert_allclose(ev["zeta"][(0, 0)], eta0 * 16 / (5 * math.pi) * b**2 * g, rtol=1e-13)
    assert np.all(ev["kappa_h"][(0, 0)] == 0)
    assert np.all(ev["Gamma"][(0, 0)] == 0)
    lun = ChuteModel(restitution=1.0, transport="lun", radial="carnahan_starling").evaluate(
        NUS, np.ones_like(NUS)
    )
    for name in ("p", "mu", "zeta", "kappa"):
        np.testing.assert_allclose(ev[name][(0, 0)], lun[name][(0, 0)], rtol=1e-13)


def test_garzo_dufty_mu_vanishes_linearly_as_e_tends_to_one():
    """μ* = O(1 − e_p): κ_h/(1 − e_p) tends to a finite nonzero limit."""
    r = []
    for e in (0.99, 0.999, 0.9999):
        kh = ChuteModel(restitution=e, transport="garzo_dufty").evaluate(NUS, np.ones_like(NUS))["kappa_h"][
            (0, 0)
        ]
        r.append(kh / (1 - e))
    assert np.all(np.abs(r[2]) > 0)
    np.testing.assert_allclose(r[1], r[2], rtol=1e-2)  # measured 3.6e-3: O(1 − e_p)
    np.testing.assert_allclose(r[0], r[2], rtol=5e-2)


@pytest.mark.parametrize("e", ES)
def test_garzo_dufty_dilute_limit_is_boltzmann(e):
    """ν → 0: Brey, Dufty, Kim & Santos (1998): η* = 1/(ν_η* − ζ*/2), κ* = 2/3 (1 + c*)/(ν_κ* − 2ζ*),
    μ* = 2ζ*(κ* + c*/(3ζ*))/(2ν_κ* − 3ζ*) with ν_η* = (1 − ¼(1−α)²)(1 − c*/64),
    ν_κ* = (1+α)/3 (1 + 33/16 (1−α) + (19 − 3α)/1024 c*), ζ* = 5/12 (1 − α²)(1 + 3c*/32)."""
    a = e
    c = 32 * (1 - a) * (1 - 2 * a**2) / (81 - 17 * a + 30 * a**2 * (1 - a))
    zeta = 5 / 12 * (1 - a**2) * (1 + 3 * c / 32)
    eta = 1 / ((1 - 0.25 * (1 - a) ** 2) * (1 - c / 64) - zeta / 2)
    nuk = (1 + a) / 3 * (1 + 33 / 16 * (1 - a) + (19 - 3 * a) / 1024 * c)
    kap = 2 / 3 * (1 + c) / (nuk - 2 * zeta)
    mu = 2 * zeta * (kap + c / (3 * zeta)) / (2 * nuk - 3 * zeta)
    nu = np.array([1e-9])
    ev = ChuteModel(restitution=e, transport="garzo_dufty").evaluate(nu, np.ones(1))
    assert ev["mu"][(0, 0)][0] == pytest.approx(5 * SQPI / 96 * eta, rel=1e-7)
    assert ev["kappa"][(0, 0)][0] == pytest.approx(25 * SQPI / 128 * kap, rel=1e-7)
    assert ev["kappa_h"][(0, 0)][0] * nu[0] == pytest.approx(25 * SQPI / 128 * mu, rel=1e-7)
    assert ev["Gamma"][(0, 0)][0] == pytest.approx(144 / (5 * SQPI) * zeta * nu[0] ** 2, rel=1e-7)


@pytest.mark.parametrize("e", ES)
def test_lun_full_heat_flux_term(e):
    """lun_full: Table 1's functions unchanged, κ_h = fh T^{3/2} (kinetic.LunFullClosure),
    proportional to (1 − e_p) through (η − 1)(2η − 1). Reference: Lun et al. (1984)'s
    coefficient as MFiX writes it (CurtinIDS/mfix model/calc_mu_s.f, GT_PDE_LUN, the
    commented-out Kphi_s = (Kth*/g0) 12/5 η(η − 1)(2η − 1)(1 + 12/5 η ν g0)(ν g0' + 2 g0) T
    with Kth* = 75√π/(48 η (41 − 33η))), per unit ρ_p σ and in √T units."""
    eta = (1 + e) / 2
    nu, T = NUS, np.full_like(NUS, 2.0)
    full = ChuteModel(restitution=e, transport="lun_full").evaluate(nu, T)
    lun = ChuteModel(restitution=e).evaluate(nu, T)
    g = (1 - nu / 0.6) ** (-1.5)
    dg = 1.5 / 0.6 * (1 - nu / 0.6) ** (-2.5)
    # MFiX's Kphi_s over ρ_p σ T^{3/2}, with Kth*/(ρ_p σ √T) = 75√π/(48 η (41 − 33η))
    kth = 75 * SQPI / (48 * eta * (41 - 33 * eta))
    fh = kth / g * 2.4 * eta * (eta - 1) * (2 * eta - 1) * (1 + 2.4 * eta * nu * g) * (nu * dg + 2 * g)
    assert np.all(fh < 0)  # heat flows up the density gradient for e_p < 1
    np.testing.assert_allclose(full["kappa_h"][(0, 0)], fh * T**1.5, rtol=1e-12)
    np.testing.assert_allclose(full["kappa_h"][(0, 1)], 1.5 * fh * T**0.5, rtol=1e-12)
    for name in ("p", "mu", "zeta", "kappa", "Gamma", "eta_star", "Gamma_star"):
        np.testing.assert_allclose(full[name][(0, 0)], lun[name][(0, 0)], rtol=1e-14)
    assert np.all(lun["kappa_h"][(0, 0)] == 0)


def test_lun_mfix_viscosity_factor():
    """MFiX LUN_1984: μ = (2 + α)/3 × Table 1's f2 √T (α = 1.6: 1.2×); η* of the floor unchanged."""
    nu, T = NUS, np.full_like(NUS, 1.3)
    m = ChuteModel.preset("mfix-lun")
    assert m.radial.name == "carnahan_starling"
    assert m.transport.alpha == 1.6
    ev = m.evaluate(nu, T)
    f2, f3, f4 = lun_f(nu, 0.7, cs(nu)[0])
    np.testing.assert_allclose(ev["mu"][(0, 0)], 1.2 * f2 * np.sqrt(T), rtol=1e-12)
    np.testing.assert_allclose(ev["zeta"][(0, 0)], f3 * np.sqrt(T), rtol=1e-12)
    np.testing.assert_allclose(ev["kappa"][(0, 0)], f4 * np.sqrt(T), rtol=1e-12)
    ref = ChuteModel(radial="carnahan_starling").evaluate(nu, T)
    np.testing.assert_allclose(ev["eta_star"][(0, 0)], ref["eta_star"][(0, 0)], rtol=1e-12)
    one = ChuteModel(radial="carnahan_starling", transport={"name": "lun_mfix", "alpha": 1.0}).evaluate(nu, T)
    np.testing.assert_allclose(one["mu"][(0, 0)], ref["mu"][(0, 0)], rtol=1e-13)


def test_ma_ahmadi_g0():
    """Ma & Ahmadi (1986): (1 + 2.5ν + 4.5904ν² + 4.515439ν³)/(1 − (ν/ν_m)³)^0.67802; → 1 + 5ν/2 as ν → 0."""
    m = ChuteModel(radial="ma_ahmadi", nu_max=0.64356)
    nu = np.array([1e-6, 0.1, 0.3, 0.5, 0.6])
    ref = (1 + 2.5 * nu + 4.5904 * nu**2 + 4.515439 * nu**3) / (1 - (nu / 0.64356) ** 3) ** 0.67802
    g, dg, _ = m.g0(nu)
    np.testing.assert_allclose(g, ref, rtol=1e-13)
    h = 1e-7
    dref = (
        (1 + 2.5 * (nu + h) + 4.5904 * (nu + h) ** 2 + 4.515439 * (nu + h) ** 3)
        / (1 - ((nu + h) / 0.64356) ** 3) ** 0.67802
        - (1 + 2.5 * (nu - h) + 4.5904 * (nu - h) ** 2 + 4.515439 * (nu - h) ** 3)
        / (1 - ((nu - h) / 0.64356) ** 3) ** 0.67802
    ) / (2 * h)
    np.testing.assert_allclose(dg, dref, rtol=1e-6)
    assert g[0] == pytest.approx(1 + 2.5e-6, rel=1e-11)


def test_presets_and_unknown_names():
    assert ChuteModel.preset("paper") == ChuteModel()
    assert ChuteModel.preset("mfix-gd", roughness=0.1) == ChuteModel(
        transport="garzo_dufty_mfix", radial="carnahan_starling", roughness=0.1
    )
    with pytest.raises(ParameterError, match=r"unknown preset 'mfix'; choose one of \['mfix-gd', 'mfix-lun'"):
        ChuteModel.preset("mfix")
    known = r"\['garzo_dufty', 'garzo_dufty_mfix', 'lun'"
    with pytest.raises(ParameterError, match=r"unknown closure 'gd'; choose one of " + known):
        ChuteModel(transport="gd")
    with pytest.raises(ParameterError, match=r"alpha = -1 is outside the allowed range \[0, 10\]"):
        ChuteModel(transport={"name": "lun_mfix", "alpha": -1})
    assert {"lun", "lun_full", "lun_mfix", "garzo_dufty", "garzo_dufty_mfix"} <= set(TRANSPORTS.names())
    m = ChuteModel.preset("mfix-lun")
    assert ChuteModel.from_dict(m.to_dict()) == m


def test_vanishing_functions():
    """κ_h ≡ 0 and Γ_U ≡ 0 for the paper's closure (and MFiX's Lun; Γ_U also for lun_full):
    the compiled steady rows leave their terms out, so the paper's numbers are bit for bit
    those before κ_h and Γ_U existed."""
    from chuteflow.closures.model import vanishing_functions

    assert vanishing_functions(*ChuteModel().closures) == ("kappa_h", "Gamma_U")
    assert vanishing_functions(*ChuteModel.preset("mfix-lun").closures) == ("kappa_h", "Gamma_U")
    assert vanishing_functions(*ChuteModel(transport="lun_full").closures) == ("Gamma_U",)
    assert vanishing_functions(*ChuteModel.preset("mfix-gd").closures) == ()
    assert vanishing_functions(*ChuteModel(transport="garzo_dufty").closures) == ()
