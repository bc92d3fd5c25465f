"""Sweep metric ``transverse`` (issue 10): values at P1, resume, Dask, the winner figure.

P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05): α2z = 75.844 (tests/stability/test_transverse.py),
the transverse branch grows at most 6.18e-5 (k_z* = 1.93e-3); along the slope the branch
grows at most 1.18e-3 near k_x = 0.002 (tests/stability: the 2D branch) — both unstable
(winner 3) and the longitudinal one is ~19× faster (fastest 1).
"""

from __future__ import annotations

import pytest
import xarray as xr

from chuteflow.sweep import Sweep, SweepConfig, run_sweep
from chuteflow.sweep.transverse import WINNER_CODES, TransverseMetric

METRICS = ("steady", "kinematic", "longwave", "transverse")


def _cfg(nu0=(0.05,)):
    return SweepConfig(theta=(16.0,), nu0=nu0, roughness=0.05, chunk=1, metrics=METRICS)


@pytest.fixture(scope="module")
def p1_sweep(tmp_path_factory):
    path = tmp_path_factory.mktemp("tr") / "p1.nc"
    sw = Sweep(_cfg(), path)
    return sw, sw.run(workers=1), path


def test_p1_values_and_winner(p1_sweep):
    _, ds, _ = p1_sweep
    p = ds.isel(theta=0, nu0=0)
    assert float(p.alpha2_z) == pytest.approx(75.844, abs=2e-3)
    assert float(p.transverse_growth_max) == pytest.approx(6.180e-5, rel=1e-3)
    assert float(p.transverse_kz_max) == pytest.approx(1.93e-3, rel=2e-2)
    # the longitudinal maximum: the refined branch maximum is at least the grid value 1.179e-3
    assert float(p.longitudinal_growth_max) == pytest.approx(1.18e-3, rel=2e-2)
    assert int(p.winner) == 3
    assert WINNER_CODES[3] == "both"
    assert int(p.fastest) == 1
    assert float(p.fastest_kz) == 0.0
    assert float(p.fastest_kx) == pytest.approx(float(p.longitudinal_kx_max))


def test_resume_recomputes_nothing(p1_sweep):
    sw0, ds, path = p1_sweep
    sw = Sweep(_cfg(), path)
    again = sw.run(workers=1)
    assert sw.stats.computed == 0
    xr.testing.assert_identical(again, ds)


def test_options_are_checked():
    from chuteflow.errors import ParameterError

    with pytest.raises(ParameterError, match="transverse"):
        TransverseMetric(n=8)


