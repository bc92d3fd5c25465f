"""Steady solver (paper §3): analytic identities, independent shooting, convergence, errors.

Tolerances come from the convergence study in ``test_convergence_*`` (changes ≲ 1e-10 when
the resolution or tolerance is tightened) and from the agreement with the independent
shooting solution (≲ 1e-10 relative, the shooting's own rtol-stability being ~1e-12).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.errors import ConvergenceError, NoSteadyFlowError, ParameterError
from chuteflow.steady import solve_steady, steady_tangent
from chuteflow.steady.state import state_of
from chuteflow.steady.tangent import state_tangent_vectors, tangent_from, tangent_vectors

from .shooting import Material, solve_by_shooting

KEYS = ("u_floor", "T_floor", "h", "nu_mean", "rho_bar", "Q", "y_max")


@pytest.fixture(scope="module")
def p1():
    """θ = 16°, ν0(0) = 0.05, φ = 0.05: the paper's main example (P1)."""
    return solve_steady(16.0, 0.05)


@pytest.fixture(scope="module")
def dense():
    """θ = 16°, ν0(0) = 0.15: non-monotonic, density maximum above the floor."""
    return solve_steady(16.0, 0.15)


def _table(model, nu):
    f = model.f(nu)
    return {k: float(v[0]) for k, v in f.items()}


@pytest.mark.parametrize("which", ["p1", "dense"])
def test_floor_conditions_T0b_dT0b(which, request):
    """eq:T0b T0 = (φ f2 f7 u0 / (f1 tanθ))² and eq:dT0b T0' = −f6 (φ u0²/3 − Φ T0/2) at
    y = 0 (analytic consequences of eq:bc1, eq:bc2 and eq:steady4). The solver imposes
    eq:bc1/eq:bc2 and eq:steady4 at different nodes, so the identities hold to the
    discretisation error (< 1e-9 by the convergence study)."""
    f = request.getfixturevalue(which)
    m = f.model
    t = _table(m, f.nu0)
    tan = math.tan(math.radians(f.theta))
    T0b = (m.roughness * t["f2"] * t["f7"] * f.u_floor / (t["f1"] * tan)) ** 2
    assert abs(f.T_floor - T0b) < 1e-9 * f.T_floor
    dT = f.derivatives()["T_y"][0]
    dT0b = -t["f6"] * (m.roughness * f.u_floor**2 / 3 - 0.5 * m.wall_loss * f.T_floor)
    assert abs(dT - dT0b) < 1e-9 * max(abs(dT0b), f.T_floor)


def test_floor_and_top_values(p1):
    """ν0(0) = nu0 exactly, ν0(y_max) = ν_top, and |T0'(y_max)| < 1e-7 (issue 2)."""
    assert p1.nu[0] == pytest.approx(0.05, rel=1e-13)
    assert p1.nu[-1] == pytest.approx(1e-9, rel=1e-10)
    assert abs(p1.derivatives()["T_y"][-1]) < 1e-7


@pytest.mark.parametrize("which", ["p1", "dense"])
def test_momentum_identity_steady4(which, request):
    """eq:steady4, Σxy = −tanθ Σyy, i.e. μ u0' = tanθ p at every node including the floor
    (where it is not imposed directly), relative to the floor stress."""
    f = request.getfixturevalue(which)
    ev = f.model.evaluate(f.nu, f.T)
    lhs = ev["mu"][(0, 0)] * f.derivatives()["u_y"]
    rhs = math.tan(math.radians(f.theta)) * ev["p"][(0, 0)]
    assert np.abs(lhs - rhs).max() < 1e-9 * rhs[0]


@pytest.mark.parametrize("which", ["p1", "dense"])
def test_rho_bar_is_floor_pressure(which, request):
    """Integrating eq:steady2 from 0 to ∞: ρ̄0 = p(0)/cosθ. The solver's ρ̄0 is a quadrature
    of ν0 plus the tail above y_max, so this checks the quadrature and the tail term."""
    f = request.getfixturevalue(which)
    p0 = float(f.model.evaluate(f.nu0, f.T_floor)["p"][(0, 0)])
    assert f.rho_bar == pytest.approx(p0 / math.cos(math.radians(f.theta)), rel=1e-10)


