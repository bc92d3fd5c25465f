"""Families at fixed θ and (θ, ν0) maps (§3.2): datasets, continuation, paper checkpoints."""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow import __version__
from chuteflow.closures import ChuteModel
from chuteflow.errors import ParameterError
from chuteflow.steady import (
    FluxMinimum,
    Separatrix,
    flux_minimum,
    separatrix,
    solve_steady,
    steady_family,
    steady_map,
)
from chuteflow.steady.maps import existence_limit
from chuteflow.steady.schema import SCALARS

PHI10 = ChuteModel(roughness=0.10)


@pytest.fixture(scope="module")
def fam16():
    return steady_family(16.0, np.geomspace(0.02, 0.2, 9))


def test_family_dataset(fam16):
    ds = fam16
    assert ds.sizes["nu0"] == 9
    for k in SCALARS + ("monotonic", "n", "status", "error"):
        assert k in ds
    assert set(ds.status.values) == {"ok"}
    for k in ("restitution", "nu_max", "roughness", "wall_loss", "nu_top", "rtol", "theta"):
        assert k in ds.attrs
    assert ds.attrs["chuteflow_version"] == __version__
    assert ds.attrs["roughness"] == 0.05
    assert ds.attrs["theta"] == 16.0
    assert float(ds.convergence.max()) < 1e-8


def test_family_matches_single_solves(fam16):
    """Continuation (tangent predictor, coarse start) gives the cold-start solution."""
    for i in (0, 4, 8):
        f = solve_steady(16.0, float(fam16.nu0[i]))
        for k in ("h", "rho_bar", "Q", "u_floor", "T_floor"):
            assert float(fam16[k][i]) == pytest.approx(getattr(f, k), rel=1e-9), k


def test_family_slope_is_exact_tangent(fam16):
    """dQ0/dρ̄0 in the dataset equals the ratio of the ν0-derivatives, and a secant of the
    family between close points (second-order accurate) within 1e-3."""
    ds = fam16
    ratio = ds.dQ_dnu0 / ds.drho_dnu0
    assert np.allclose(ratio, ds.dQ_drho, rtol=1e-12)
    f1 = solve_steady(16.0, 0.05 - 1e-4)
    f2 = solve_steady(16.0, 0.05 + 1e-4)
    sec = (f2.Q - f1.Q) / (f2.rho_bar - f1.rho_bar)
    mid = steady_family(16.0, [0.05]).dQ_drho.values[0]
    assert mid == pytest.approx(sec, rel=1e-3)


def test_points_without_flow_are_nan_with_status():
    """No exception for points without a steady flow: NaN and a status string."""
    ds = steady_family(14.0, [0.02, 0.08, 0.1])
    st = ds.status.values
    assert st[1] == "ok"
    assert st[2] == "ok"
    assert st[0] != "ok"
    assert np.isnan(ds.h.values[0])
    assert np.isnan(ds.monotonic.values[0])


def test_family_rejects_bad_input():
    with pytest.raises(ParameterError, match="increasing"):
        steady_family(16.0, [0.1, 0.05])
    with pytest.raises(ParameterError, match="nu0"):
        steady_family(16.0, [0.05, 0.7])
    with pytest.raises(ParameterError, match="theta"):
        steady_family(-1.0, [0.05])


def test_flux_monotonic_at_14_degrees():
    """§3.2, fig steadyphase005(b): Q0(ρ̄0) increases monotonically for θ = 14° — exact
    dQ0/dρ̄0 > 0 and dρ̄0/dν0(0) > 0 on the whole computed family (ν0(0) from the collapse
    near 0.05 to 0.3)."""
    ds = steady_family(14.0, np.geomspace(0.05, 0.3, 8))
    ok = ds.status.values == "ok"
    assert ok.sum() >= 6
    assert (ds.dQ_drho.values[ok] > 0).all()
    assert (ds.drho_dnu0.values[ok] > 0).all()
    assert flux_minimum(14.0, nu0_values=np.geomspace(0.05, 0.3, 8)) is None


def test_flux_minimum_at_16_degrees():
    """§3.2: at θ = 16° Q0 decreases with ρ̄0 for ρ̄0 ≲ 0.2 and has a minimum. Found by
    Brent on the exact tangent: ρ̄0 = 0.2272, Q0 = 2.3103 at ν0(0) = 0.03434."""
    r = flux_minimum(16.0, nu0_values=np.geomspace(0.02, 0.08, 6))
    assert isinstance(r, FluxMinimum)
    assert r.nu0 == pytest.approx(0.034338, rel=1e-4)
    assert 0.15 < r.rho_bar < 0.3
    assert r.bracket[0] < r.nu0 < r.bracket[1]
    # converged: Brent to xtol and the flow there to rtol (its estimate below 1e-8)
    assert r.converged
    assert r.convergence <= 1e-8
    assert "xtol" in r.note
    d = r.to_dict()
    assert d["nu0"] == r.nu0
    assert d["converged"] is True
    assert "family" not in d
    assert int((r.family.status.values == "ok").sum()) == 6
    f = solve_steady(16.0, r.nu0)
    from chuteflow.steady import steady_tangent

    assert abs(steady_tangent(f)["dQ_drho"]) < 1e-6


def test_flux_phi010_monotonic_20_minimum_21():
    """§3.2, fig steadyphase010(b): φ = 0.10, Q0(ρ̄0) monotonic at θ = 20°, minimum at 21°."""
    nus = np.geomspace(0.01, 0.2, 8)
    assert flux_minimum(20.0, PHI10, nu0_values=nus) is None
    r = flux_minimum(21.0, PHI10, nu0_values=nus)
    assert r is not None
    assert 0.05 < r.rho_bar < 0.3


