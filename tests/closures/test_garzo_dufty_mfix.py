"""garzo_dufty, garzo_dufty_mfix and lun_mfix against MFiX's Fortran (an independent implementation).

Transcribed for testing from MFiX as stored in the public repository CurtinIDS/mfix
(commit aa5da900933766e158dd4188220765689855bde7):

* ``model/calc_mu_s.f``, subroutine ``GT_PDE_GD`` (``KT_TYPE = 'GD_1999'``, author J. E.
  Galvin): ``P_s_v``, ``Mu_s_v = eta0 eta_star``, ``Mu_b_v = eta0 gamma_star`` (bulk
  viscosity), ``Kth_s = kappa0 kappa_star``, ``Kphi_s = Theta kappa0 qmu_star / n`` (the
  coefficient of ∇n in the heat flux), without the gas-phase terms (``SWITCH = 0``);
* ``model/kintheory_mod.f``: the dissipation ``EDT_s_ip = 3/2 ρ_s ε_s nu0 zeta0_star``
  (times Θ in ``source_granular_energy.f``) and the first-order cooling ``EDvel_sM_ip =
  3/2 ρ_s ε_s zeta1`` (times Θ ∇·u there), subroutine ``CALC_GD_99_ENERGY_DISSIPATION_SS``;
* ``model/calc_mu_s.f``, subroutine ``GT_PDE_LUN`` (``KT_TYPE = 'LUN_1984'``): ``P_s_v``, ``Kth_s``,
  ``Mu_s_v`` with the factor (2 + ALPHA)/3, ``ALPHA = 1.6d0`` a PARAMETER in ``model/constant_mod.f``;
* ``model/rdf_mod.f``: for one solids phase g0 is Carnahan–Starling, ``DG_0DNU =
  (2.5 − ε)/(1 − ε)⁴``.

Units: ρ_s = d_p = 1 and Θ = T (MFiX's Θ is per unit mass, as chuteflow's T), so
m = π/6 and n = ν/m; chuteflow's κ_h multiplies ∇ν, i.e. κ_h = Kphi_s/m.

μ_k*'s density factors: MFiX's GT_PDE_GD writes (1 + ν χ') and (1 + ½ ν χ') where GD99 has
(1 + ν ∂_ν ln χ) and (1 + ½ ν ∂_ν ln χ) (n ∂_n ln ζ^(0), ζ^(0) ∝ nχ; MFiX's own GT_PDE_GTSH and
GHD code use the ln χ form: chuteflow.closures.garzo_dufty's docstring). The reference
below is GT_PDE_GD as written (``ln_chi=False``), checked against ``garzo_dufty_mfix`` (the
``mfix-gd`` preset), and with χ' divided by χ in those two factors (``ln_chi=True``), checked
against ``garzo_dufty``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel

PI = math.pi
NUS = np.linspace(0.01, 0.5, 12)
ES = (0.6, 0.7, 0.8, 0.9, 0.95, 0.99)


def mfix_gd(ep, c_e, theta, ln_chi=False):
    """GT_PDE_GD (and the GD_1999 dissipation) with ρ_s = d_p = 1, SWITCH = 0; ``ln_chi``:
    GD99's ∂ ln χ in μ_k*'s two density factors (module docstring)."""
    chi = (1 - ep / 2) / (1 - ep) ** 3
    dchi = (2.5 - ep) / (1 - ep) ** 4
    dchi_mu = dchi / chi if ln_chi else dchi
    m_p = PI / 6
    n_p = ep / m_p
    press_star = 1 + 2 * (1 + c_e) * ep * chi
    c_star = 32 * (1 - c_e) * (1 - 2 * c_e**2) / (81 - 17 * c_e + 30 * c_e**2 * (1 - c_e))
    zeta0_star = 5 / 12 * chi * (1 - c_e**2) * (1 + 3 / 32 * c_star)
    nu_eta_star = chi * (1 - 0.25 * (1 - c_e) ** 2) * (1 - c_star / 64)
    gamma_star = 4 / 5 * (32 / PI) * ep**2 * chi * (1 + c_e) * (1 - c_star / 32)
    eta_k_star = (1 - 2 / 5 * (1 + c_e) * (1 - 3 * c_e) * ep * chi) / (nu_eta_star - 0.5 * zeta0_star)
    eta_star = eta_k_star * (1 + 4 / 5 * ep * chi * (1 + c_e)) + 3 / 5 * gamma_star
    eta0 = 5 * m_p * np.sqrt(theta / PI) / 16
    kappa0 = 15 / 4 * eta0
    nu_kappa_star = chi / 3 * (1 + c_e) * (1 + 33 / 16 * (1 - c_e) + (19 - 3 * c_e) / 1024 * c_star)
    c_kk = 0.5 * (1 + c_e) - 5 / (3 * (1 + c_e))
    kappa_k_star = (
        2
        / 3
        * (
            1
            + 0.5 * (1 + press_star) * c_star
            + 3 / 5 * ep * chi * (1 + c_e) ** 2 * (2 * c_e - 1 + c_kk * c_star)
        )
        / (nu_kappa_star - 2 * zeta0_star)
    )
    kappa_c = 256 / 25 * (ep**2 / PI) * chi * (1 + c_e) * (1 + 7 / 32 * c_star)
    kappa_star = kappa_k_star * (1 + 6 / 5 * ep * chi * (1 + c_e)) + kappa_c
    qmu_k_star = (
        2
        * (
            (1 + ep * dchi_mu) * zeta0_star * kappa_k_star
            + (press_star / 3 + 2 / 3 * ep * (1 + c_e) * (chi + ep * dchi)) * c_star
            - 4
            / 5
            * ep
            * chi
            * (1 + ep / 2 * dchi_mu)
            * (1 + c_e)
            * (c_e * (1 - c_e) + 0.25 * (4 / 3 + c_e * (1 - c_e)) * c_star)
        )
        / (2 * nu_kappa_star - 3 * zeta0_star)
    )
    qmu_star = qmu_k_star * (1 + 6 / 5 * ep * chi * (1 + c_e))
    nu0 = 96 / 5 * ep * np.sqrt(theta / PI)
    kphi = theta * kappa0 / n_p * qmu_star
    # CALC_GD_99_ENERGY_DISSIPATION_SS (model/kintheory_mod.f): zeta1 = ζ_U (the 1/nu0 of
    # cD cancels against the nu0 of zeta1 = nu0 zeta1_star), EDvel_sM_ip = 3/2 rop_s zeta1,
    # times Θ tr(D) in source_granular_energy.f (S12)
    c3 = 15 * c_e**3 - 15 * c_e**2 + 498 * c_e - 434
    nu_gamma_star = (1 + c_e) / 48 * chi * (128 - 96 * c_e + 15 * c_e**2 - 15 * c_e**3 + c_star / 64 * c3)
    l3 = 159 * c_e + 3 * c_e**2 - 19 * c_e - 15 * c_e**3  # MFiX's lambda_num as written
    lambda_num = 3 / 8 * ((1 - c_e) * (5 * c_e**2 + 4 * c_e - 1) + c_star / 12 * l3) * (1 + c_e)
    cd_num = (4 / 15 * lambda_num * ep * chi + (press_star - 1) * (2 / 3 - c_e) * c_star) / (
        0.5 * zeta0_star + nu_gamma_star + 5 * c_star / 64 * (1 + 3 * c_star / 64) * chi * (1 - c_e**2)
    )
    zeta1 = -(1 - c_e) * (press_star - 1) + 5 / 32 * (1 - c_e**2) * (1 + 3 * c_star / 64) * chi * cd_num
    edvel = 1.5 * ep * zeta1
    return {
        "p": ep * theta * press_star,
        "mu": eta0 * eta_star,
        "zeta": eta0 * gamma_star,
        "kappa": kappa0 * kappa_star,
        "Gamma": 1.5 * ep * nu0 * zeta0_star * theta,
        "kappa_h": kphi / m_p,
        "Gamma_U": edvel * theta,
    }


def mfix_lun_mu(ep, c_e, theta, alpha=1.6):
    """GT_PDE_LUN's Mu_s_v (SWITCH = 0, one solids phase), ρ_s = d_p = 1."""
    eta = (1 + c_e) / 2
    g0 = (1 - ep / 2) / (1 - ep) ** 3
    mu = 5 * np.sqrt(PI * theta) / 96
    mu_b = 256 * mu * ep * ep * g0 / (5 * PI)
    return (
        (2 + alpha)
        / 3
        * (
            mu
            / (eta * (2 - eta) * g0)
            * (1 + 1.6 * eta * ep * g0)
            * (1 + 1.6 * eta * (3 * eta - 2) * ep * g0)
            + 0.6 * mu_b * eta
        )
    )