def test_profiles_shape(p1, dense):
    """fig steady(a): ν0(0) = 0.05 decays monotonically, 0.15 has its maximum above the
    floor (paper: 'the maximum density appears at a finite height')."""
    assert p1.monotonic
    assert p1.y_peak == 0.0
    assert not dense.monotonic
    assert 0.5 < dense.y_peak < 3.0
    assert dense.nu_peak > 0.15
    y = np.linspace(0, dense.y_max, 2001)
    nu = dense.profiles(y)["nu"]
    assert y[np.argmax(nu)] == pytest.approx(dense.y_peak, abs=dense.y_max / 1000)


def test_against_independent_shooting(p1):
    """ρ̄0 (tail included), Q0, u0(0), T0(0), h against the paper's method done independently
    (tests/steady/shooting.py: Table 1 transcribed again, solve_ivp DOP853 rtol 1e-11 and
    brentq on u0(0) by the sign of T0'). The shooting result is stable to ~1e-12 under its
    rtol and independent of ν_top; the two agree to 1e-10 (measured 3e-12 … 3e-11)."""
    s = solve_by_shooting(16.0, 0.05, Material())
    for k in ("u_floor", "T_floor", "rho_bar", "Q", "h"):
        assert getattr(p1, k) == pytest.approx(getattr(s, k), rel=1e-10), k


@pytest.mark.slow
@pytest.mark.parametrize(
    ("theta", "nu0", "phi"), [(16.0, 0.10, 0.05), (14.0, 0.08, 0.05), (20.0, 0.10, 0.10)]
)
def test_against_independent_shooting_more(theta, nu0, phi):
    f = solve_steady(theta, nu0, ChuteModel(roughness=phi))
    s = solve_by_shooting(theta, nu0, Material(phi=phi))
    for k in ("u_floor", "T_floor", "rho_bar", "Q", "h"):
        assert getattr(f, k) == pytest.approx(getattr(s, k), rel=1e-9), k


def test_convergence_under_resolution_and_tolerance(p1):
    """Tightening rtol (1e-8 → 1e-10) or starting from a finer grid (n 64 → 96) changes the
    scalars by < 1e-9 relative (measured ≲ 1e-10): ≥ 8 significant digits."""
    for kw in ({"rtol": 1e-10}, {"n": 96}):
        g = solve_steady(16.0, 0.05, **kw)
        for k in KEYS:
            assert getattr(g, k) == pytest.approx(getattr(p1, k), rel=1e-9), (kw, k)
    assert p1.convergence < 1e-8
    assert p1.spectral_tail < 1e-12


def test_independent_of_domain_top(p1):
    """The weight of the tail above y_max is kept (eq:steady4 integrated to ∞), so moving
    the top from ν_top = 1e-9 to 1e-11 changes the floor values, ρ̄0, Q0 and h by < 1e-9
    (measured ~1e-11); y_max itself moves (by ≈ ln(100) decay lengths)."""
    g = solve_steady(16.0, 0.05, nu_top=1e-11)
    for k in ("u_floor", "T_floor", "h", "rho_bar", "Q"):
        assert getattr(g, k) == pytest.approx(getattr(p1, k), rel=1e-9), k
    assert g.y_max > p1.y_max + 10


