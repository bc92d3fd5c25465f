"""Closures (paper §2, Table 1, eq:pmuetc, etastar, gammastar): derivatives, limits, validation.

The reference values here come from an independent numpy transcription of Table 1
written in this file, not from the package's sympy statement.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import FUNCTIONS, ORDERS, ChuteModel
from chuteflow.errors import ChuteflowError, ParameterError

SQPI = math.sqrt(math.pi)

MODELS = {
    "paper": ChuteModel(),  # e_p = 0.7, ν_m = 0.6, φ = 0.05, Φ = 0.39
    "rough-elastic": ChuteModel(restitution=0.95, nu_max=0.64, roughness=0.1, wall_loss=0.2),
    "inelastic": ChuteModel(restitution=0.3, nu_max=0.55, roughness=0.02, wall_loss=0.9),
    "carnahan-starling": ChuteModel(radial="carnahan_starling"),
}
NU = np.array([1e-3, 0.01, 0.05, 0.12, 0.2, 0.3, 0.4, 0.45, 0.5])
T = np.array([1e-4, 0.02, 1.0, 50.0])


def _grid(model: ChuteModel):
    nus = np.concatenate(
        [NU[NU < 0.9 * model.nu_max], model.nu_max - np.array([0.05, 0.01])]
    )  # close to ν_m too
    return np.meshgrid(nus, T, indexing="ij")


# ---------------------------------------------------------------------------------------
# Independent transcription of Table 1 and of eq:pmuetc, etastar, gammastar.
# ---------------------------------------------------------------------------------------
def table1(nu, e, nu_m, radial="lun_savage"):
    """f1 … f7 of Table 1 and g0 (Lun & Savage 1986, or Carnahan–Starling), in numpy."""
    nu = np.asarray(nu, dtype=float)
    eta = (1.0 + e) / 2.0
    if radial == "lun_savage":
        g0 = 1.0 / (1.0 - nu / nu_m) ** (2.5 * nu_m)
    else:
        g0 = (2.0 - nu) / (2.0 * (1.0 - nu) ** 3)
    f1 = nu * (1.0 + 4.0 * eta * nu * g0)
    f2 = (
        5.0
        * SQPI
        / (96.0 * eta * (2.0 - eta))
        * (1.0 + 8.0 / 5.0 * eta * nu * g0)
        * (1.0 / g0 + 8.0 / 5.0 * eta * (3.0 * eta - 2.0) * nu)
        + 8.0 / (5.0 * SQPI) * eta * nu**2 * g0
    )
    f3 = 8.0 / (3.0 * SQPI) * eta * nu**2 * g0
    f4 = (
        25.0
        * SQPI
        / (16.0 * eta * (41.0 - 33.0 * eta))
        * (1.0 + 12.0 / 5.0 * eta * nu * g0)
        * (1.0 / g0 + 12.0 / 5.0 * eta**2 * (4.0 * eta - 3.0) * nu)
        + 4.0 / SQPI * eta * nu**2 * g0
    )
    f5 = 12.0 / SQPI * nu**2 * g0
    f6 = math.sqrt(3.0) * math.pi * nu * g0 / (2.0 * nu_m * f4)
    f7 = math.pi * nu * g0 / (2.0 * math.sqrt(3.0) * nu_m * f2)
    return dict(f1=f1, f2=f2, f3=f3, f4=f4, f5=f5, f6=f6, f7=f7, g0=g0)


def transport(model: ChuteModel, nu, T):
    """eq:pmuetc, etastar and gammastar from :func:`table1`."""
    f = table1(nu, model.restitution, model.nu_max, model.radial.name)
    e, phi, Phi = model.restitution, model.roughness, model.wall_loss
    sq = np.sqrt(T)
    return {
        "p": f["f1"] * T,
        "mu": f["f2"] * sq,
        "zeta": f["f3"] * sq,
        "kappa": f["f4"] * sq,
        "Gamma": (1.0 - e**2) * f["f5"] * T * sq,
        "kappa_h": 0.0 * T,  # the paper drops the κ_h∇ν heat flux (footnote to eq. 2.7)
        "Gamma_U": 0.0 * T,  # Lun et al.'s closure has no first-order cooling rate ζ_U∇·u
        "eta_star": phi * f["f7"] * f["f2"] * sq,
        "Gamma_star": 0.5 * Phi * f["f6"] * f["f4"] * T * sq,
    }


# ---------------------------------------------------------------------------------------
# (a) Partial derivatives against central finite differences.
# ---------------------------------------------------------------------------------------
# Step and tolerance. Each derivative of order n+1 is checked against a central difference
# of the *analytic* derivative of order n (so no second differences are taken). Steps are
# relative to the local length scale of the variable: L_ν = min(ν, ν_m − ν) (g0 ∝
# (1 − ν/ν_m)^(−2.5ν_m) is singular at ν_m, and ν is the scale at small ν) and L_T = T (all
# functions are powers T^a, a ≤ 3/2). With h = 1e-5 L:
#   truncation  h² |F'''| / 6 ≲ 1e-10 · O(10) · |F'|  (F''' / F' ~ (2.5ν_m+1)(2.5ν_m+2)/L²),
#   round-off   ε |F| / h ≈ 2e-16 / 1e-5 · |F|/L ≈ 2e-11 |F|/L (×~100 for lambdify's
#               operation count).
# Both are ≲ 1e-8 of the natural derivative scale |F'| + |F|/L, so a relative tolerance of
# 1e-6 on that scale leaves two orders of margin yet catches any wrong term (which would
# be O(1) wrong). The |F|/L part keeps the test meaningful where F' = 0 (e.g. the minimum
# of f2(ν), where a purely relative test on F' would be ill-posed).
H_REL = 1e-5
RTOL_FD = 1e-6


def _fd_check(an, fd, lower, scale, label):
    bound = RTOL_FD * (np.abs(an) + np.abs(lower) / scale)
    err = np.abs(fd - an)
    # where a function vanishes identically (κ_h of the paper's closure) bound and err are 0
    ratio = np.divide(err, bound, out=np.where(err > 0, np.inf, 0.0), where=bound > 0)
    worst = np.unravel_index(np.argmax(ratio), err.shape)
    assert np.all(err <= bound), (
        f"{label}: |fd - analytic| = {err[worst]:.3e} > "
        f"{bound[worst]:.3e} at index {worst} "
        f"(analytic {an[worst]:.10g}, fd {fd[worst]:.10g})"
    )


@pytest.mark.parametrize("name", sorted(MODELS))
def test_partials_match_finite_differences(name):
    model = MODELS[name]
    nu, t = _grid(model)
    L_nu = np.minimum(nu, model.nu_max - nu)
    h_nu, h_t = H_REL * L_nu, H_REL * t
    base = model.evaluate(nu, t)
    nu_p, nu_m = model.evaluate(nu + h_nu, t), model.evaluate(nu - h_nu, t)
    t_p, t_m = model.evaluate(nu, t + h_t), model.evaluate(nu, t - h_t)

    # (order checked, order differenced, variable): d/dν or d/dT of a lower order.
    chains = [
        ((1, 0), (0, 0), "nu"),
        ((0, 1), (0, 0), "T"),
        ((2, 0), (1, 0), "nu"),
        ((1, 1), (1, 0), "T"),
        ((1, 1), (0, 1), "nu"),
        ((0, 2), (0, 1), "T"),
    ]
    assert {c[0] for c in chains} | {(0, 0)} == set(ORDERS)
    for fname in FUNCTIONS:
        for target, lower, var in chains:
            if var == "nu":
                fd = (nu_p[fname][lower] - nu_m[fname][lower]) / (2 * h_nu)
                scale = L_nu
            else:
                fd = (t_p[fname][lower] - t_m[fname][lower]) / (2 * h_t)
                scale = t
            _fd_check(
                np.asarray(base[fname][target], float),
                fd,
                base[fname][lower],
                scale,
                f"{name}: {fname} {target} from d/d{var} of {lower}",
            )


@pytest.mark.parametrize("name", sorted(MODELS))
def test_table1_and_g0_derivatives_match_finite_differences(name):
    model = MODELS[name]
    nu = _grid(model)[0][:, 0]
    L = np.minimum(nu, model.nu_max - nu)
    h = H_REL * L
    f0, fp, fm = model.f(nu), model.f(nu + h), model.f(nu - h)
    g0, gp, gm = model.g0(nu), model.g0(nu + h), model.g0(nu - h)
    for key in [*sorted(f0), "g0"]:
        val, valp, valm = (g0, gp, gm) if key == "g0" else (f0[key], fp[key], fm[key])
        for n in (1, 2):
            fd = (valp[n - 1] - valm[n - 1]) / (2 * h)
            _fd_check(np.asarray(val[n], float), fd, val[n - 1], L, f"{name}: {key}^({n})")


# ---------------------------------------------------------------------------------------
# (b) Values: Table 1 transcription, eq:pmuetc forms, and the dilute limit ν → 0.
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(MODELS))
def test_values_match_table1_transcription(name):
    model = MODELS[name]
    nu, t = _grid(model)
    got = model.evaluate(nu, t)
    ref = transport(model, nu, t)
    for fname in FUNCTIONS:
        np.testing.assert_allclose(got[fname][(0, 0)], ref[fname], rtol=1e-11, atol=0, err_msg=fname)
    nus = nu[:, 0]
    f = model.f(nus)
    tab = table1(nus, model.restitution, model.nu_max, model.radial.name)
    for k in ("f1", "f2", "f3", "f4", "f5", "f6", "f7"):
        np.testing.assert_allclose(f[k][0], tab[k], rtol=1e-11, err_msg=k)
    np.testing.assert_allclose(model.g0(nus)[0], tab["g0"], rtol=1e-12)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_floor_terms_match_collision_rate_definition(name):
    """etastar, gammastar from η*|u_s| = (π/6) φ |u_s| Ω and eq:gammas, Ω = √(3T) ν g0/ν_m."""
    model = MODELS[name]
    nu, t = _grid(model)
    got = model.evaluate(nu, t)
    g0 = table1(nu, model.restitution, model.nu_max, model.radial.name)["g0"]
    omega = np.sqrt(3 * t) * nu * g0 / model.nu_max
    np.testing.assert_allclose(got["eta_star"][(0, 0)], math.pi / 6 * model.roughness * omega, rtol=1e-11)
    np.testing.assert_allclose(
        got["Gamma_star"][(0, 0)], model.wall_loss * math.pi / 6 * 1.5 * t * omega, rtol=1e-11
    )


@pytest.mark.parametrize("e", [0.3, 0.7, 0.95, 1.0])
def test_dilute_limit(e):
    """ν → 0 (g0 → 1): kinetic-gas values of Table 1, approached at rate O(ν)."""
    model = ChuteModel(restitution=e)
    eta = (1 + e) / 2
    limits = {
        "f1": (1, 1.0),  # f1/ν → 1
        "f2": (0, 5 * SQPI / (96 * eta * (2 - eta))),
        "f3": (2, 8 * eta / (3 * SQPI)),  # f3/ν² → 8η/(3√π)
        "f4": (0, 25 * SQPI / (16 * eta * (41 - 33 * eta))),
        "f5": (2, 12 / SQPI),  # f5/ν² → 12/√π
    }
    nus = np.array([1e-2, 1e-4, 1e-6, 1e-8])
    f = model.f(nus)
    for k, (power, lim) in limits.items():
        rel = np.abs(f[k][0] / nus**power / lim - 1)
        assert np.all(rel <= 20 * nus), (k, rel)  # O(ν) approach
        assert rel[-1] <= 1e-6, (k, rel[-1])
    g0 = model.g0(nus)[0]
    assert np.all(np.abs(g0 - 1) <= 3 * nus)  # g0 = 1 + 2.5 ν + O(ν²)
    # f6, f7 vanish ∝ ν with the slopes implied by their definitions.
    np.testing.assert_allclose(
        f["f6"][0][-1] / 1e-8, math.sqrt(3) * math.pi / (2 * model.nu_max * limits["f4"][1]), rtol=1e-6
    )
    np.testing.assert_allclose(
        f["f7"][0][-1] / 1e-8, math.pi / (2 * math.sqrt(3) * model.nu_max * limits["f2"][1]), rtol=1e-6
    )


@pytest.mark.parametrize("name", sorted(MODELS))
def test_transport_forms_eq_pmuetc(name):
    """p = f1 T, μ = f2 √T, ζ = f3 √T, κ = f4 √T, Γ = (1−e²) f5 T^{3/2}; η*, Γ* likewise."""
    model = MODELS[name]
    nu, t = _grid(model)
    got = model.evaluate(nu, t)
    f = {k: v[0] for k, v in model.f(nu).items()}
    e, phi, Phi = model.restitution, model.roughness, model.wall_loss
    forms = {
        "p": f["f1"] * t,
        "mu": f["f2"] * t**0.5,
        "zeta": f["f3"] * t**0.5,
        "kappa": f["f4"] * t**0.5,
        "Gamma": (1 - e**2) * f["f5"] * t**1.5,
        "eta_star": phi * f["f7"] * f["f2"] * t**0.5,
        "Gamma_star": 0.5 * Phi * f["f6"] * f["f4"] * t**1.5,
    }
    for k, v in forms.items():
        np.testing.assert_allclose(got[k][(0, 0)], v, rtol=1e-12, err_msg=k)


# ---------------------------------------------------------------------------------------
# (c) Parameter validation.
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "name", "rng"),
    [
        ({"restitution": 1.5}, "restitution", "(0, 1]"),
        ({"restitution": 0.0}, "restitution", "(0, 1]"),
        ({"restitution": -0.2}, "restitution", "(0, 1]"),
        ({"restitution": float("nan")}, "restitution", "(0, 1]"),
        ({"nu_max": 0.0}, "nu_max", "(0, 0.74048]"),
        ({"nu_max": 0.8}, "nu_max", "(0, 0.74048]"),
        ({"roughness": 0.0}, "roughness", "(0, inf)"),
        ({"roughness": -0.05}, "roughness", "(0, inf)"),
        ({"roughness": float("nan")}, "roughness", "(0, inf)"),
        ({"wall_loss": -0.01}, "wall_loss", "[0, 1]"),
        ({"wall_loss": 1.01}, "wall_loss", "[0, 1]"),
    ],
)
def test_invalid_parameters_raise(kwargs, name, rng):
    with pytest.raises(ParameterError) as info:
        ChuteModel(**kwargs)
    msg = str(info.value)
    assert msg.startswith(name), msg
    assert rng in msg, msg
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, ChuteflowError)


def test_non_numeric_parameter_raises():
    with pytest.raises(ParameterError, match="restitution"):
        ChuteModel(restitution="abc")


def test_infinite_roughness_raises():
    with pytest.raises(ParameterError, match="roughness"):
        ChuteModel(roughness=float("inf"))


@pytest.mark.parametrize("value", ["0.7", True, None])
def test_parameter_types_are_checked(value):
    with pytest.raises(ParameterError, match="restitution"):
        ChuteModel(restitution=value)


def test_parameters_stored_as_float_and_partials_float():
    m = ChuteModel(restitution=1, roughness=np.float32(0.05))
    assert type(m.restitution) is float
    assert type(m.roughness) is float
    ev = m.evaluate([0.1, 0.2], 1.0)
    assert all(a.dtype == float for f in ev.values() for a in f.values())


@pytest.mark.parametrize(
    "kwargs",
    [
        {"restitution": 1.0},
        {"restitution": 1e-3},
        {"nu_max": 0.74048},
        {"roughness": 10.0},
        {"wall_loss": 0.0},
        {"wall_loss": 1.0},
    ],
)
def test_valid_edge_parameters_accepted(kwargs):
    ChuteModel(**kwargs)


# ---------------------------------------------------------------------------------------
# (d) Johnson–Jackson identities behind eq:T0b and eq:dT0b.
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(MODELS))
def test_johnson_jackson_identities(name):
    """η*/μ = φ f7 and f6 f4 / 3 = f7 f2 (both = π ν g0 / (2√3 ν_m))."""
    model = MODELS[name]
    nu, t = _grid(model)
    got = model.evaluate(nu, t)
    f = {k: v[0] for k, v in model.f(nu).items()}
    np.testing.assert_allclose(
        got["eta_star"][(0, 0)] / got["mu"][(0, 0)], model.roughness * f["f7"], rtol=1e-12
    )
    np.testing.assert_allclose(f["f6"] * f["f4"] / 3, f["f7"] * f["f2"], rtol=1e-12)


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("theta_deg", [12.0, 16.0, 25.0])
def test_floor_conditions_reduce_to_eq_T0b_dT0b(name, theta_deg):
    """eq:bc1 + eq:u00 give eq:T0b; eq:bc2 + eq:bc1 give eq:dT0b.

    Floor normal n = +y, Σ = p I − 2μS, q = −κ∇T, so at y = 0:
    bc1: μ u0' = η* u0;   bc2: −κ T0' = μ u0 u0' − Γ*.
    """
    model = MODELS[name]
    tan = math.tan(math.radians(theta_deg))
    phi, Phi = model.roughness, model.wall_loss
    nu = np.array([0.02, 0.05, 0.1, 0.2, 0.3, 0.45])
    nu = nu[nu < 0.9 * model.nu_max]
    u0 = np.array([0.5, 3.0, 20.0])[:, None]
    f = {k: v[0] for k, v in model.f(nu).items()}

    # eq:T0b, then check bc1 with u0' from eq:u00.
    T0 = (phi * f["f2"] * f["f7"] / (f["f1"] * tan) * u0) ** 2
    ev = model.evaluate(nu, T0)
    du0 = f["f1"] * np.sqrt(T0) / f["f2"] * tan  # eq:u00
    np.testing.assert_allclose(ev["mu"][(0, 0)] * du0, ev["eta_star"][(0, 0)] * u0, rtol=1e-12)

    # eq:dT0b from bc2 with u0' from bc1, at arbitrary T (not only T0b).
    T = np.array([0.01, 1.0, 7.0])[:, None, None]
    ev = model.evaluate(nu, T)
    du0 = ev["eta_star"][(0, 0)] * u0 / ev["mu"][(0, 0)]  # bc1
    dT_bc2 = (ev["Gamma_star"][(0, 0)] - ev["mu"][(0, 0)] * u0 * du0) / ev["kappa"][(0, 0)]
    dT_paper = -f["f6"] * (phi * u0**2 / 3 - 0.5 * Phi * T)  # eq:dT0b
    np.testing.assert_allclose(dT_bc2, dT_paper, rtol=1e-11, atol=1e-14)