def mfix_lun_p_kappa(ep, c_e, theta):
    """GT_PDE_LUN's P_s_v and Kth_s (SWITCH = 0, one solids phase), ρ_s = d_p = 1."""
    eta = (1 + c_e) / 2
    g0 = (1 - ep / 2) / (1 - ep) ** 3
    kth = 75 * np.sqrt(PI * theta) / (48 * eta * (41 - 33 * eta))
    a = (1 + 12 / 5 * eta * ep * g0) * (1 + 12 / 5 * eta**2 * (4 * eta - 3) * ep * g0)
    kappa = kth / g0 * (a + 64 / (25 * PI) * (41 - 33 * eta) * (eta * ep * g0) ** 2)
    return ep * (1 + 4 * eta * ep * g0) * theta, kappa


@pytest.mark.parametrize("e", ES)
def test_garzo_dufty_mfix_matches_mfix_gd_1999(e):
    """The mfix-gd preset is MFiX's GD_1999 as written, to round-off."""
    T = np.linspace(0.5, 3.0, NUS.size)
    ev = ChuteModel.preset("mfix-gd", restitution=e).evaluate(NUS, T)
    ref = mfix_gd(NUS, e, T)
    for key in ("p", "mu", "zeta", "kappa", "Gamma", "kappa_h", "Gamma_U"):
        np.testing.assert_allclose(ev[key][(0, 0)], ref[key], rtol=1e-10, err_msg=key)