def test_tangent_against_finite_differences(p1):
    """steady_tangent (exact, J dX/dβ = −∂R/∂β) against central differences of solve_steady
    with δ = 1e-5: truncation O(δ²) ~ 1e-10 relative, noise ~1e-11/δ ~ 1e-6; agreement
    to 1e-5 relative."""
    t = steady_tangent(p1)
    d = 1e-5
    fp = solve_steady(16.0, 0.05 + d, guess=p1)
    fm = solve_steady(16.0, 0.05 - d, guess=p1)
    for k in ("rho_bar", "Q", "h", "u_floor", "T_floor"):
        fd = (getattr(fp, k) - getattr(fm, k)) / (2 * d)
        assert t["d" + k] == pytest.approx(fd, rel=1e-5), k
    dq = (fp.Q - fm.Q) / (fp.rho_bar - fm.rho_bar)
    assert t["dQ_drho"] == pytest.approx(dq, rel=1e-5)
    # nodal tangent of u0(0) and y_max
    assert t["u"][0] == pytest.approx((fp.u_floor - fm.u_floor) / (2 * d), rel=1e-5)
    assert t["y_max"] == pytest.approx((fp.y_max - fm.y_max) / (2 * d), rel=1e-5)


def test_tangent_is_cached_and_protected(p1):
    """steady_tangent is computed once per flow (sweep metrics share it): a second call
    returns the same arrays, which are read-only, and replacing a key in the returned dict
    does not reach the cache."""
    t1 = steady_tangent(p1)
    t2 = steady_tangent(p1)
    assert t1["u"] is t2["u"]
    with pytest.raises(ValueError, match="read-only"):
        t1["u"][0] = 0.0
    t1["dQ_drho"] = 0.0
    assert steady_tangent(p1)["dQ_drho"] == t2["dQ_drho"] != 0.0
    # the cached tangent may come from Newton's last LU (test below): the same to 1e-8
    fresh = tangent_from(p1, tangent_vectors(p1, theta=False)[0])
    np.testing.assert_allclose(t2["T"], fresh["T"], rtol=0, atol=1e-8 * np.abs(fresh["T"]).max())


def test_newton_tangent_matches_a_fresh_factorisation():
    """dX/dβ from Newton's last LU (a second right-hand side; solve_point keeps it when the
    last step after that LU is below TANGENT_STEP = 1e-10) against a new LU of the exact
    Jacobian at the flow (tangent_vectors), along a family at θ = 16°: measured at most
    2.2e-9 relative (max norm) over 127 flows of θ = 12 … 18°, ν0(0) = 0.01 … 0.25 (and
    at most 2.6e-8 in dQ0/dρ̄0): 1e-8 leaves a margin of four. A state converged from
    itself (min_iter = 1: the LU is taken at the solution) agrees to round-off."""
    from chuteflow.steady import tangent
    from chuteflow.steady.one_grid import solve_state
    from chuteflow.steady.options import Options
    from chuteflow.steady.rows import continue_row

    pts = continue_row(16.0, np.geomspace(0.03, 0.2, 10), ChuteModel(), Options(tangent=False))
    flows = [p.flow for p in pts if p.flow is not None]
    stored = [(f, dX) for f in flows if (dX := tangent._BETA_TANGENTS.get(f)) is not None]
    assert len(flows) == 10
    assert len(stored) >= 5
    for f, dX in stored:
        fresh = tangent_vectors(f, theta=False)[0]
        assert np.abs(dX - fresh).max() <= 1e-8 * np.abs(fresh).max()
    f = flows[3]
    st, _, _ = solve_state(
        f.theta, f.nu0, f.model, f.nu_top, f.n, guess=state_of(f), tangents=True, min_iter=1
    )
    d_beta, step = st.tangents
    ref = state_tangent_vectors(f.theta, f.nu0, f.model, f.nu_top, st, theta=False)[0]
    assert step < 1e-10
    assert np.abs(d_beta - ref).max() <= 1e-9 * np.abs(ref).max()


def _counting_lu():
    """A patch of the chord Newton's LU (steady.linear._lu_factor) that counts its calls."""
    from unittest import mock

    from chuteflow.steady import linear

    calls = [0]
    factor = linear._lu_factor

    def counted(A):
        calls[0] += 1
        return factor(A)

    return mock.patch.object(linear, "_lu_factor", counted), calls


