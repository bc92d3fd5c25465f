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
