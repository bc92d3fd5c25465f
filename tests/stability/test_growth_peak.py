"""Largest growth rate along each axis of the (k_x, k_z) plane, for the sweep metric
``transverse`` (issue 10): :func:`longitudinal_peak` and :func:`transverse_peak` against the
scans they replace.

Reference numbers (this code, measured on the same flows):

- P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05), longitudinal: the old metric (BranchTracker judged on
  20 k_x in [1e-4, 0.05] at N = 80, bounded refinement) gave 1.187488e-3 at k_x = 2.283e-3;
  the peak 1.187485e-3 at 2.273e-3 (N = 48, drift 7e-8). Transverse: ``transverse`` (40 k_z,
  judged at every point) 6.18015e-5 at k_z* = 1.928e-3, cut-off 3.2539e-3; the peak
  6.180235e-5 at 1.9325e-3 (at N = 48 and 80 alike, drift ≤ 7e-10).
- θ = 15.4286°, ν0(0) = 0.0442857 (a point of the 8 × 8 φ = 0.05 grid): the continuation
  from k_x = 1e-4 fails when it must land on k_x = 1.6e-4, where the branch meets the
  advected continuum; it passes through 1.58e-4. Old metric: 6.948239e-4; the peak
  (nudged scan) 6.948254e-4. Across the slope the maximum is the last resolved point of
  the scan before the branch is lost (k_z = 6.87e-4 at N = 48, 1.984e-6): refined between
  it and the loss, 2.212289e-6 at N = 48 and 2.212288e-6 at N = 80 (``transverse``,
  fixed grid: 2.212256e-6).
"""

from __future__ import annotations

import math

import pytest

from chuteflow.closures import ChuteModel
from chuteflow.longwave.spanwise import (
    _refine_peak,
    longitudinal_peak,
    transverse_longwave,
    transverse_peak,
)
from chuteflow.stability import RejectionPolicy, least_stable
from chuteflow.steady import solve_steady

#: A flow of the φ = 0.05 diagram whose longitudinal scan crosses the continuum.
CROSSING = (15.428571428571429, 0.04428571428571429)


@pytest.fixture(scope="module")
def crossing_flow():
    return solve_steady(*CROSSING, ChuteModel(roughness=0.05))


def test_refine_peak_skewed_maximum():
    """Brent's bounded search finds the maximum of y = e^{2x} − e^{4x}/2 (at x = 0, as
    Re α = α2 k² − α4 k⁴ in x = ln k) from a wide, skewed bracket, to 0.02 in x."""

    def f(x):
        return math.exp(2 * x) - 0.5 * math.exp(4 * x), x

    xs = [-0.9, -0.2, 0.5]
    x, y, pay, n = _refine_peak(f, xs, [f(v)[0] for v in xs])
    assert abs(x) < 0.02
    assert pay == x
    assert y == pytest.approx(0.5, rel=1e-3)
    assert n <= 12


def test_longitudinal_peak_p1(p1_flow):
    """The maximum of the longitudinal branch at P1 equals the old metric's (1.187488e-3;
    tolerance 1e-5 relative: both refine to 2 % in k_x about a quadratic maximum), is a
    physical mode, and is the least-stable mode there (``least_stable``, an independent
    solve; tolerance 1e-7, the drift threshold)."""
    pk = longitudinal_peak(p1_flow)
    assert pk.physical
    assert pk.direction == "longitudinal"
    assert pk.growth == pytest.approx(1.187488e-3, rel=1e-5)
    assert pk.k == pytest.approx(2.28e-3, rel=0.03)
    assert pk.cutoff == pytest.approx(7.125e-3, rel=0.02)  # k_c ≈ 0.00712 (paper ≈ 0.007)
    ref = least_stable(p1_flow, pk.k)
    assert abs(ref.alpha.real - pk.growth) < 1e-7
    # a maximum: 5 % either side the branch grows slower
    for f in (0.95, 1.05):
        assert least_stable(p1_flow, pk.k * f).alpha.real < pk.growth


def test_transverse_peak_p1(p1_flow):
    """The transverse maximum at P1 agrees with ``transverse`` (fixed 40-point grid judged
    everywhere, bounded refinement): growth to 2e-5 relative, k_z* to 2 %, cut-off to 1e-3
    (its Brent tolerance); the mode there is physical and stationary."""
    a2z = float(transverse_longwave(p1_flow, 80).alpha2_z.real)
    pk = transverse_peak(p1_flow, alpha2z=a2z, policy=RejectionPolicy(n_start=48))
    assert pk.physical
    assert pk.alpha_im == 0.0
    assert pk.growth == pytest.approx(6.18015e-5, rel=2e-5)
    assert pk.k == pytest.approx(1.928e-3, rel=0.02)
    assert pk.cutoff == pytest.approx(3.2539e-3, rel=1e-3)


def test_longitudinal_peak_steps_over_the_continuum(crossing_flow):
    """The scan point k_x = 1.6e-4 cannot be landed on (the branch meets the continuum
    there); the nudged scan follows the branch to its maximum, the old metric's value."""
    pk = longitudinal_peak(crossing_flow)
    assert pk.physical
    assert pk.growth == pytest.approx(6.948239e-4, rel=1e-5)


def test_transverse_peak_refined_before_the_loss(crossing_flow):
    """The largest resolved point is the last before the branch is lost: the maximum is
    refined between it and the loss, the same at N = 48 and 80 (to 1e-5 relative; measured
    4e-7) and above the grid value 1.984e-6."""
    got = [
        transverse_peak(crossing_flow, n=n, policy=RejectionPolicy(n_start=n, n_max=160)) for n in (48, 80)
    ]
    assert all(g.physical for g in got)
    assert got[0].growth == pytest.approx(got[1].growth, rel=1e-5)
    assert got[0].growth == pytest.approx(2.2123e-6, rel=1e-4)
    assert got[0].k == pytest.approx(5.75e-4, rel=0.02)


def test_one_resolution_check_serves_both_axes(p1_flow):
    """``judge_resolved`` (the check shared by the longitudinal maximum and the modes past
    the transverse branch, review item D2) gives the tracked branch's own verdict: the same
    α, drift |α(N) − α(N')| and tail as ``BranchTracker.mode`` (P1, k = 0.005, N = 80)."""
    from chuteflow.stability import BranchTracker
    from chuteflow.stability.transverse import judge_resolved

    tr = BranchTracker(p1_flow, 80, n_max=80)
    alpha, w = tr.advance(0.005)
    ref = tr.mode(0.005)
    mode = judge_resolved(p1_flow, 0.005, 0.0, alpha, w, 80, three_d=False, policy=RejectionPolicy(n_max=80))
    assert mode is not None
    assert mode.physical == ref.physical
    assert mode.n == ref.n == 80
    assert mode.alpha == ref.alpha
    assert mode.drift == pytest.approx(ref.drift, rel=1e-6, abs=1e-15)
    assert mode.tail == pytest.approx(ref.tail, rel=1e-9)
