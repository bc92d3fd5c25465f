"""Garzó & Dufty (1999) inelastic Enskog transport coefficients, first Sonine approximation.

V. Garzó & J. W. Dufty, "Dense fluid transport for inelastic hard spheres", Phys. Rev. E
59, 5895 (1999), §VII (d = 3); the same forms are in V. Garzó, *Granular Gaseous Flows*
(Springer 2019), ch. 5. With χ = g0(ν), ν the solid fraction (their φ), α = e_p, the
reduced coefficients are::

    a2 = 16 (1 − α)(1 − 2α²) / (81 − 17α + 30α²(1 − α)),   c* = 2 a2  (Sonine coefficient),
    p* = 1 + 2 (1 + α) ν χ,
    ζ* = 5/12 χ (1 − α²)(1 + 3/16 a2)                                   (cooling rate),
    ν_η* = χ (1 − ¼(1 − α)²)(1 − a2/32),
    γ* = 128/(5π) ν² χ (1 + α)(1 − a2/16),
    η_k* = (1 − 2/5 (1 + α)(1 − 3α) ν χ) / (ν_η* − ζ*/2),
    η* = η_k* (1 + 4/5 ν χ (1 + α)) + 3/5 γ*                             (shear viscosity),
    λ* = γ*                                                            (bulk viscosity),
    ν_κ* = (1 + α)/3 χ (1 + 33/16 (1 − α) + (19 − 3α)/1024 c*),
    κ_k* = 2/3 (1 + ½(1 + p*) c* + 3/5 ν χ (1 + α)² (2α − 1 + ((1 + α)/2 − 5/(3(1 + α))) c*))
           / (ν_κ* − 2ζ*),
    κ* = κ_k* (1 + 6/5 ν χ (1 + α)) + 256/(25π) ν² χ (1 + α)(1 + 7/32 c*)  (conductivity),
    μ_k* = 2 (ζ* κ_k* (1 + ν ∂_ν ln χ) + p*/3 (1 + ν ∂_ν ln p*) c*
              − 4/5 ν χ (1 + α)(1 + ½ ν ∂_ν ln χ)(α(1 − α) + ¼(4/3 + α(1 − α)) c*))
           / (2ν_κ* − 3ζ*),
    μ* = μ_k* (1 + 6/5 ν χ (1 + α))                                     (coefficient of ∇n),

in units of the dilute elastic coefficients η0 = (5/16σ²)√(mT/π), κ0 = 15η0/(4m),
ν0 = nT/η0 (ζ^(0) = ζ* ν0) and Tκ0/n (μ). In chuteflow's units (σ, ρ_p σ³, √(σ/g);
T the temperature per unit mass, m = π/6) this is, as for Table 1's Lun closure::

    p = ν p* T,   μ = (5√π/96) η* √T,   ζ = (5√π/96) λ* √T,   κ = (25√π/128) κ* √T,
    Γ = (3/2) ν T ζ^(0) = (144/(5√π)) ζ* ν² T^{3/2},   κ_h = (25√π/128) μ*/ν T^{3/2},
    Γ_U = (3/2) ν T ζ_U,

(q = −κ∇T − μ∇n with n ∝ ν gives κ_h = Tκ0 μ*/ν). At α = 1 these are Table 1's Lun
functions at e_p = 1 (the Enskog values of Chapman & Cowling, first approximation); as
ν → 0 they are the Boltzmann (dilute) values of Brey, Dufty, Kim & Santos (1998).

The cooling rate to first order is ζ = ζ^(0) + ζ_U ∇·u (GD99 §VII; the first-order part
is the cooling rate's response to compression, nonzero only with collisions: ζ_U = O(νχ)).
In the first Sonine approximation, as MFiX's ``CALC_GD_99_ENERGY_DISSIPATION_SS``
(``model/kintheory_mod.f``) writes it in GD99's symbols::

    ζ_U = ζ_10 + ζ_11,   ζ_10 = −(1 − α)(p* − 1) = −2(1 − α²) ν χ,
    ζ_11 = 5/32 (1 − α²)(1 + 3/64 c*) χ c_D,
    c_D = (4/15 λ ν χ + (p* − 1)(2/3 − α) c*) / (½ζ* + ν_γ* + 5/64 c* (1 + 3/64 c*) χ (1 − α²)),
    ν_γ* = (1 + α)/48 χ (128 − 96α + 15α² − 15α³ + c*/64 (15α³ − 15α² + 498α − 434)),
    λ = 3/8 (1 + α)((1 − α)(5α² + 4α − 1) + c*/12 (159α + 3α² − 19α − 15α³)),

and the energy balance loses (3/2) n T ζ_U ∇·u besides (3/2) n T ζ^(0) (MFiX:
``EDvel_sM_ip = 3/2 ρ_s ε_s ζ_U``, times Θ ∇·u in ``source_granular_energy.f``). In
chuteflow's units Γ_U = (3/2) ν T ζ_U (the coefficient of ∇·u in the sink Γ + Γ_U ∇·u of
:func:`chuteflow.equations.governing_equations`). ζ_10 is also MFiX's ζ_10 of its
independent ``GTSH_2012`` implementation (``rho_10 = 2χφ(α² − 1)``); ζ_11 is ~1 % of ζ_U at
the paper's points. Caveat: λ's "− 19α" is MFiX's as written (GD99's text was not at hand;
"− 19" would change ζ_11 by < 5 % and ζ_U by < 0.1 % for α ≥ 0.5).

Verification (2026-12-04). The forms above were checked term by term against MFiX's
Fortran implementation of ``KT_TYPE = 'GD_1999'`` (repository CurtinIDS/mfix, file
``model/calc_mu_s.f``, subroutine ``GT_PDE_GD``: ``press_star``, ``c_star``,
``zeta0_star``, ``nu_eta_star``, ``gamma_star``, ``eta_k_star``, ``eta_star``,
``nu_kappa_star``, ``kappa_k_star``, ``kappa_star``, ``qmu_k_star``, ``qmu_star``; the
cooling rate ``EDT_s_ip = 3/2 ρ_s ν ν0 ζ*`` in ``model/kintheory_mod.f``), by
``tests/closures/test_garzo_dufty_mfix.py``. p*, ζ*, ν_η*, γ*, η_k*, η*, λ* = γ* (MFiX's
``Mu_b_v``) and the prefactor 6/5 of μ* agreed as first written; the earlier version had
(19 − 3α)/256 a2 = (19 − 3α)/512 c* in ν_κ* (MFiX: /1024 c*), 1 + c* and (1 + α)c*/2 in
κ_k* (MFiX: ½(1 + p*) c* and ((1 + α)/2 − 5/(3(1 + α))) c*), 7/32 a2 in κ* (MFiX: 7/32
c*) and wrong second and third terms (and a missing factor 2) in μ_k*; these are now
MFiX's forms.

The factors (1 + ν ∂_ν ln χ) and (1 + ½ ν ∂_ν ln χ) of μ_k* (decided 2026-12-05). The
first is n ∂ ln ζ^(0)/∂n: in the Chapman–Enskog solution the integral equation for the
∇ln n part of the first-order distribution has n ∂ζ^(0)/∂n times the ∇ln T part as an
inhomogeneous term (GD99; written for d dimensions in V. Garzó, "Enskog kinetic theory
for d-dimensional dense granular gases", arXiv:1204.5114, whose inhomogeneous term of that
equation contains the density derivative of the zeroth-order cooling rate), and
ζ^(0) ∝ n χ √T, so n ∂_n ln ζ^(0) = 1 + φ ∂_φ ln χ; the second is the density derivative
of the collisional transfer ∝ n²χ, (1/2)(n/χ) ∂χ/∂n. MFiX's
``GT_PDE_GD`` writes both with φχ' in place of φχ'/χ, but MFiX itself uses the ln χ form
everywhere else it states the same coefficient: ``GT_PDE_GTSH`` (Garzó, Tenneti,
Subramaniam & Hrenya, J. Fluid Mech. 712, 129 (2012), eq. (7.20), whose gas-free limit is
GD99's μ_k), ``Muk = ... EDT_s_ip*(one+EP_SM/Chi*dChiOdphi) ... (one+0.5d0*EP_SM/Chi*
dChiOdphi)``, and the polydisperse GHD theory (``model/GhdTheory/dufour_coeff.f``:
``0.5d0*(ni(l)/chi(i,l)*dchi0il_dnj(i,l,j)*ni(l) ...)`` and n ∂ζ^(0)/∂n by differencing
ζ^(0)). ``garzo_dufty`` therefore follows GD99 (ln χ); MFiX's ``GD_1999`` transcription is
the separate closure ``garzo_dufty_mfix`` (:class:`GarzoDuftyMfixClosure`, the ``mfix-gd``
preset), equal to MFiX's numbers to round-off. With Carnahan–Starling χ and e_p = 0.7 the
MFiX form's κ_h is larger by 1.6 % at ν = 0.05, 33 % at ν = 0.2 and a factor 5.7 at
ν = 0.5; they agree as ν → 0 (χ → 1).
Carnahan–Starling is MFiX's only g0 for one solids phase.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .._codegen import lazy_module
from .kinetic import TransportClosure, register_transport

sp = lazy_module("sympy")

__all__ = ["GarzoDuftyClosure", "GarzoDuftyMfixClosure", "garzo_dufty_reduced"]


def garzo_dufty_reduced(nu, e, g0, dg0=None, *, mfix_dchi: bool = False) -> dict:
    """The reduced coefficients of Garzó & Dufty (1999) (module docstring) as sympy
    expressions of ν, α = e and χ = g0 (``dg0`` = dχ/dν; by default sympy's derivative
    of ``g0`` in ``nu``): keys a2, c_star, p_star, zeta_star, nu_eta_star, gamma_star,
    eta_k_star, eta_star, lambda_star, nu_kappa_star, kappa_k_star, kappa_star, mu_k_star,
    mu_star, and of the first-order cooling rate nu_gamma_star, lambda_u, c_d, zeta_10,
    zeta_11, zeta_u (ζ_U).

    ``mfix_dchi``: μ_k*'s factors as MFiX's ``GT_PDE_GD`` writes them, (1 + ν χ') and
    (1 + ½ ν χ'), instead of GD99's (1 + ν ∂_ν ln χ) and (1 + ½ ν ∂_ν ln χ)."""
    a, chi = e, g0
    if dg0 is None:
        dg0 = sp.diff(g0, nu)
    pi = sp.pi
    r = sp.Rational
    a2 = 16 * (1 - a) * (1 - 2 * a**2) / (81 - 17 * a + 30 * a**2 * (1 - a))
    c = 2 * a2
    p_star = 1 + 2 * (1 + a) * nu * chi
    zeta = r(5, 12) * chi * (1 - a**2) * (1 + r(3, 16) * a2)
    nu_eta = chi * (1 - r(1, 4) * (1 - a) ** 2) * (1 - a2 / 32)
    gamma = r(128, 5) / pi * nu**2 * chi * (1 + a) * (1 - a2 / 16)
    eta_k = (1 - r(2, 5) * (1 + a) * (1 - 3 * a) * nu * chi) / (nu_eta - zeta / 2)
    eta = eta_k * (1 + r(4, 5) * nu * chi * (1 + a)) + r(3, 5) * gamma
    lam = gamma
    nu_kappa = (1 + a) / 3 * chi * (1 + r(33, 16) * (1 - a) + (19 - 3 * a) / 1024 * c)
    kappa_k = (
        r(2, 3)
        * (
            1
            + (1 + p_star) * c / 2
            + r(3, 5) * nu * chi * (1 + a) ** 2 * (2 * a - 1 + ((1 + a) / 2 - r(5, 3) / (1 + a)) * c)
        )
        / (nu_kappa - 2 * zeta)
    )
    kappa = kappa_k * (1 + r(6, 5) * nu * chi * (1 + a)) + r(256, 25) / pi * nu**2 * chi * (1 + a) * (
        1 + r(7, 32) * c
    )
    # n ∂_n ln ζ^(0) − 1 = ν ∂_ν ln χ (GD99); MFiX's GT_PDE_GD has ν χ' (module docstring)
    dlnchi = nu * dg0 if mfix_dchi else nu * dg0 / chi
    # p*/3 (1 + ν ∂_ν ln p*) c*, written as MFiX does: p*/3 + 2/3 ν (1 + α)(χ + ν χ')
    dp_term = p_star / 3 + r(2, 3) * nu * (1 + a) * (chi + nu * dg0)
    mu_k = (
        2
        * (
            zeta * kappa_k * (1 + dlnchi)
            + dp_term * c
            - r(4, 5) * nu * chi * (1 + a) * (1 + dlnchi / 2) * (a * (1 - a) + (r(4, 3) + a - a**2) * c / 4)
        )
        / (2 * nu_kappa - 3 * zeta)
    )
    mu = mu_k * (1 + r(6, 5) * nu * chi * (1 + a))
    # first-order cooling rate ζ_U (module docstring)
    nu_gamma = (
        (1 + a)
        / 48
        * chi
        * (128 - 96 * a + 15 * a**2 - 15 * a**3 + c / 64 * (15 * a**3 - 15 * a**2 + 498 * a - 434))
    )
    lam_u = (
        r(3, 8)
        * (1 + a)
        * ((1 - a) * (5 * a**2 + 4 * a - 1) + c / 12 * (159 * a + 3 * a**2 - 19 * a - 15 * a**3))
    )
    c_d = (r(4, 15) * lam_u * nu * chi + (p_star - 1) * (r(2, 3) - a) * c) / (
        zeta / 2 + nu_gamma + r(5, 64) * c * (1 + r(3, 64) * c) * chi * (1 - a**2)
    )
    zeta_10 = -(1 - a) * (p_star - 1)
    zeta_11 = r(5, 32) * (1 - a**2) * (1 + r(3, 64) * c) * chi * c_d
    return {
        "a2": a2,
        "c_star": c,
        "p_star": p_star,
        "zeta_star": zeta,
        "nu_eta_star": nu_eta,
        "gamma_star": gamma,
        "eta_k_star": eta_k,
        "eta_star": eta,
        "lambda_star": lam,
        "nu_kappa_star": nu_kappa,
        "kappa_k_star": kappa_k,
        "kappa_star": kappa,
        "mu_k_star": mu_k,
        "mu_star": mu,
        "nu_gamma_star": nu_gamma,
        "lambda_u": lam_u,
        "c_d": c_d,
        "zeta_10": zeta_10,
        "zeta_11": zeta_11,
        "zeta_u": zeta_10 + zeta_11,
    }


@register_transport
@dataclass(frozen=True)
class GarzoDuftyClosure(TransportClosure):
    """Garzó & Dufty (1999) inelastic Enskog theory, first Sonine approximation (d = 3; the
    forms and units in :mod:`chuteflow.closures.garzo_dufty`).

    The functions f1 … f7 keep Table 1's meaning (p = f1 T, μ = f2 √T, ζ = f3 √T,
    κ = f4 √T, f5 = 12/√π ν² g0; f6, f7 of the floor conditions from f4, f2), so the
    Johnson–Jackson floor conditions take the same form with this closure's μ and κ;
    Γ = (1 − e_p²)(1 + 3a2/16) f5 T^{3/2} (the cooling rate ζ* with its Sonine
    correction), κ_h = fh T^{3/2}, fh = (25√π/128) μ*/ν, and the first-order cooling
    Γ_U = fU T, fU = (3/2) ν ζ_U (the coefficient of ∇·u in the energy sink).
    """

    name: ClassVar[str] = "garzo_dufty"
    #: μ_k*'s density factors as MFiX's GT_PDE_GD writes them (:class:`GarzoDuftyMfixClosure`)
    mfix_dchi: ClassVar[bool] = False

    def functions(self, nu, e, nu_max, g0):
        """f1 … f7 and fh of Garzó & Dufty (1999) as sympy expressions in ν, given g0(ν)."""
        c = garzo_dufty_reduced(nu, e, g0, mfix_dchi=self.mfix_dchi)
        sqpi = sp.sqrt(sp.pi)
        f2 = 5 * sqpi / 96 * c["eta_star"]
        f4 = 25 * sqpi / 128 * c["kappa_star"]
        return {
            "f1": nu * c["p_star"],
            "f2": f2,
            "f3": 5 * sqpi / 96 * c["lambda_star"],
            "f4": f4,
            "f5": 12 / sqpi * nu**2 * g0,
            "f6": sp.sqrt(3) * sp.pi * nu * g0 / (2 * nu_max * f4),
            "f7": sp.pi * nu * g0 / (2 * sp.sqrt(3) * nu_max * f2),
            "fh": 25 * sqpi / 128 * c["mu_star"] / nu,
            "cool": 1 + sp.Rational(3, 16) * c["a2"],
            "fU": sp.Rational(3, 2) * nu * c["zeta_u"],
        }

    def transport(self, f, T, e):
        """p, μ, ζ, κ, Γ and κ_h (module docstring) from :meth:`functions`."""
        sqT = sp.sqrt(T)
        return {
            "p": f["f1"] * T,
            "mu": f["f2"] * sqT,
            "zeta": f["f3"] * sqT,
            "kappa": f["f4"] * sqT,
            "Gamma": (1 - e**2) * f["cool"] * f["f5"] * T * sqT,
            "kappa_h": f["fh"] * T * sqT,
            "Gamma_U": f["fU"] * T,
        }


@register_transport
@dataclass(frozen=True)
class GarzoDuftyMfixClosure(GarzoDuftyClosure):
    """MFiX's ``KT_TYPE = 'GD_1999'`` (``GT_PDE_GD`` in CurtinIDS/mfix ``model/calc_mu_s.f``):
    :class:`GarzoDuftyClosure` with μ_k*'s factors (1 + ν ∂_ν ln χ) and (1 + ½ ν ∂_ν ln χ)
    written, as MFiX writes them, (1 + ν χ') and (1 + ½ ν χ') (module docstring). Every
    other coefficient is GD99's; only κ_h differs. The ``mfix-gd`` preset
    (:meth:`~chuteflow.closures.ChuteModel.preset`); equal to MFiX's numbers to round-off
    (tests/closures/test_garzo_dufty_mfix.py).
    """

    name: ClassVar[str] = "garzo_dufty_mfix"
    mfix_dchi: ClassVar[bool] = True