def test_small_map():
    """A 3 × 5 map: dims, θ rows continued from each other, statuses, values equal to the
    family's."""
    ths = [15.0, 16.0, 17.0]
    nus = np.geomspace(0.02, 0.12, 5)
    ds = steady_map(ths, nus, workers=1)
    assert ds.h.dims == ("theta", "nu0")
    assert ds.h.shape == (3, 5)
    assert (ds.status.values == "ok").all()
    fam = steady_family(17.0, nus)
    assert np.allclose(ds.h.sel(theta=17.0), fam.h, rtol=1e-9)
    # at moderate ν0(0) h grows with θ (the θ contours of fig steadyphase005(a) move right;
    # at ν0(0) = 0.12, θ = 17° the layer is already non-monotonic and thinner)
    assert (np.diff(ds.h.values[:, :4], axis=0) > 0).all()


@pytest.mark.slow
def test_map_two_workers_equals_one():
    ths = np.arange(14.0, 18.01, 0.5)
    nus = np.geomspace(0.01, 0.3, 10)
    a = steady_map(ths, nus, workers=1)
    b = steady_map(ths, nus, workers=2)
    assert (a.status.values == b.status.values).all()
    assert np.allclose(a.h.values, b.h.values, rtol=1e-9, equal_nan=True)


@pytest.mark.slow
def test_existence_range_phi005():
    """§3.2: φ = 0.05, solutions for roughly 8° ≲ θ ≲ 20°. Measured: the branches end at
    ≈ 9.3° (ν0(0) = 0.55, h ≪ 1) and ≈ 19.7° (ν0(0) = 0.005, dense band over a hot cushion)."""
    ds, flows = steady_map(
        np.arange(8.0, 22.01, 1.0), np.geomspace(0.005, 0.55, 12), workers=2, return_flows=True
    )
    lo = existence_limit(flows, ds, "low")
    hi = existence_limit(flows, ds, "high")
    assert abs(lo["theta"] - 8.0) <= 2.0
    assert abs(hi["theta"] - 20.0) <= 2.0


@pytest.mark.slow
def test_separatrix():
    """§3.2: contours of θ separate near h ≈ 7 around θ ≈ 15° (θ ≤ 14° → h → 0, θ ≥ 15°
    diverge). Measured θ* ≈ 14.5°, h ≈ 5.8 at ν̄ ≈ 1e-3."""
    sp = separatrix(xtol=0.05)
    assert isinstance(sp, Separatrix)
    assert 14.0 < sp.theta < 15.0
    assert abs(sp.h - 7.0) < 0.3 * 7.0
    assert sp.converged
    assert sp.bracket[1] - sp.bracket[0] <= 0.05
    assert sp.to_dict()["theta"] == sp.theta


def test_steady_row_is_steady_family_without_the_table():
    """steady_row (the sweep's rows) makes the same solves as steady_family: the same
    statuses, errors and flows bit for bit."""
    from chuteflow.steady import steady_family, steady_row

    nus = [0.01, 0.03, 0.05, 0.3, 0.55]
    ds, flows = steady_family(16.0, nus, tangent=False, return_flows=True)
    row = steady_row(16.0, nus)
    assert [r[0] for r in row] == list(ds["status"].values)
    assert [r[2] for r in row] == list(ds["error"].values)
    for (_, f, _), g in zip(row, flows):
        assert (f is None) == (g is None)
        if f is not None:
            assert np.array_equal(f.u, g.u)
            assert np.array_equal(f.T, g.T)
            assert f.y_max == g.y_max


def test_no_step_up_from_a_layer_at_the_top_changes_no_answer():
    """rows._TOP_GAP: a flow whose dense layer ends within 0.1 h of the top of the domain
    is not continued to a larger ν0(0) (those steps fail: 107 of 107 on the two 60 × 60
    paper maps). On a row that crosses the upper existence boundary (θ = 17°, φ = 0.05)
    the rule skips such steps, takes fewer continuation attempts, and gives the same
    statuses and the same flows (to their convergence estimates; here to the last bit) as
    the row with every step tried."""
    from unittest import mock

    from chuteflow.steady import continuation_step, proofs, rows, steady_row

    nus = list(np.geomspace(0.12, 0.2, 10))
    skips, attempts = [], {"rule": 0, "all": 0}
    top_bound, attempt = rows._top_bound, continuation_step._attempt

    def counting_top_bound(point):
        out = top_bound(point)
        skips.append(out)
        return out

    def counting_attempt(key):
        def run(*args, **kwargs):
            attempts[key] += 1
            return attempt(*args, **kwargs)

        return run

    rule_attempt, all_attempt = counting_attempt("rule"), counting_attempt("all")
    with (
        mock.patch.object(rows, "_top_bound", counting_top_bound),
        mock.patch.object(continuation_step, "_attempt", rule_attempt),
        mock.patch.object(proofs, "_attempt", rule_attempt),
    ):
        rule = steady_row(17.0, nus)
    with (
        mock.patch.object(rows, "_TOP_GAP", 0.0),
        mock.patch.object(continuation_step, "_attempt", all_attempt),
        mock.patch.object(proofs, "_attempt", all_attempt),
    ):
        every = steady_row(17.0, nus)
    assert sum(skips) >= 1
    assert attempts["rule"] < attempts["all"]
    assert [s for s, _, _ in rule] == [s for s, _, _ in every]
    assert {s for s, _, _ in rule} >= {"ok", "no_steady_flow"}  # the row crosses the boundary
    for (_, a, _), (_, b, _) in zip(rule, every):
        if a is not None:
            tol = 2 * max(a.convergence, b.convergence) + 1e-14
            for q in ("Q", "h", "rho_bar"):
                assert getattr(a, q) == pytest.approx(getattr(b, q), rel=tol)
