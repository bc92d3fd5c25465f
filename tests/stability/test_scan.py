"""One rule for k_c, the peak and the cut-off of the α(0) = 0 branch (issue 40, item 5;
paper §4.2, figures 7–9): :class:`BranchScan` on synthetic samples, exact numbers.

The grids are dyadic (k = i/256) and the values small integers, so every linear crossing
and parabola vertex below is exact in binary floating point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.errors import ParameterError
from chuteflow.stability import BranchScan, Crossings, critical_k, crossings
from chuteflow.stability.scan import critical_index, cutoff_index, linear_crossing, peak_index, sign_changes

K = np.arange(1, 9) / 256  # 1/256 … 8/256


def _scan(re):
    return BranchScan.from_samples(K[: len(re)], np.asarray(re, dtype=float) - 3j * K[: len(re)])


def test_long_wave_unstable_branch():
    """Re α > 0 from the smallest k, one + → − change: k_c = cut-off = the crossing, the peak
    the vertex of the parabola through the largest sample and its neighbours."""
    #        k: 1    2    3    4    5     6     7 (/256)
    s = _scan([3.0, 5.0, 5.0, 3.0, -1.0, -7.0, -15.0])
    # crossing in [4, 5]/256: 4/256 + 3/(3 + 1)·(1/256) = 4.75/256
    assert s.crossings == (4.75 / 256,)
    assert s.k_c == 4.75 / 256
    assert s.cutoff() == s.k_c
    # parabola through (1, 3), (2, 5), (3, 5) (k in 1/256): 5 − (x − 2.5)² + 0.25 … vertex
    # at x = 2.5 with value 5.25
    pk = s.peak()
    assert pk.k == 2.5 / 256
    assert pk.growth == 5.25
    assert pk.refined
    assert not pk.at_edge
    assert s.converged
    c = s.to_crossings()
    assert isinstance(c, Crossings)
    assert list(c) == [4.75 / 256]
    assert c.converged
    assert c.k_reached == 7 / 256


def test_long_wave_stable_branch_with_a_finite_band():
    """Re α < 0 at the smallest k, unstable on a finite band: k_c is None (no band
    0 < k < k_c), both crossings are listed, the cut-off is the upper edge of the band."""
    s = _scan([-1.0, -0.5, 0.5, 1.0, 0.5, -0.5, -1.0])
    assert s.crossings == (2.5 / 256, 5.5 / 256)
    assert s.k_c is None
    assert s.cutoff() == 5.5 / 256
    pk = s.peak()
    assert pk.k == 4 / 256
    assert pk.growth == 1.0
    assert pk.refined
    assert not pk.at_edge


def test_signs_kept_on_the_scan():
    """No sign change: no k_c, no cut-off; the peak at the edge of the scan is not refined."""
    up = _scan([1.0, 2.0, 3.0, 4.0])
    assert up.crossings == ()
    assert up.k_c is None
    assert up.cutoff() is None
    assert up.peak() == (4 / 256, 4.0, False, True)
    down = _scan([-1.0, -2.0, -3.0])
    assert down.k_c is None
    assert down.cutoff() is None
    assert down.peak() == (1 / 256, -1.0, False, True)


def test_exact_zero_and_unreached_samples():
    """A sample exactly 0 closes the bracket that ends there (counted once); no sign change is
    decided across an unreached sample (NaN), and the scan is then not converged."""
    s = _scan([2.0, 0.0, -2.0])
    assert s.crossings == (2 / 256,)
    assert s.k_c == 2 / 256
    gap = _scan([2.0, math.nan, -2.0])
    assert gap.crossings == ()
    assert gap.k_c is None
    assert not gap.converged
    assert gap.k_reached == 3 / 256


def test_the_sampled_rule():
    """The functions the sampled callers (sweep metric, transverse peaks) share."""
    v = [-1.0, 1.0, 2.0, -1.0, math.nan, 1.0, -1.0]
    assert sign_changes(v) == [0, 2, 5]
    assert critical_index(v) is None  # first change − → +
    assert cutoff_index(v) == 5
    assert critical_index([1.0, -1.0, 1.0, -1.0]) == 0
    assert cutoff_index([1.0, -1.0, 1.0, -1.0]) == 2
    assert cutoff_index([1.0, -1.0, 1.0]) is None  # positive at the last sample
    assert peak_index(v) == 2
    assert peak_index([math.nan, -np.inf]) is None
    assert peak_index([5.0, 1.0, 2.0], k=[0.0, 1.0, 2.0]) == 2  # k = 0 is outside (0, k_max]
    assert linear_crossing([1.0, 3.0], [1.0, -3.0], 0) == 1.5


def test_to_xarray():
    ds = _scan([3.0, 5.0, 5.0, 3.0, -1.0, -7.0, -15.0]).to_xarray()
    assert ds.attrs["k_c"] == 4.75 / 256
    assert ds.attrs["cutoff"] == 4.75 / 256
    assert ds.attrs["peak_growth"] == 5.25
    assert ds.attrs["converged"] == 1
    np.testing.assert_array_equal(ds.alpha_re.values, [3.0, 5.0, 5.0, 3.0, -1.0, -7.0, -15.0])
    assert "k_c" not in _scan([-1.0, -0.5, 0.5, 1.0, 0.5, -0.5, -1.0]).to_xarray().attrs


def test_from_samples_checks_its_grid():
    with pytest.raises(ParameterError):
        BranchScan.from_samples([2.0, 1.0], [1.0, -1.0])


def test_api_forms_agree_with_the_scan(p1_flow):
    """critical_k and crossings are the scan's k_c and crossings (P1: k_c = 0.00712487)."""
    from chuteflow.stability import branch_scan

    scan = branch_scan(p1_flow, k_max=0.02, num=15)
    assert scan.k_c == critical_k(p1_flow, k_max=0.02, num=15)
    assert tuple(crossings(p1_flow, k_max=0.02, num=15)) == scan.crossings
    assert scan.k_c == pytest.approx(0.00712486, rel=2e-6)
    assert scan.cutoff() == scan.k_c
    # the peak (tests/stability/test_growth_peak.py: 1.187485e-3 at k = 2.273e-3)
    pk = scan.peak()
    assert pk.refined
    assert pk.growth == pytest.approx(1.187488e-3, rel=1e-5)
    assert pk.k == pytest.approx(2.28e-3, rel=0.01)
    assert pk.growth >= np.nanmax(scan.growth)
