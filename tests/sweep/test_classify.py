"""Classification: regimes A, B, C from the contour kind, the paper's checks, and the known
points of §4.2 (P1 unstable in B with k_c ≈ 0.007, P2 and P3 stable, P4 and P5 unstable)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from chuteflow.longwave.theory import taylor_coefficients
from chuteflow.papers.mitarai2004.checks import (
    check_C_monotonicity,
    check_low_density_unstable,
    check_regimes_placed,
)
from chuteflow.stability import OperatorCache
from chuteflow.stability.modes import stability_operator
from chuteflow.steady import solve_steady, steady_tangent
from chuteflow.sweep import STATUS, SweepConfig, classify, run_sweep
from chuteflow.sweep.regimes import REGIMES, regimes


def test_regimes_from_contour_kind():
    """Rows whose least dense flow gets slower when lighter (dU/dρ̄ ≥ 0) are A-kind; a
    denser-faster unstable region on rows that end in lighter-faster flows is C."""
    un = np.array(
        [
            [1, 0, 0, 1],  # A-kind row: A at low density, A at high density too
            [1, 0, 0, 0],
            [1, 1, 0, 1],  # B at low density; C at the dense end
            [1, 0, 1, 1],
        ]
    )
    dU = np.array([[+2.0, +1, +1, +1], [+3.0, +1, +1, +1], [-5.0, -1, +1, +2], [-6.0, +1, +1, +2]])
    h = np.ones((4, 4))
    reg = regimes(un, dU, h, h)
    A, B, C, S = REGIMES["A"], REGIMES["B"], REGIMES["C"], REGIMES["stable"]
    np.testing.assert_array_equal(reg, [[A, S, S, A], [A, S, S, S], [B, B, S, C], [B, S, C, C]])
    # missing stability → unknown
    un2 = un.copy()
    un2[0, 0] = -1
    assert regimes(un2, dU, h, h)[0, 0] == -1


def _synthetic_ds():
    th = np.array([13.0, 14.0, 16.0, 17.0])
    nu = np.array([0.02, 0.05, 0.1, 0.2])
    d = ("theta", "nu0")
    T, N = np.meshgrid(th, nu, indexing="ij")
    a2 = np.array([[5.0, -1, -1, -1], [3, -1, -1, -1], [50, -1, -1, 9], [80, -1, 7, 9]])
    dU = np.array([[2.0, 1, 1, 1], [3, 1, 1, 1], [-5, -1, 1, 2], [-6, 1, 1, 2]])
    h = np.where(T < 15, 0.5 + 10 * N, 30 - 80 * N)
    nb = np.where(T < 15, 0.2 * N, 0.5 * N)
    mono = (N < 0.08).astype(np.int8)
    ds = xr.Dataset(
        {
            "alpha2_re": (d, a2),
            "dU_drho": (d, dU),
            "h": (d, h),
            "nu_mean": (d, nb),
            "monotonic": (d, mono),
            "status": (d, np.zeros(T.shape, np.int8)),
        },
        coords={"theta": th, "nu0": nu},
        attrs={"roughness": 0.05},
    )
    return classify(ds)


def test_checks_on_a_synthetic_diagram():
    ds = _synthetic_ds()
    np.testing.assert_array_equal(ds["unstable"].values, ds["alpha2_re"].values > 0)
    c = check_regimes_placed(ds)
    assert c["passed"], c["computed"]
    c = check_low_density_unstable(ds)  # every row's least dense flow: A or B
    assert c["passed"]
    assert "4 of 4" not in c["computed"]
    assert check_C_monotonicity(ds)["passed"]  # φ = 0.05: C only where non-monotonic
    ds2 = ds.copy()
    ds2["monotonic"] = ds["monotonic"] * 0 + 1
    assert not check_C_monotonicity(ds2)["passed"]
    ds3 = ds.copy()
    ds3.attrs["roughness"] = 0.10
    assert check_C_monotonicity(ds3)["passed"] is False  # φ = 0.10 needs monotonic C points
    # a stable least dense flow with h ≥ 1 fails the low-density check
    ds4 = ds.copy()
    reg = ds4["regime"].values.copy()
    reg[2, 0] = REGIMES["stable"]
    ds4["regime"] = (("theta", "nu0"), reg)
    assert not check_low_density_unstable(ds4)["passed"]


def test_unresolved_sign_labels_nothing():
    """A point whose long-wave sign the resolutions N and 0.8 N disagree on
    (``longwave_consistent`` = 0: e.g. θ = 12.305°, ν0(0) = 0.2093 of the 60 × 60 φ = 0.05
    diagram, Re α/k² = ±0.0025 at N = 160, at the eigenvalue's round-off) is neither
    unstable nor stable: ``unstable`` and ``regime`` are −1 (unknown) there, the other points
    keep their labels."""
    ds = _synthetic_ds()
    cons = np.ones(ds["alpha2_re"].shape, dtype=np.int8)
    cons[2, 3] = 0
    ds2 = classify(ds.drop_vars(["unstable", "regime"]).assign(longwave_consistent=(("theta", "nu0"), cons)))
    assert ds2["unstable"].values[2, 3] == -1
    assert ds2["regime"].values[2, 3] == -1
    keep = cons == 1
    np.testing.assert_array_equal(ds2["unstable"].values[keep], ds["unstable"].values[keep])
    np.testing.assert_array_equal(ds2["regime"].values[keep], ds["regime"].values[keep])


def test_P1_unstable_P3_stable():
    """§4.2, fig disp: along θ = 16°, P1 (ν0 = 0.05) is unstable with the lighter flow faster
    (regime B) and P3 (ν0 = 0.10) is stable (sign of Re α2)."""
    cfg = SweepConfig(theta=(16.0,), nu0=(0.05, 0.10), metrics=("steady", "kinematic", "longwave"))
    ds = run_sweep(cfg, workers=1)
    assert list(ds["unstable"].values[0]) == [1, 0]
    assert list(ds["regime"].values[0]) == [REGIMES["B"], REGIMES["stable"]]
    assert (ds["longwave_consistent"].values == 1).all()


@pytest.mark.slow
def test_known_points_of_the_paper():
    """§4.2, figures disp and disp-AC: P1 (16°, 0.05) unstable, lighter flow faster (B), with
    k_c ≈ 0.007; P2 (16°, 0.08) and P3 (16°, 0.10) stable; P4 (14°, 0.05) and P5 (17°, 0.10)
    unstable with the denser flow faster (A, C). Tolerance on k_c: 5 % (the paper quotes one
    digit; the growth metric refines k_c to 1e-6 relative on a converged branch)."""
    metrics = ("steady", "kinematic", "longwave", {"name": "growth", "options": {"stride": 1}})
    cfg = SweepConfig(
        theta=(16.0,),
        nu0=(0.05, 0.08, 0.10),
        metrics=metrics,
        markers=(("P4", 14.0, 0.05), ("P5", 17.0, 0.10)),
    )
    ds = run_sweep(cfg, workers=1)
    assert (ds["status"].values == STATUS["ok"]).all(), ds["message"].values
    assert list(ds["unstable"].values[0]) == [1, 0, 0]
    assert ds["regime"].values[0, 0] == REGIMES["B"]
    assert ds["k_c"].values[0, 0] == pytest.approx(0.007, rel=0.05)
    assert ds["growth_max"].values[0, 0] > 0 > ds["growth_max"].values[0, 1]
    assert (ds["finite_k_disagrees"].values[0] == 0).all()
    assert list(ds["marker_unstable"].values) == [1, 1]
    assert (ds["marker_dU_drho"].values > 0).all()  # denser flow faster: A or C
    # the long-wave phase velocity is −dQ0/dρ̄0 (Appendix B, eq:vp0). The metric's α1 comes
    # from the exact steady tangent (dQ0/dρ̄0 changes by ≤ 1e-9 relative between steady
    # N = 96 … 324 at P1–P5), so it equals the kinematic metric's value
    np.testing.assert_allclose(ds["alpha1_im"], -ds["dQ_drho"], rtol=1e-6)
    # independent method: bordered perturbation theory on the plain Chebyshev grid converges
    # to it as ≈ N⁻⁴ (P1, relative error 1.2e-4, 4.5e-5, 1.8e-5, 5.3e-6, 7.4e-7 at
    # N = 48, 60, 75, 100, 160; P2 9.2e-8, P3 2.5e-8 at N = 160)
    for j, nu0 in enumerate((0.05, 0.08, 0.10)):
        flow = solve_steady(16.0, nu0)
        op = stability_operator(flow, 160, cache=OperatorCache(1, mapped=False))
        a1, _ = taylor_coefficients(op, steady_tangent(flow))
        assert a1.imag == pytest.approx(float(ds["alpha1_im"].values[0, j]), rel=1e-6)
