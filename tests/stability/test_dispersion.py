"""The α(0) = 0 branch: long-wave limit, dispersion relations and k_c (paper §4.2, App. B).

Numbers quoted in comments were measured with this code (φ = 0.05 unless stated,
ν_top = 1e-9, N from the adaptive ladder 80, 100, 125, …).
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.errors import ConvergenceError, ParameterError
from chuteflow.stability import (
    BranchTracker,
    OperatorCache,
    critical_k,
    dispersion,
    least_stable,
    null_vectors,
    stability_operator,
)
from chuteflow.steady import solve_steady, steady_tangent

from .conftest import P1


def tangent_at_fixed_y(flow, y):
    """∂(ν0, u0, 0, T0)/∂β at fixed height from the steady family (Appendix B, eq:last)."""
    tg = steady_tangent(flow)
    g = flow.grid
    shift = (g.y / flow.y_max) * tg["y_max"]  # the family's tangent is at fixed y/y_max
    at_y = {
        "nu": flow.nu * tg["log_nu"] - shift * (g.D @ flow.nu),
        "u": tg["u"] - shift * (g.D @ flow.u),
        "T": tg["T"] - shift * (g.D @ flow.T),
    }
    return {f: g.interpolate(v, y) for f, v in at_y.items()}


def test_k0_mode_is_the_steady_family_tangent(p1_flow):
    """α(0) = 0 and its eigenvector is ∂X0/∂β with v̂ = 0 (Appendix B, eq:x01–eq:last).

    They differ only because the steady family is computed at fixed ν0(y_max) = ν_top,
    while the stability domain is fixed: measured 4e-6 at ν_top = 1e-9 and 5e-8 at 1e-11,
    i.e. proportional to ν_top.
    """
    op = stability_operator(p1_flow, 80)
    nv = null_vectors(op)
    assert abs(nv.alpha0) < 1e-11  # round-off: |α| of the branch at k = 1e-6 is 4e-6
    r = op.pencil(0.0).split(nv.right)
    t = tangent_at_fixed_y(p1_flow, op.grid.y)
    scale = np.vdot(t["u"], r["u"]) / np.vdot(t["u"], t["u"])
    for f in ("nu", "u", "T"):
        assert np.abs(r[f] - scale * t[f]).max() <= 2e-5 * np.abs(r[f]).max(), f
    assert np.abs(r["v"]).max() < 1e-9 * np.abs(nv.right).max()
    # left null vector: annihilates A0 and is normalised against B
    A0 = op.series()[0]
    assert np.abs(nv.left.conj() @ A0).max() < 1e-8 * np.abs(nv.left).max() * np.abs(A0).max()
    assert np.vdot(nv.left, op.B @ nv.right) == pytest.approx(1.0)


def test_phase_velocity_tends_to_minus_dQ_drho(p1_flow):
    """Im α / k → −dQ0/dρ̄0 (Appendix B, eq:vp0; figure 8). At k = 1e-7 the O(k)
    correction Im α2 k is 1.7e-4 (Im α2 ≈ −1.7e3), i.e. 4e-5 relative."""
    dq = steady_tangent(p1_flow)["dQ_drho"]
    assert dq == pytest.approx(4.1524, abs=1e-4)  # reference value of the steady stage
    m = least_stable(p1_flow, 1e-7)
    assert m.physical
    assert -m.alpha.imag / 1e-7 == pytest.approx(dq, rel=1e-4)


def test_growth_rate_is_quadratic_only_at_very_small_k(p1_flow):
    """Re α ∝ k² (figure 8) for k ≲ 1e-5; by k = 2e-3 Re α / k² has fallen ~40-fold
    (ERRATA). Measured: 12448 (k = 1e-6), 12308 (1e-5), 294.7 (2e-3)."""
    tr = BranchTracker(p1_flow, 80)
    ratio = {k: tr.mode(k).alpha.real / k**2 for k in (1e-6, 1e-5, 2e-3)}
    assert ratio[1e-6] > 0
    assert ratio[1e-5] == pytest.approx(ratio[1e-6], rel=0.02)
    assert 30 < ratio[1e-6] / ratio[2e-3] < 55


def test_p1_is_unstable_below_k_c_of_about_0_007(p1_flow):
    """P1 (θ = 16°, ν0 = 0.05): Re α > 0 for 0 < k < k_c, k_c ≈ 0.007 (figure 7a).
    Measured k_c = 0.00712486 at N = 100 and 125 (relative change 1e-8)."""
    k_c = critical_k(p1_flow, k_max=0.02, num=15)
    assert 0.0065 < k_c < 0.0075
    assert k_c == pytest.approx(0.00712486, rel=2e-6)
    ds = dispersion(p1_flow, [0.3 * k_c, 0.9 * k_c, 1.1 * k_c, 2 * k_c])
    assert (ds["alpha_re"].values[:2] > 0).all()
    assert (ds["alpha_re"].values[2:] < 0).all()


def test_dispersion_dataset(p1_flow):
    ks = np.linspace(0.0, 0.02, 11)
    ds = dispersion(p1_flow, ks[::-1])  # any order in, tracked in increasing k
    assert np.allclose(ds["k"].values, ks[::-1])
    assert ds["physical"].values.all()
    # the paper's criterion: eigenvalues change by less than 1e-7 between resolutions
    assert (ds["drift"].values < 1e-7).all()
    assert (ds["tail"].values < 1e-7).all()
    assert abs(ds["alpha_re"].values[-1]) < 1e-11  # k = 0 (last, as given)
    assert ds.attrs["theta"] == P1[0]
    assert ds.attrs["roughness"] == 0.05
    assert ds.attrs["dQ_drho"] == pytest.approx(4.1524, abs=1e-4)
    assert ds["alpha_re"].attrs["units"]


def test_p2_stable_for_all_k(flows):
    """P2 (16°, 0.08): the least-stable mode is damped at every k > 0 (figure 7b)."""
    ds = dispersion(flows("P2"), np.linspace(0.0, 0.05, 21)[1:])
    assert (ds["alpha_re"].values < 0).all()


def test_p4_unstable(flows):
    """P4 (14°, 0.05, regime A): unstable at long waves (figure 9a); measured
    max Re α ≈ 9.8e-6 near k = 1e-3, stable again by k = 2e-3."""
    ds = dispersion(flows("P4"), [1e-4, 5e-4, 1e-3, 3e-3])
    re = ds["alpha_re"].values
    assert (re[:3] > 0).all()
    assert re[3] < 0


@pytest.mark.slow
def test_p3_stable_for_all_k(flows):
    """P3 (16°, 0.10): stable (figure 7c). Its branch converges slowly near k ~ 1e-3
    (N = 125 needed for drift < 1e-7 on the plain Chebyshev grid, ERRATA); the sinh-mapped
    default grid resolves the layer edge and needs N ≤ 80 (benchmarks/probes/n_table.py)."""
    ks = np.linspace(0.0, 0.05, 26)[1:]
    ds = dispersion(flows("P3"), ks)
    assert (ds["alpha_re"].values < 0).all()
    assert ds["physical"].values.all()
    assert ds["n"].values.max() <= 80
    plain = dispersion(flows("P3"), ks, cache=OperatorCache(mapped=False))
    assert (plain["alpha_re"].values < 0).all()
    assert plain["n"].values.max() >= 100
    # two discretisations of one problem agree to the paper's eigenvalue criterion
    assert np.abs(plain["alpha_re"].values - ds["alpha_re"].values).max() < 1e-7


@pytest.mark.slow
@pytest.mark.parametrize("name", ["P5", "Q3"])
def test_unstable_checkpoints(flows, name):
    """P5 (17°, 0.10, regime C; figure 9b) and Q3 (φ = 0.10, 20°, 0.17; figure 13c) are
    long-wave unstable; measured max Re α ≈ 4.2e-4 (P5) and 1.8e-4 (Q3) near k = 2e-3."""
    ds = dispersion(flows(name), np.geomspace(1e-5, 2e-2, 15))
    assert ds["alpha_re"].values.max() > 1e-5
    assert ds["physical"].values.all()


@pytest.mark.slow
def test_k_c_converges_with_resolution(p1_flow):
    kc = [critical_k(p1_flow, k_max=0.02, num=15, n=n, n_max=n) for n in (100, 125)]
    assert abs(kc[0] - kc[1]) < 1e-7 * kc[1]


@pytest.mark.slow
def test_domain_top_moves_results_as_in_errata():
    """ERRATA: moving the top from ν_top = 1e-7 to 1e-13 shifts Re α(k = 0.002) at P1 by
    about 0.5 % and k_c by about 0.8 %. Measured −0.53 % and −0.75 %."""
    out = {}
    for nu_top in (1e-7, 1e-13):
        flow = solve_steady(*P1, nu_top=nu_top)
        out[nu_top] = (least_stable(flow, 2e-3).alpha.real, critical_k(flow, k_max=0.02, num=12))
    d_re = (out[1e-13][0] - out[1e-7][0]) / out[1e-7][0]
    d_kc = (out[1e-13][1] - out[1e-7][1]) / out[1e-7][1]
    assert -0.007 < d_re < -0.003
    assert -0.011 < d_kc < -0.005


@pytest.mark.slow
def test_unconverged_branch_raises_when_strict(flows):
    """P4 at k = 0.05: the wave speed lies within the range of u0(y) (critical layer), the
    eigenfunction is not resolved by N = 100, and with ``strict=True`` the solver says so
    instead of returning numbers."""
    with pytest.raises(ConvergenceError, match="branch|not converged"):
        dispersion(flows("P4"), [0.01, 0.05], n_max=100, strict=True)


def test_dispersion_rejects_bad_k(p1_flow):
    with pytest.raises(ParameterError, match="k = -0.001"):
        dispersion(p1_flow, [0.001, -0.001])
    with pytest.raises(ParameterError, match="k_max"):
        critical_k(p1_flow, k_max=0.0)


@pytest.mark.slow
def test_non_strict_dispersion_flags_instead_of_raising(flows):
    ds = dispersion(flows("P4"), [1e-3, 0.05], n_max=100)  # strict=False: the default
    assert ds["physical"].values.tolist() == [True, False]
    assert ds["alpha_re"].values[0] > 0


def test_first_step_from_k0_is_halved_until_alpha1_k_predicts_it():
    """θ = 16.475°, ν0(0) = 0.02 (dilute, a sampled point of the φ = 0.05 diagrams): the k²
    regime ends near k ~ 1e-6 (Re α/k² = 2.2 at k = 1e-7, 0.99 at 1e-5), so the first step
    1e-5 lands 41 % of the step off α1 k. Accepting it gave the next predictor the slope α1
    at k = 0, every shorter step missed by the same 41 %, and the branch was "lost" at
    k = 1e-5 (the growth metric gave no value; ``chuteflow dispersion`` ran > 10 min in
    dense QZ fallbacks). Checked against the dense QZ spectrum (the independent method, the
    same N): the one resolved eigenvalue there with Re α > 0."""
    from chuteflow.stability.modes import spectrum

    flow = solve_steady(16.475, 0.02)
    tracker = BranchTracker(flow, 80, n_max=80)
    mode = tracker.mode(1e-4)
    assert mode.physical
    qz = spectrum(flow, 1e-4, n=80)
    ref = min(qz, key=lambda m: abs(m.alpha - mode.alpha))
    # measured α(1e-4) = 6.7911e-4 − 6.1612e-4i, drift 1.8e-12 against N' = 64
    assert abs(mode.alpha - ref.alpha) < 1e-9 * abs(ref.alpha) + 1e-12
    assert ref.alpha.real > 6e-4
    assert ref.alpha.real == max(m.alpha.real for m in qz)
    # and the branch starts on α1 k: at k = 1e-7 the first step hits the predictor
    a = BranchTracker(flow, 80, n_max=80).mode(1e-7).alpha
    assert abs(a - tracker.alpha1 * 1e-7) < 0.02 * abs(tracker.alpha1) * 1e-7


@pytest.mark.slow
def test_dispersion_past_a_dissolved_branch_is_resolved_cheaply():
    """θ = 15.3559°, ν0(0) = 0.11983: the branch dissolves into the continuum near
    k = 0.003 (critical layer). The larger k are followed once with relaxed tails, and a
    resolved, less damped direct mode outranks the flagged relaxed value (as in
    least_stable); k not reached are solved directly along the policy's ladder from its
    first rung. Before, each k was followed afresh from k = 0 (at k = 0.05 the answer was a
    relaxed value α = −0.0290 − 0.346i with drift 1.4e-3, at k = 0.0447 −0.699 − 0.337i
    with drift 3.3e-2, while a mode at −0.0215 − 0.257i passes both tests), the direct
    solves started at the tracker's last N (256), and ``chuteflow dispersion --k-max 0.05
    --num 20`` took 217 s (now 36 s)."""
    flow = solve_steady(15.35593220339, 0.119830508475)
    ks = [0.0026, 0.0079, 0.05]
    ds = dispersion(flow, ks, strict=False)
    assert ds.attrs["branch_lost_at"] == pytest.approx(0.0079)
    for i in (1, 2):
        assert bool(ds["direct"].values[i])
        assert ds["n"].values[i] <= 100
        assert ds["drift"].values[i] < 1e-7
    # measured −0.0214659 − 0.2570957i at N = 80 (drift 2.9e-8 against N' = 64)
    assert complex(ds.alpha_re.values[2], ds.alpha_im.values[2]) == pytest.approx(
        complex(-0.0214659, -0.2570957), abs=1e-6
    )


def test_direct_ladder_follows_the_first_rungs_candidate_to_the_qz_ladders_answer():
    """Where the branch is lost and the relaxed continuation does not reach k,
    ``dispersion`` solves each k directly: dense QZ at the first rung, then the candidate
    followed up the ladder by shift-invert (``_direct_ladder``). Independent method: the
    QZ ladder of ``least_stable(method="qz")`` (a dense QZ at every rung). Off the paper:
    θ = 21.293°, ν0(0) = 0.0506, φ = 0.0878, Φ = 0.337, e_p = 0.685 (branch lost near
    k = 4.5e-4); at k = 0.0155 both pass at N = 125 with the same eigenvalue (measured
    |Δα| = 2.3e-13, drift 2.9e-8; 0.7 s against 4.6 s). Over the 50 k of ``chuteflow
    dispersion`` there: the same α to ≤ 7e-12 and the same N at 46 k, at two k a better
    resolved answer (N 195 → 244, 80 → 100, drifts 1.5e-7 → 2.5e-8, 1.3e-7 → 4.3e-9, α within
    2.5e-8); 274 s → 33 s."""
    import importlib

    from chuteflow.closures import ChuteModel
    from chuteflow.stability import RejectionPolicy

    disp = importlib.import_module("chuteflow.stability.lost")
    flow = solve_steady(21.293, 0.0506, ChuteModel(roughness=0.0878, wall_loss=0.337, restitution=0.685))
    policy = RejectionPolicy()
    got = disp._direct_ladder(flow, 0.0155, policy, OperatorCache(2))
    ref = least_stable(flow, 0.0155, method="qz", policy=policy, cache=OperatorCache(2))
    assert ref.physical
    assert ref.n == 125
    assert got.physical
    assert got.n == ref.n
    # both converge the same eigenvalue at N = 125 (a dense QZ and shift-invert: round-off
    # apart, ~1e-13); 1e-10 is far below the drift 2.9e-8 that both report
    assert abs(got.alpha - ref.alpha) < 1e-10
    assert got.drift == pytest.approx(ref.drift, rel=1e-3)
