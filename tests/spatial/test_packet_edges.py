"""One edge of the growing packet is the kinematic (long-wave) wave speed.

At k → 0 the α(0) = 0 branch is α = −i (dQ0/dρ̄0) k + α2 k² + …, with Re α2 > 0 at the
paper's unstable points (long-wave unstable): the ray growth Re(α + ikV) vanishes at k = 0 for
every V, and the saddle family reaches the branch point k = 0 at V = dQ0/dρ̄0. So that edge
must equal the long-wave phase velocity of :mod:`chuteflow.longwave` — two independent
computations (the continued saddle of the complex-k branch; the steady family's tangent,
appendix B). It is the lower edge V− at P1, the upper edge V+ at P4 and P5.
"""

import pytest

from chuteflow.closures import ChuteModel
from chuteflow.longwave import longwave
from chuteflow.spatial import AbsoluteResult, absolute_instability
from chuteflow.steady import solve_steady


@pytest.mark.slow
def test_p1_lower_edge_is_the_kinematic_wave_speed():
    """Measured: V− = 4.152490 against dQ0/dρ̄0 = 4.152360 (``longwave(flow).dQ_drho``; −Im α1
    = 4.152360 too): 3.1e-5 relative, V− being −Im(α'(k) − k α''(k)) at k = 2e-5 k_peak (the
    linear term 2 α2 k removed; 4.152547, 4.5e-5, with −Im α'(k) alone at the old k = 2e-5 k_peak).
    Tolerance 2e-4 relative. The upper edge V+ = 9.00427 (measured; 1e-3)."""
    flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
    res = absolute_instability(flow)
    assert isinstance(res, AbsoluteResult)
    assert res.converged, res.note
    assert res.verdict == "convective"
    c0 = longwave(flow).dQ_drho
    assert res.v_minus == pytest.approx(c0, rel=2e-4)
    assert res.v_plus == pytest.approx(9.004, rel=1e-3)
    d = res.to_dict()
    assert {"verdict", "v_minus", "v_plus", "absolute_growth", "converged", "note"} <= set(d)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("theta", "nu0", "v_minus", "v_plus"),
    [(14.0, 0.05, 1.876156, 2.275087), (17.0, 0.10, 16.20181, 18.13926)],
    ids=["P4", "P5"],
)
def test_p4_p5_upper_edge_is_the_kinematic_wave_speed(theta, nu0, v_minus, v_plus):
    """Measured: P4 V+ = 2.2750979 against dQ0/dρ̄0 = 2.2750995 (7e-7), P5 V+ = 18.139269
    against 18.139275 (3.5e-7); both convective. Tolerance 2e-4 relative, as at P1."""
    flow = solve_steady(theta, nu0, ChuteModel(roughness=0.05))
    res = absolute_instability(flow)
    assert res.converged, res.note
    assert res.verdict == "convective"
    assert res.v_plus == pytest.approx(longwave(flow).dQ_drho, rel=2e-4)
    assert res.v_minus == pytest.approx(v_minus, rel=1e-3)
    assert res.v_plus == pytest.approx(v_plus, rel=1e-3)


def test_p5_edges_do_not_depend_on_the_continuation_step():
    """The saddle family continued in V with steps of 0.08 V_peak (the default is 0.1): before
    the corrector had to land near the predictor (``absolute.CORRECTOR_RATIO``), the first
    step down from the temporal peak at P5 jumped to another saddle family (k* ≈ 0.028 −
    0.012i, σ < 0) and reported V− = V_peak = 16.889 as converged; the edges with steps of
    0.04 … 0.12 V_peak now agree to 1e-8 (measured: V− = 16.2018095 at each of 0.04, 0.06,
    0.08, 0.1, 0.12). Tolerance 1e-6 relative against the default step's value, 16.20181 the
    reproduce stage's reference (docs/spatial.md)."""
    import dataclasses

    from chuteflow.spatial import DEFAULT_SPATIAL_POLICY

    flow = solve_steady(17.0, 0.10, ChuteModel(roughness=0.05))
    res = absolute_instability(flow, policy=dataclasses.replace(DEFAULT_SPATIAL_POLICY, ray_step=0.08))
    assert res.converged, res.note
    assert res.v_minus == pytest.approx(16.2018095, rel=1e-6)
    assert res.v_plus == pytest.approx(18.1392688, rel=1e-6)


def test_a_corrector_far_from_the_predictor_is_rejected():
    """The acceptance rule itself: Newton's saddle within CORRECTOR_RATIO × the predictor's
    step of the predictor is the same family; further away it is not."""
    from types import SimpleNamespace

    from chuteflow.errors import ConvergenceError
    from chuteflow.spatial.absolute import CORRECTOR_RATIO, _check_same_family

    e = SimpleNamespace(k=1.6e-3 + 0j)
    pred = 1.5e-3 - 1e-4j  # a step of ~1.4e-4
    _check_same_family(e, pred, SimpleNamespace(k=pred + 0.2 * CORRECTOR_RATIO * abs(pred - e.k)))
    with pytest.raises(ConvergenceError, match="another saddle family"):
        _check_same_family(e, pred, SimpleNamespace(k=0.028 - 0.012j))


@pytest.mark.slow
def test_p4_edges_at_the_coarse_continuation_equal_the_full_one():
    """The continuation at N = 0.6 N with the edges refined at N (``SpatialPolicy.coarse``,
    the default) against the whole continuation at N (coarse = 1): measured V− 1.8761555800 /
    1.8761555799, V+ 2.2750979589 / 2.2750978627 (4e-8 apart: V+ is the branch-point estimate
    at k = 2e-5 k_peak, reached from a different last saddle). Tolerance 1e-7 relative."""
    import dataclasses

    from chuteflow.spatial import DEFAULT_SPATIAL_POLICY

    flow = solve_steady(14.0, 0.05, ChuteModel(roughness=0.05))
    fast = absolute_instability(flow)
    full = absolute_instability(flow, policy=dataclasses.replace(DEFAULT_SPATIAL_POLICY, coarse=1.0))
    assert fast.converged, fast.note
    assert full.converged, full.note
    assert fast.v_minus == pytest.approx(full.v_minus, rel=1e-7)
    assert fast.v_plus == pytest.approx(full.v_plus, rel=1e-7)