@pytest.mark.parametrize("e", ES)
def test_garzo_dufty_matches_mfix_gd_1999_with_gd99_ln_chi(e):
    """garzo_dufty is MFiX's GD_1999 with GD99's ∂ ln χ in μ_k*: every coefficient but κ_h
    identical to garzo_dufty_mfix, κ_h different where χ differs from 1."""
    T = np.linspace(0.5, 3.0, NUS.size)
    ev = ChuteModel(restitution=e, transport="garzo_dufty", radial="carnahan_starling").evaluate(NUS, T)
    ref = mfix_gd(NUS, e, T, ln_chi=True)
    for key in ("p", "mu", "zeta", "kappa", "Gamma", "kappa_h", "Gamma_U"):
        np.testing.assert_allclose(ev[key][(0, 0)], ref[key], rtol=1e-10, err_msg=key)
    mf = mfix_gd(NUS, e, T)
    assert abs(mf["kappa_h"][-1] / ref["kappa_h"][-1] - 1) > 0.1  # ν = 0.5: χ' ≠ χ'/χ


@pytest.mark.parametrize("alpha", [1.0, 1.6])
@pytest.mark.parametrize("e", ES)
def test_lun_mfix_viscosity_matches_mfix_lun_1984(e, alpha):
    T = np.linspace(0.5, 3.0, NUS.size)
    model = ChuteModel(
        restitution=e, transport={"name": "lun_mfix", "alpha": alpha}, radial="carnahan_starling"
    )
    ev = model.evaluate(NUS, T)
    np.testing.assert_allclose(ev["mu"][(0, 0)], mfix_lun_mu(NUS, e, T, alpha), rtol=1e-10)
    p, kappa = mfix_lun_p_kappa(NUS, e, T)
    np.testing.assert_allclose(ev["p"][(0, 0)], p, rtol=1e-10)
    np.testing.assert_allclose(ev["kappa"][(0, 0)], kappa, rtol=1e-10)
    assert np.all(np.asarray(ev["kappa_h"][(0, 0)]) == 0.0)  # MFiX: Kphi_s = 0 for LUN_1984
    assert np.all(np.asarray(ev["Gamma_U"][(0, 0)]) == 0.0)  # and EDvel_sM_ip = 0
