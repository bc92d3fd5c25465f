"""The fast transverse path (issue 10): the α(0) = 0 branch tracked in k_z against the dense
scan, at P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05).

Reference numbers (dense scan of every eigenvalue, drift and tail tests, this code): Re α =
7.534909e-9 (k_z = 1e-5), 3.863650e-5 (1.028e-3), 5.893682e-5 (2.225e-3), drifts ≤ 7e-13;
k_z* = 1.93e-3, growth 6.18e-5, cut-off 3.254e-3 (brentq on dense solves).
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.errors import ParameterError
from chuteflow.longwave.spanwise import transverse, transverse_longwave
from chuteflow.stability.transverse import transverse_dispersion, transverse_mode
from chuteflow.stability.transverse_tracking import TransverseTracker


@pytest.fixture(scope="module")
def a2z(p1_flow):
    return float(transverse_longwave(p1_flow).alpha2_z.real)


@pytest.mark.parametrize("kz", [1e-5, 1.028e-3, 2.225e-3])
def test_tracked_branch_equals_dense_scan(p1_flow, a2z, kz):
    """Same eigenvalue as the dense scan. Tolerance 2e-12 + 1e-7 |α|: the dense scan's own
    drift between N = 80 and 64 is up to 7e-13 on these points (and the round-off floor of
    the inverse iteration near α ~ 1e-8 is ~1e-17)."""
    tr = TransverseTracker(p1_flow, alpha2z=a2z)
    m = tr.mode(kz)
    ref = transverse_mode(p1_flow, kz)
    assert m.physical
    assert ref.physical
    assert abs(m.alpha - ref.alpha) < 2e-12 + 1e-7 * abs(ref.alpha)
    assert m.method == "branch"


def test_tracker_without_alpha2z_prediction(p1_flow):
    """Without α2z the first point's α/k_z² is the predictor: same branch."""
    d = transverse_dispersion(p1_flow, [1e-4, 2e-3])
    assert bool(d.physical.all())
    assert list(d.method) == ["branch", "branch"]
    assert d.alpha_re[1] == pytest.approx(6.1655e-5, rel=1e-4)


def test_branch_is_lost_in_the_continuum_past_the_band(p1_flow, a2z):
    """At P1 the branch crosses Re α = 0 at k_z = 3.254e-3 into the near-neutral continuum
    of the dilute top (Re α ≈ −1.4e-8, tails ≥ 2e-6) and is lost there; the points past it
    are left NaN with method "lost" (the dense scan answers there)."""
    ks = np.array([1e-3, 2e-3, 3e-3, 5e-3, 1e-2])
    d = transverse_dispersion(p1_flow, ks, alpha2z=a2z)
    # the first failed step past the crossing (where exactly depends on the step sizes)
    assert 3.254e-3 < d.branch_lost_at < 3.5e-3
    assert list(d.method) == ["branch"] * 3 + ["lost"] * 2
    assert np.isnan(d.alpha_re[3:]).all()
    assert d.to_xarray().attrs["branch_lost_at"] == d.branch_lost_at


def test_fast_transverse_analysis_matches_dense_numbers(p1_flow):
    """k_z* and the growth of the tracked branch equal the dense-scan analysis (1.93e-3,
    6.18e-5: tests/stability/test_transverse.py); the cut-off from the branch's last three
    points before the continuum equals brentq on dense solves (3.254e-3) to 1e-3."""
    r = transverse(p1_flow, num=50)
    s = r.to_dict()
    assert s["method"] == "track"
    assert s["all_physical"]
    assert s["kz_max"] == pytest.approx(1.928e-3, rel=1e-2)
    assert s["growth_max"] == pytest.approx(6.1801e-5, rel=1e-4)
    assert s["stationary"]
    assert s["unstable"]
    assert s["kz_cutoff"] == pytest.approx(3.254e-3, rel=1e-3)


def test_method_is_checked(p1_flow):
    with pytest.raises(ParameterError, match="method"):
        transverse_dispersion(p1_flow, [1e-3], method="fast")
    with pytest.raises(ParameterError, match="kz"):
        transverse_dispersion(p1_flow, [0.0])


@pytest.mark.slow
def test_beyond_the_branch_candidates_match_dense(p1_flow, a2z):
    """Past the branch (``beyond=True``) candidate modes from a coarse dense scan, followed
    by shift-invert: at k_z = 0.0104 and 0.383 the same least-stable modes as the dense scan
    (≈ −0.2839 ± 0.518i at N = 100, −1.5946 real at N = 80). Tolerance 1e-7: the drift
    threshold both pass (measured drifts ≤ 4e-9)."""
    ks = [2e-3, 0.0104, 0.383]
    d = transverse_dispersion(p1_flow, ks, alpha2z=a2z, beyond=True)
    ref = transverse_dispersion(p1_flow, ks[1:], method="dense")
    assert list(d.method) == ["branch", "shift", "shift"]
    assert bool(d.physical.all())
    assert bool(ref.physical.all())
    assert np.allclose(d.alpha_re[1:], ref.alpha_re, rtol=0, atol=1e-7)
    assert np.allclose(np.abs(d.alpha_im[1:]), np.abs(ref.alpha_im), rtol=0, atol=1e-7)
    assert d.alpha_re[1] == pytest.approx(-0.2839, abs=1e-3)
    assert d.alpha_re[2] == pytest.approx(-1.5946, abs=1e-3)