@pytest.mark.parametrize(("theta", "nu0"), [(16.0, 0.05), (17.0, 0.12), (14.5, 0.1)])
def test_chord_newton_matches_full_newton(theta, nu0):
    """Newton with chord steps (the continuation road: the last LU reused while each step
    lowers the residual ≥ 10 times, down to a tenth of tol or the round-off floor) reaches
    the state of full Newton from the same guess (a neighbour's flow at ν0(0) − 0.002) to
    round-off: measured 4.4e-11, 2.2e-11, 2.2e-11 relative (max norm; both end at scaled
    residuals of 5e-12 … 7e-11, the floor at n = 96), so 1e-9 leaves a margin of twenty;
    with fewer LUs than full Newton's steps."""
    from chuteflow.steady.one_grid import solve_state
    from chuteflow.steady.state import resample

    model = ChuteModel()
    g = resample(state_of(solve_steady(theta, nu0 - 0.002)), 96)
    a, steps, _ = solve_state(theta, nu0, model, 1e-9, 96, guess=g, grid_map=g.grid_map)
    patch, lus = _counting_lu()
    with patch:
        b, _, res = solve_state(theta, nu0, model, 1e-9, 96, guess=g, grid_map=g.grid_map, chord=True)
    X, Y = a.pack(), b.pack()
    assert np.abs(X - Y).max() <= 1e-9 * np.abs(X).max()
    assert res < 1e-10  # at the floor (Newton's own acceptance: step < 1e-11 there)
    assert 1 <= lus[0] < steps


def test_map_rows_reuse_the_neighbours_lu():
    """Without exact dX/dβ for the flows (``Options.beta_tangents = False``, the steady map)
    every rung of a continuation step starts its chord steps from the LU of the neighbour's
    solve, so a row takes fewer factorisations (θ = 16°, 12 flows: measured 33 instead of 41)
    and gives the same flows to round-off (Q0: measured 3.6e-11 relative; 1e-9 leaves a
    margin of thirty, far below rtol = 1e-8)."""
    from chuteflow.steady.options import Options
    from chuteflow.steady.rows import continue_row

    nus = np.geomspace(0.03, 0.2, 12)
    rows, counts = [], []
    for exact in (True, False):
        patch, lus = _counting_lu()
        with patch:
            rows.append(continue_row(16.0, nus, ChuteModel(), Options(tangent=False, beta_tangents=exact)))
        counts.append(lus[0])
    exact_row, map_row = rows
    assert [p.status for p in exact_row] == [p.status for p in map_row] == ["ok"] * 12
    assert counts[1] < counts[0]
    for p, q in zip(exact_row, map_row):
        assert abs(p.flow.Q - q.flow.Q) <= 1e-9 * abs(p.flow.Q)


def test_equal_flows_keep_their_own_newton_tangent():
    """Two flows equal in value (the same cold start solved twice, as a marked point and
    its grid point by two tasks in the threads of one Dask worker) each keep Newton's
    dX/dβ: one of them dying does not take the other's, so both tangents come from Newton's
    LU, whichever order they are used in (they differed by 2e-10 in dQ0/dρ̄0 when a
    value-keyed store dropped the entry with the first flow: tests/sweep/test_dask.py)."""
    import gc

    from chuteflow.steady import tangent

    f1, f2 = solve_steady(16.0, 0.05), solve_steady(16.0, 0.05)
    assert f1 == f2
    assert f1 is not f2
    assert tangent._BETA_TANGENTS.get(f1) is not None
    assert tangent._BETA_TANGENTS.get(f2) is not None
    expected = tangent_from(f2, tangent._BETA_TANGENTS.get(f2))["dQ_drho"]
    del f1
    gc.collect()
    assert tangent._BETA_TANGENTS.get(f2) is not None
    assert steady_tangent(f2)["dQ_drho"] == expected


def test_guess_gives_same_solution(p1):
    """Continuation from a neighbour converges to the same flow as the cold start."""
    g = solve_steady(16.0, 0.06)
    c = solve_steady(16.0, 0.06, guess=p1)
    for k in KEYS:
        assert getattr(c, k) == pytest.approx(getattr(g, k), rel=1e-9), k


