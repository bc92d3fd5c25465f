"""Eigen-solvers and spurious-mode rejection (paper §4.1)."""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.errors import ParameterError
from chuteflow.spectral import ChebyshevGrid
from chuteflow.stability import Mode, ShiftInvert, least_stable, qz, spectrum, stability_operator
from chuteflow.stability.modes import nearest_eigenpair, normalise, tail

K = 2e-3  # the wavenumber of the paper's eigenfunction figures (eigens, eigenu)


def test_shift_invert_agrees_with_qz_on_the_same_pencil(p1_flow):
    """The targeted solver returns QZ's eigenvalue to 1e-9 (benchmark criterion), from a
    shift 1e-4 away."""
    p = stability_operator(p1_flow, 80).pencil(K)
    w, _ = qz(*p.equilibrated(), vectors=False)
    mode = least_stable(p1_flow, K, n=80)
    ref = w[np.argmin(np.abs(w - mode.alpha))]
    alpha, _ = nearest_eigenpair(p, mode.alpha + 1e-4)
    assert abs(alpha - ref) < 1e-9
    assert abs(mode.alpha - ref) < 1e-9


def test_shift_invert_handles_singular_B_without_M_trick():
    """(A − σB)⁻¹B x: B's zero rows give θ = 0, never an eigenvalue; a 3 × 3 example with
    one infinite eigenvalue and finite ones 1 and 2."""
    A = np.array([[1.0, 0, 0], [0, 2.0, 0], [1.0, 1.0, 1.0]], dtype=complex)
    B = np.diag([1.0, 1.0, 0.0])
    w, _ = qz(A, B)
    assert np.allclose(np.sort(w.real), [1.0, 2.0])
    si = ShiftInvert(A, B, 1.2)
    a, V = si.nearest(1)
    assert abs(a[0] - 1.0) < 1e-12
    assert np.allclose(A @ V[:, 0], a[0] * B @ V[:, 0], atol=1e-12)


def test_tail_statistic_and_normalisation():
    g = ChebyshevGrid(64, 0.0, 10.0)
    smooth = np.concatenate([np.exp(-g.y), 0.5j * np.exp(-g.y / 2)])
    v = normalise(smooth * (3 - 2j))
    big = v[np.argmax(np.abs(v))]
    assert abs(abs(big.real) + abs(big.imag) - 1.0) < 1e-15  # paper's normalisation
    assert tail(smooth, 2) < 1e-13
    rough = smooth + 1e-5 * (-1.0) ** np.arange(smooth.size)  # grid-scale noise
    assert tail(rough, 2) > 1e-6


def test_continuum_passes_drift_but_fails_tail(flows):
    """ERRATA: the dilute top carries near-neutral modes α ≈ −ik u0(y_max) − 1e-8 whose
    eigenvalues barely drift with N but whose eigenvectors are unresolved. At P3 (stable)
    they lie above the physical mode: drift alone would call the flow neutral."""
    flow = flows("P3")
    modes = spectrum(flow, K, n=80, physical_only=False)
    top = modes[0]
    assert top.alpha.real > -1e-6
    assert abs(top.alpha.imag + K * flow.u[-1]) < 1e-6
    assert top.drift < 1e-7 < top.tail
    assert not top.physical
    physical = [m for m in modes if m.physical]
    assert physical
    assert physical[0].alpha.real < -1e-3


@pytest.mark.slow
def test_qz_scan_and_branch_agree_on_the_least_stable_mode(flows):
    """The least-stable physical mode of the whole spectrum (dense QZ) is the α(0) = 0
    branch at the paper's checkpoints (§4.2: 'the least stable mode satisfies α(0) = 0')."""
    for name in ("P1", "P2", "P5"):
        flow = flows(name)
        for k in (1e-3, 5e-3):
            by_qz = least_stable(flow, k, method="qz", n=100)
            by_branch = least_stable(flow, k, n=100)
            assert abs(by_qz.alpha - by_branch.alpha) < 1e-9, (name, k)


def test_mode_carries_convergence_and_exports(p1_flow):
    m = least_stable(p1_flow, K)
    assert isinstance(m, Mode)
    assert m.physical
    assert m.drift < 1e-7
    assert m.tail < 1e-7
    assert m.n_check < m.n
    assert set(m.fields) == {"nu", "u", "v", "T"}
    big = max(np.abs(f).max() for f in m.fields.values())
    assert big == pytest.approx(1.0)
    s = m.to_dict()
    assert {"k", "alpha_re", "alpha_im", "drift", "tail", "n"} <= set(s)
    ds = m.to_xarray()
    assert ds["nu"].shape == m.y.shape
    assert ds.attrs["n"] == m.n
    assert m.wave_speed == pytest.approx(-m.alpha.imag / K)


def test_bad_parameters_name_the_parameter(p1_flow):
    with pytest.raises(ParameterError, match="k = -0.1"):
        least_stable(p1_flow, -0.1)
    with pytest.raises(ParameterError, match="method"):
        least_stable(p1_flow, K, method="magic")
    with pytest.raises(ParameterError, match="drift_tol"):
        least_stable(p1_flow, K, drift_tol=0.0)
    with pytest.raises(ParameterError, match="n = 3"):
        spectrum(p1_flow, K, n=3)


def test_spanwise_perturbation_matches_qz(p1_flow):
    """3D: the least-stable mode for k along z (kx = 0), tracked from k = 0 with ŵ and the
    z-momentum balance, is the least-stable physical mode of the whole 3D spectrum."""
    kz = 2e-3
    by_branch = least_stable(p1_flow, 0.0, kz=kz, n=64)
    by_qz = spectrum(p1_flow, 0.0, kz=kz, n=64)[0]
    assert set(by_branch.fields) == {"nu", "u", "v", "w", "T"}
    assert abs(by_branch.alpha - by_qz.alpha) < 1e-10


def test_spectrum_on_a_ladder_reuses_the_rung_below_as_its_check(p1_flow):
    """On the policy's ladder N' = 0.8 N is the rung below: ``spectrum`` at N = 100 after
    N = 80 takes the check eigenvalues at N' = 80 from that call (QZ with eigenvectors)
    instead of a second QZ without them. The modes are those of a fresh computation, bit
    for bit (the same QZ iteration on the same pencil; measured), and the memo is what was
    used: replacing it by a sentinel moves every drift."""
    from chuteflow.stability import OperatorCache

    ladder, fresh = OperatorCache(), OperatorCache()
    spectrum(p1_flow, 0.5, n=80, physical_only=False, cache=ladder)
    got = spectrum(p1_flow, 0.5, n=100, physical_only=False, cache=ladder)
    ref = spectrum(p1_flow, 0.5, n=100, physical_only=False, cache=fresh)
    assert [(m.alpha, m.drift, m.tail) for m in got] == [(m.alpha, m.drift, m.tail) for m in ref]
    op80 = stability_operator(p1_flow, 80, cache=ladder)
    assert (0.5, 0.0) in op80.qz_eigenvalues
    op80.qz_eigenvalues[(0.5, 0.0)] = np.array([1e3 + 0j])
    moved = spectrum(p1_flow, 0.5, n=100, physical_only=False, cache=ladder)
    assert all(m.drift > 1e2 for m in moved)