@pytest.mark.slow
def test_dask_equals_local(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    cfg = _cfg(nu0=(0.05, 0.06))
    local = run_sweep(cfg, workers=1)
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        sw = Sweep(cfg, tmp_path / "dask.nc")
        got = sw.run(client=client)
    assert sw.stats.backend == "dask"
    xr.testing.assert_identical(got, local)


def test_winner_figure(p1_sweep, tmp_path):
    from chuteflow.figures.transverse import winner_figure

    _, ds, _ = p1_sweep
    path = winner_figure(ds, tmp_path / "w.png")
    assert path.stat().st_size > 5_000


def test_thick_dilute_flow_unstable_both_ways_has_a_winner():
    """θ = 16.475°, ν0(0) = 0.02 (h = 52): unstable along and across the slope. Version 3 lost
    the longitudinal branch at k = 1e-5 (the tracker's first step accepted off α1 k) and
    named no winner, like 55 of the 178 such points of the 40 × 40 φ = 0.05 diagram. The
    longitudinal maximum is checked against the dense QZ spectrum at its k (the independent
    method: the largest Re α of all modes, N = 80)."""
    from chuteflow.stability.modes import spectrum
    from chuteflow.steady import solve_steady
    from chuteflow.sweep.metrics import LongWaveMetric
    from chuteflow.sweep.points import Point

    flow = solve_steady(16.475, 0.02)
    point = Point(-1, -1, 16.475, 0.02)
    point.values.update(LongWaveMetric().compute(flow, point))
    out = TransverseMetric().compute(flow, point)
    assert out["winner"] == 3
    assert out["fastest"] == 1
    assert not point.notes
    k, growth = out["longitudinal_kx_max"], out["longitudinal_growth_max"]
    # measured: 1.93618e-3 at k_x = 1.437e-3 against the transverse 5.39e-4 at k_z = 1.92e-3
    assert growth > 2 * out["transverse_growth_max"]
    qz = max(m.alpha.real for m in spectrum(flow, k, n=80))
    assert growth == pytest.approx(qz, rel=1e-7)


def test_dense_thin_flow_longitudinal_growth_at_the_third_rung():
    """θ = 16°, ν0(0) = 0.25 (h = 6): the longitudinal branch's eigenvector is not resolved
    at N = 48 and 60 (tails 1.8e-4, 1.8e-5 against the tracking threshold 1e-5), and the
    scan gave up after two rungs lost before its first point (a rule meant for the dilute
    flows of the first-step loss): 36 longitudinal-only points of the 40 × 40 φ = 0.05
    diagram had no growth rate. At N = 75 it is followed; checked against the dense QZ
    spectrum at N = 100 (measured 7.05707e-4 against 7.05708e-4)."""
    from chuteflow.stability import RejectionPolicy
    from chuteflow.stability.axis_peaks import longitudinal_peak
    from chuteflow.stability.modes import spectrum
    from chuteflow.steady import solve_steady

    flow = solve_steady(16.0, 0.25)
    peak = longitudinal_peak(flow, k_max=0.05, policy=RejectionPolicy(n_start=48, n_max=160))
    assert peak.physical
    assert peak.growth > 0
    qz = max(m.alpha.real for m in spectrum(flow, peak.k, n=100))
    assert peak.growth == pytest.approx(qz, rel=1e-5)


def test_transverse_branch_followed_over_its_flat_start():
    """θ = 17.846°, ν0(0) = 0.02846, φ = 0.05 (a point of the 40 × 40 diagram): version 4
    "lost" the (real) transverse branch after its first point, k_z = 1e-5 (growth 2.05e-7
    there reported as the maximum, no cut-off): where Re α is flat, the tracker's
    acceptance (a miss below a quarter of the predicted change, plus 1e-3 |α|) needed more
    than its 6 step halvings. With 10 it follows the branch to its maximum, which is
    checked against the dense spectrum of the k_x = 0 pencil at its k_z (the independent
    method: QZ, N = 100; measured 3.3950426e-3 against 3.3950425e-3, drift 1e-8)."""
    from chuteflow.closures import ChuteModel
    from chuteflow.longwave.spanwise import transverse_longwave
    from chuteflow.stability import RejectionPolicy
    from chuteflow.stability.axis_peaks import transverse_peak
    from chuteflow.stability.transverse import dense_modes
    from chuteflow.steady import solve_steady

    flow = solve_steady(17.846153846154, 0.028461538462, ChuteModel(roughness=0.05))
    a2z = float(transverse_longwave(flow, 80).alpha2_z.real)
    peak = transverse_peak(flow, alpha2z=a2z, policy=RejectionPolicy(n_start=48, n_max=160))
    assert peak.physical
    assert peak.cutoff is not None
    assert peak.k > 1e-3
    modes, _ = dense_modes(flow, 0.0, peak.k, n=100)
    qz = max(m.alpha.real for m in modes if m.physical)
    assert peak.growth == pytest.approx(qz, abs=peak.mode.drift + 1e-12)


def test_metric_keeps_no_operator_past_its_flow():
    """The metric's operators come from a cache of its own, dropped with the flow: the
    module's cache (six operators; a three-dimensional one at N = 195 holds ~110 MB) kept
    those of earlier flows, and a worker of the 40 × 40 §5.3 diagram reached 577 MiB
    (measured on an 8 × 12 sweep of the same range: peak 640 → 569 MiB, the same values)."""
    from chuteflow.stability.modes import OPERATORS
    from chuteflow.steady import solve_steady
    from chuteflow.sweep.metrics import LongWaveMetric
    from chuteflow.sweep.points import Point

    p1_flow = solve_steady(16.0, 0.05)
    OPERATORS.clear()
    point = Point(-1, -1, 16.0, 0.05)
    point.values.update(LongWaveMetric().compute(p1_flow, point))
    n_before = len(OPERATORS)
    out = TransverseMetric().compute(p1_flow, point)
    assert out["winner"] == 3
    assert len(OPERATORS) == n_before