@pytest.mark.parametrize(
    ("theta", "nu0", "match"),
    [
        (16.0, 0.6, "nu0"),
        (16.0, 0.7, "nu0"),
        (16.0, 0.0, "nu0"),
        (16.0, -0.1, "nu0"),
        (0.0, 0.05, "theta"),
        (-5.0, 0.05, "theta"),
        (90.0, 0.05, "theta"),
        (float("nan"), 0.05, "theta"),
        ("abc", 0.05, "number"),
    ],
)
def test_parameter_errors(theta, nu0, match):
    with pytest.raises(ParameterError, match=match):
        solve_steady(theta, nu0)


def test_parameter_error_nu_top():
    with pytest.raises(ParameterError, match="nu_top"):
        solve_steady(16.0, 0.05, nu_top=0.01)


def test_no_steady_flow_angle_too_small():
    """θ = 12°, ν0(0) = 0.1 (φ = 0.05): the layer collapses (decay length below one
    diameter, §3.2); the message names the case and the parameters."""
    with pytest.raises(NoSteadyFlowError) as exc:
        solve_steady(12.0, 0.1, continuation=False)
    msg = str(exc.value)
    assert "too small" in msg
    assert "theta = 12" in msg
    assert "nu0 = 0.1" in msg


@pytest.mark.slow
def test_no_steady_flow_angle_too_small_with_fallback():
    """With the θ-continuation fallback the branch of ν0(0) = 0.1 is followed down from 13°
    and ends above 12° (near 13.3°, where h ≈ 0.2): still 'too small'."""
    with pytest.raises(NoSteadyFlowError) as exc:
        solve_steady(12.0, 0.1)
    assert "too small" in str(exc.value)


def test_no_steady_flow_angle_too_large():
    """θ = 19°, ν0(0) = 0.05: the branch of this floor density ends near 18.5° (the decay
    length of the dilute cushion grows, §3.2); the message says the angle is too large."""
    with pytest.raises(NoSteadyFlowError) as exc:
        solve_steady(19.0, 0.05)
    msg = str(exc.value)
    assert "too large" in msg
    assert "theta = 19" in msg
    assert "roughness = 0.05" in msg


def test_thin_layer_rejected_and_kept():
    """A converged layer thinner than min_thickness is refused (h < 1 is unphysical, §3.2)
    but is available with min_thickness = 0."""
    f = solve_steady(14.0, 0.045, min_thickness=0.0)
    assert 0 < f.h < 1
    with pytest.raises(NoSteadyFlowError, match="below 1 particle"):
        solve_steady(14.0, 0.045)


def test_no_fallback_fails_fast():
    """continuation=False reports the cold start's failure at once."""
    with pytest.raises((NoSteadyFlowError, ConvergenceError)):
        solve_steady(19.0, 0.05, continuation=False)


def test_fallback_finds_non_monotonic_branch():
    """θ = 18°, ν0(0) = 0.05: the isothermal cold start fails, the flow (a dense band over a
    hot dilute cushion) is found by continuation in θ and agrees with shooting."""
    f = solve_steady(18.0, 0.05)
    assert not f.monotonic
    assert f.nu_peak > 0.05
    assert f.u_floor == pytest.approx(17.1727184, rel=1e-6)  # shooting: 17.17271897


def test_summary_and_xarray(p1):
    s = p1.to_dict()
    for k in (
        "theta",
        "nu0",
        "roughness",
        "wall_loss",
        "restitution",
        "nu_max",
        "u_floor",
        "T_floor",
        "h",
        "nu_mean",
        "rho_bar",
        "Q",
        "monotonic",
        "y_max",
        "convergence",
    ):
        assert k in s
    ds = p1.to_xarray()
    assert ds.sizes["y"] == p1.n + 1
    assert ds.attrs["roughness"] == 0.05


