"""The 1D model of §5.1.2: functions from the steady family and its analytic linear theory."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.errors import NoSteadyFlowError, ParameterError
from chuteflow.reduced import LocalCoefficients, local_coefficients, reduced_model


def _state(rho0=0.5, a=0.02, U=8.0, dU=5.0, Tbar=1.5, dTbar=-2.0, mu=0.3, theta=16.0):
    """A manufactured uniform state with prescribed a, U, U', T̄, T̄', μ̄ (for pure algebra)."""
    s = math.sin(math.radians(theta))
    a = rho0 * s / U  # U = ρ0 sinθ / a
    da = (s / a - dU) * a**2 / (rho0 * s)  # U' = sinθ/a − ρ0 sinθ a'/a²
    return LocalCoefficients(
        theta=theta, rho0=rho0, F=0.1, dF=0.2, Tbar=Tbar, dTbar=dTbar, a=a, da=da, mu_bar=mu, dmu_bar=0.0
    )


STATES = [
    _state(),
    _state(dU=-3.0, dTbar=-10.0),
    _state(dU=0.5, dTbar=0.5),
    _state(rho0=1.3, dU=2.0, dTbar=-0.6, mu=0.05),
    _state(rho0=0.2, dU=1.0, dTbar=1.0),
]


def test_manufactured_states_have_the_prescribed_slopes():
    c = _state(U=8.0, dU=5.0)
    assert c.U == pytest.approx(8.0, rel=1e-14)
    assert c.dU == pytest.approx(5.0, rel=1e-12)


@pytest.mark.parametrize("c", STATES)
def test_dispersion_closed_form_is_the_eigenvalues_of_the_2x2_matrix(c):
    # analytic identity: α = −ikU + λ, λ² + bλ + c = 0 are the eigenvalues of M(k)
    k = np.logspace(-6, 1.5, 60)
    closed = c.dispersion(k)
    eig = np.linalg.eigvals(c.matrix(k))
    eig = np.take_along_axis(eig, np.argsort(-eig.real, axis=-1), axis=-1)
    scale = np.abs(eig).max(axis=-1, keepdims=True)
    assert np.abs(closed - eig).max() / scale.min() < 1e-9
    # least stable first, and the small-k root without cancellation: α(k) ≈ −i k dq0/dρ0
    assert (closed[:, 0].real >= closed[:, 1].real).all()
    assert abs(closed[0, 0] / k[0] - c.alpha1 - c.alpha2 * k[0]) < 1e-6 * abs(c.alpha1)


@pytest.mark.parametrize("c", STATES)
def test_condition_with_errata_is_exactly_the_sign_of_the_growth_rate(c):
    # ERRATA 4: (aU')² k² > ((a + μ̄k²)/ρ0)² (ρ0T̄)' k² ⇔ Re α(k) > 0 for every k
    k = np.logspace(-4, 1.2, 400)
    g = c.growth_rate(k)
    clear = np.abs(g) > 1e-12 * np.abs(c.dispersion(k)).max(axis=-1)
    assert clear.sum() > 300
    assert np.array_equal(c.condition(k)[clear], (g > 0)[clear])


def test_printed_condition_differs_from_the_exact_one_at_finite_k():
    # the paper's (a/ρ0 + μ̄k²)² agrees only when ρ0 = 1 or k → 0: ERRATA item 4
    c = _state(rho0=0.5, dU=5.0, dTbar=-2.0)
    assert c.dP > 0
    assert c.unstable
    k = np.linspace(0.01, 3 * c.k_c, 2000)
    exact = c.growth_rate(k) > 0
    printed = c.condition(k, errata=False)
    wrong = exact != printed
    assert wrong.any()
    # …and only near the critical wavenumber (the O(k⁴) term), not at small k
    assert k[wrong].min() > 0.5 * c.k_c
    assert np.array_equal(c.condition(k[:20], errata=False), exact[:20])


@pytest.mark.parametrize("c", [s for s in STATES if s.unstable and s.dP > 0])
def test_k_c_is_the_neutral_wavenumber(c):
    kc = c.k_c
    assert 0 < kc < math.inf
    scale = abs(c.dispersion(kc)[0])
    assert abs(c.growth_rate(kc)) < 1e-10 * scale
    assert c.growth_rate(0.999 * kc) > 0 > c.growth_rate(1.001 * kc)
    assert c.L_c == pytest.approx(2 * math.pi / kc)
    kmax, smax = c.most_unstable()
    assert 0 < kmax < kc
    assert smax >= c.growth_rate(np.linspace(1e-4, kc, 500)).max() - 1e-12


def test_short_wave_unstable_and_stable_states():
    c = _state(dU=-3.0, dTbar=-10.0)  # (ρ0 T̄)' < 0
    assert c.short_wave_unstable
    assert c.unstable
    assert c.k_c == math.inf
    assert c.L_c == 0.0
    k = np.logspace(-3, 3, 50)
    assert (c.growth_rate(k) > 0).all()
    # the growth rate saturates at ρ0 |(ρ0T̄)'| / μ̄ for k → ∞
    assert c.growth_rate(1e5) == pytest.approx(c.rho0 * abs(c.dP) / c.mu_bar, rel=1e-6)
    s = _state(dU=0.5, dTbar=0.5)
    assert not s.unstable
    assert s.k_c == 0.0
    assert s.L_c == math.inf
    assert (s.growth_rate(k) < 0).all()


@pytest.mark.parametrize("c", STATES)
def test_long_wave_expansion_disp_oned(c):
    # label disp-oned: α = −i (ρ0U)' k + (ρ0/a)[(ρ0U')² − (ρ0T̄)'] k² + O(k³)
    k1, k2 = 1e-3, 1e-4
    b = c.a / c.rho0
    k1, k2 = 1e-3 * b / (1 + abs(c.dU) + abs(c.dP)), 1e-4 * b / (1 + abs(c.dU) + abs(c.dP))
    e1 = abs(c.dispersion(k1)[0] - c.alpha1 * k1 - c.alpha2 * k1**2)
    e2 = abs(c.dispersion(k2)[0] - c.alpha1 * k2 - c.alpha2 * k2**2)
    assert 300 < e1 / e2 < 3000  # third order: a factor 1000 per decade of k
    # phase velocity Im α / k → −dq0/dρ0, q0 = ρ0 U(ρ0): the kinematic wave (§5.1.1)
    assert c.dispersion(k2)[0].imag / k2 == pytest.approx(-c.dq0, rel=1e-6)
    assert c.phase_velocity == c.dq0  # c = −Im α1 (chuteflow.conventions)
    assert (c.alpha2 > 0) == c.unstable


def test_knots_reproduce_the_exact_coefficients(rm16):
    for c in rm16.coefficients_at_knots:
        i = rm16.coefficients(c.rho0)
        for name in ("F", "dF", "Tbar", "dTbar", "a", "da"):
            assert getattr(i, name) == pytest.approx(getattr(c, name), rel=1e-12, abs=1e-14)


def test_interpolation_error_measured_and_within_tolerance(rm16):
    acc = rm16.accuracy
    assert acc["midpoints"] == len(rm16.rho) - 1
    assert max(acc["F"], acc["Tbar"], acc["a"]) <= 1e-4  # reduced_model's default tol
    assert max(acc["dF"], acc["dTbar"], acc["da"]) < 1e-2


def test_interpolants_against_an_independent_solve(rm16):
    # a floor density that is neither a knot nor a checked midpoint
    from chuteflow.steady import solve_steady

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        flow = solve_steady(16.0, 0.1234, ChuteModel())
    exact = local_coefficients(flow)
    interp = rm16.coefficients(flow.rho_bar)
    for name in ("F", "Tbar", "a"):  # Hermite cubic: error O(Δρ̄⁴), measured ≤ 1e-4
        assert getattr(interp, name) == pytest.approx(getattr(exact, name), rel=3e-4)
    for name in ("dF", "dTbar", "da", "dU"):  # slopes O(Δρ̄³)
        assert getattr(interp, name) == pytest.approx(getattr(exact, name), rel=1e-2)
    assert rm16.rho_at_nu0(0.1234) == pytest.approx(flow.rho_bar, rel=3e-4)


def test_tangent_slopes_against_central_differences_of_direct_solves():
    # F' = 1/(dρ̄/dβ), T̄' and a' from the exact tangent vs independent solves at β ± δ
    from chuteflow.steady import solve_steady

    m = ChuteModel()
    beta, d = 0.1, 1e-4
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        f0, fp, fm = (solve_steady(16.0, b, m, rtol=1e-10) for b in (beta, beta + d, beta - d))
    c = local_coefficients(f0)
    drho = fp.rho_bar - fm.rho_bar
    assert c.dF == pytest.approx(2 * d / drho, rel=1e-5)  # truncation O(δ²) ~ 1e-7
    assert c.dTbar == pytest.approx((fp.T_mean - fm.T_mean) / drho, rel=1e-5)
    eta = [float(m.evaluate(f.nu0, f.T_mean)["eta_star"][(0, 0)]) for f in (fp, fm)]
    assert c.da == pytest.approx((eta[0] - eta[1]) / drho, rel=1e-5)
    # a = η*(ν0(0), T̄0) (oneaandu) and U = ρ̄ sinθ / a
    assert c.a == pytest.approx(float(m.evaluate(beta, f0.T_mean)["eta_star"][(0, 0)]))
    assert c.U == pytest.approx(f0.rho_bar * math.sin(math.radians(16.0)) / c.a)
    # μ̄ = (4/3) f2(0) H(T̄) √T̄, H = T̄/cosθ
    f20 = float(m.f(0.0)["f2"][0])
    assert c.mu_bar == pytest.approx(4 / 3 * f20 * c.Tbar**1.5 / math.cos(math.radians(16.0)))


def test_functions_are_consistent(rm16):
    r = np.linspace(*rm16.rho_range, 50)
    s = math.sin(math.radians(16.0))
    assert np.allclose(rm16.U(r), r * s / rm16.a(r), rtol=1e-14)
    assert np.allclose(rm16.P(r), r * rm16.Tbar(r), rtol=1e-14)
    # a(ρ̄) interpolated on its own agrees with η*(F(ρ̄), T̄(ρ̄)) to the interpolation error
    eta = ChuteModel().evaluate(rm16.F(r), rm16.Tbar(r))["eta_star"][(0, 0)]
    assert np.allclose(rm16.a(r), eta, rtol=3e-4)
    # derivatives are the derivatives: compare with central differences of the interpolants
    h = 1e-6
    rr = r[1:-1]
    for fn in (rm16.F, rm16.Tbar, rm16.a, rm16.U, rm16.P, rm16.mu_bar):
        fd = (fn(rr + h) - fn(rr - h)) / (2 * h)
        assert np.allclose(fn(rr, 1), fd, rtol=1e-5, atol=1e-9)


def test_outside_the_family_is_an_error_naming_the_range(rm16):
    lo, hi = rm16.rho_range
    with pytest.raises(NoSteadyFlowError, match="outside"):
        rm16.F(hi * 1.01)
    with pytest.raises(NoSteadyFlowError, match="steady family"):
        rm16.coefficients(lo * 0.5)
    with pytest.raises(ParameterError, match="nu0"):
        rm16.rho_at_nu0(0.3)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"theta": 95.0}, "theta"),
        ({"theta": 16.0, "nu0_min": 0.3, "nu0_max": 0.2}, "nu0_min"),
        ({"theta": 16.0, "tol": 0.5}, "tol"),
    ],
)
def test_bad_parameters(kw, match):
    theta = kw.pop("theta")
    with pytest.raises(ParameterError, match=match):
        reduced_model(theta, ChuteModel(), **kw)


def test_table_and_summary(rm16):
    ds = rm16.table(20)
    assert {"F", "Tbar", "a", "U", "criterion_margin", "k_c"} <= set(ds.data_vars)
    assert ds.attrs["theta"] == 16.0
    s = rm16.to_dict()
    assert s["knots"] == len(rm16.rho)
    assert s["rho_range"][0] == rm16.rho_range[0]


def test_rho_at_nu0_is_exact_at_every_knot(rm16):
    # the ends of the family are knots; F(ρ̄_k) − ν0_k is round-off there (issue: P4 printed
    # scipy's "f(a) and f(b) must have different signs" at the family's lowest knot)
    for r, nu in zip(rm16.rho, rm16.nu0):
        assert rm16.rho_at_nu0(float(nu)) == r
        # one ulp beside a knot: still answers, within round-off of the knot
        for x in (np.nextafter(nu, 0.0), np.nextafter(nu, 1.0)):
            if rm16.nu0[0] <= x <= rm16.nu0[-1]:
                assert rm16.rho_at_nu0(float(x)) == pytest.approx(r, rel=1e-12)


# Off the paper: at θ = 16.237°, φ = 0.0469, Φ = 0.322, e_p = 0.86 the steady flows exist only
# for ν0(0) ≲ 0.025 (`chuteflow steady` solves 0.005 … 0.0245 and finds no flow at 0.026 and
# above; ν0(0) = 0.0251 is the family's unresolved end). Seen with try-random-points style
# checks: `chuteflow reduced --nu0 0.0219` answered "no steady flow to build the 1D model on".
_LOW = ChuteModel(roughness=0.0469, wall_loss=0.322, restitution=0.86)


def test_family_is_found_where_no_default_seed_has_a_flow():
    # every default seed (0.03 … 0.3) lies beyond the family; the ln ν0 scan finds it
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        rm = reduced_model(16.237, _LOW, tol=1e-3)
    assert rm.nu0[0] == 0.005  # down to the requested bound
    assert 0.024 < rm.nu0[-1] < 0.026  # up to the family's end
    # the end is the steady solver's own verdict at the next density (one clause)
    assert rm.ends[1].startswith("no steady flow found beyond nu0 = 0.02")
    assert "steady solver did not converge although shooting finds a solution" in rm.ends[1]


def test_walk_goes_on_where_continuation_stalls_inside_the_family():
    # from ν0(0) = 0.0219 (the user's point first, as the CLI does) Newton from the
    # neighbour stalls both ways although each flow solves alone: the walk asks the steady
    # solver there instead of ending the family (it was "too short": 1 flow)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        rm = reduced_model(16.237, _LOW, tol=1e-3, seeds=(0.0219,))
    assert rm.nu0[0] == 0.005
    assert 0.024 < rm.nu0[-1] < 0.026
    c = rm.coefficients(rm.rho_at_nu0(0.0219))
    assert np.isfinite(c.alpha2)
    assert c.rho0 > 0


def test_no_family_at_all_is_one_clear_error():
    with pytest.raises(NoSteadyFlowError, match=r"none at \d+ floor densities nu0 in \[0.005, 0.45\]"):
        reduced_model(30.0, ChuteModel())