def test_unresolved_flow_is_not_called_no_flow():
    """θ = 16.2712°, ν0(0) = 0.25 (φ = 0.05, a point of the 60 × 60 paper map near the
    upper existence boundary: a nearly packed band, h ≈ 9.1): the independent shooting
    scan of tests/steady/shooting.py finds a flow. solve_steady either resolves it or says
    that it does not (ConvergenceError with the scan's estimate) — never "no steady flow",
    which the θ-continuation fallback used to say when the branch it followed from 15°
    ended at 15.98° (another branch)."""
    from .test_existence import reference_verdict

    exists, _ = reference_verdict(16.2712, 0.25, 0.05)
    assert exists
    unresolved = None
    try:
        f = solve_steady(16.2712, 0.25, ChuteModel(roughness=0.05))
    except NoSteadyFlowError as exc:
        pytest.fail(f"a flow exists, but solve_steady says: {exc}")
    except ConvergenceError as exc:
        unresolved = str(exc)
    if unresolved is not None:
        assert "shooting finds a solution" in unresolved
        assert "h = 9.1" in unresolved
    else:
        assert f.h == pytest.approx(9.137, rel=1e-3)


def test_unresolved_flow_is_returned_flagged_without_strict():
    """The same point: Newton from the shooting profile converges at every resolution, but
    the change between the last two (n = 288 → 384) stays at 3.4e-8 > rtol = 1e-8 (a nearly
    packed band, Newton's round-off floor). ``strict=False`` returns that flow flagged
    (``converged`` False, ``convergence`` its estimate) instead of raising (the guide: a
    result that misses the precision comes with its estimate; the default); ``strict=True``
    raises. Its thickness agrees with the independent shooting scan of
    tests/steady/shooting.py (h = 9.137 there, read at 4 digits by the scan's message)
    and with the scan of :func:`steady_existence`."""
    from chuteflow.steady import steady_existence

    model = ChuteModel(roughness=0.05)
    f = solve_steady(16.2712, 0.25, model)  # strict=False: the default
    if f.converged:  # resolved after all: then it must meet rtol
        assert f.convergence <= 1e-8
    else:
        assert 1e-8 < f.convergence < 1e-6
        assert "not converged to the requested tolerance" in f.note
        assert f.to_dict()["converged"] is False
        with pytest.raises(ConvergenceError):
            solve_steady(16.2712, 0.25, model, strict=True)
    v = steady_existence(16.2712, 0.25, model)
    assert f.h == pytest.approx(v.h, rel=1e-4)
    assert f.h == pytest.approx(9.137, rel=1e-3)
    # a converged flow says so and has no warning
    g = solve_steady(16.0, 0.05, model, strict=False)
    assert g.converged
    assert g.note == ""
    assert g.to_dict()["converged"] is True


@pytest.mark.parametrize("n_max", [100, 130])
def test_resolution_ladder_ends_at_n_max(n_max):
    """``n_max`` is the largest resolution tried (solve_steady's docstring): the ladder
    n → n + n/2 ends at n_max itself, not one rung beyond it (64 → 96 → 144 with n_max =
    100 before; on the 60 × 60 paper map 8 flows were accepted at n = 432 and 486 with
    n_max = 384). rtol = 1e-14 is below the round-off floor, so the ladder runs to its end
    and the flow is returned flagged, with the change between its last two rungs."""
    f = solve_steady(16.0, 0.05, n_max=n_max, rtol=1e-14, strict=False)
    assert f.n == n_max
    assert not f.converged
    assert 0 < f.convergence < 1e-9


def test_failed_cold_start_leaves_no_reference_cycle():
    """A failed cold start raises its diagnosis without leaving a reference cycle: the
    first Newton failure is kept without its traceback, whose frames (with their callers',
    through f_back: in a map, the row's flows) would otherwise stay in memory until the
    cyclic garbage collector's next run (stop 36: 8.7 MiB of a diagram row's flows)."""
    import gc

    from chuteflow.steady.one_grid import solve_state

    gc.collect()
    gc.disable()
    gc.set_debug(gc.DEBUG_SAVEALL)
    try:
        with pytest.raises(NoSteadyFlowError, match="layer collapses"):
            solve_state(10.0, 0.05, ChuteModel(), 1e-9, 64)
        gc.collect()
        assert [o for o in gc.garbage if type(o).__name__ == "frame"] == []
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        gc.enable()
