"""Maps and families decide every point (issue 9, item 1): the verdicts of
:func:`chuteflow.steady.steady_map` — continuation, the shooting scan where continuation
does not reach a point, and the quadrants a scan's verdict covers (``family.Proof``) —
agree with the independent shooting scan of tests/steady/shooting.py (Table 1 typed
again, scipy DOP853; :func:`tests.steady.test_existence.reference_verdict`) at random
(θ, ν0(0)) over both of the paper's ranges (figures 6 and 12: φ = 0.05, θ 12–18°;
φ = 0.10, θ 16.5–22.5°; ν0(0) 0.01–0.30).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.papers.mitarai2004.points import DIAGRAM_RANGES
from chuteflow.steady import steady_family, steady_map
from chuteflow.steady.proofs import Proof

from . import shooting as ref
from .test_existence import reference_verdict


def _random_grid(phi, n_theta, n_nu, seed):
    rng = np.random.default_rng(seed)
    (t0, t1), (n0, n1) = DIAGRAM_RANGES[phi]
    ths = np.sort(rng.uniform(t0, t1, n_theta))
    nus = np.sort(np.exp(rng.uniform(math.log(n0), math.log(n1), n_nu)))
    return ths, nus


def _physical_reference(theta, nu0, phi):
    """Whether the independent scan finds a flow, and whether it is at least one diameter
    thick (h from the reference solution; §3.2)."""
    exists, _ = reference_verdict(theta, nu0, phi)
    if not exists:
        return False, False
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        h = ref.solve_by_shooting(theta, nu0, ref.Material(phi=phi), u_hi=1e3, n_scan=60, rtol=1e-9).h
    return True, h >= 1.0


def _check_map(phi, n_theta, n_nu, seed):
    ths, nus = _random_grid(phi, n_theta, n_nu, seed)
    ds = steady_map(ths, nus, ChuteModel(roughness=phi), workers=1)
    st, err = ds.status.values, ds.error.values
    assert not (st == "unreached").any()
    for i, th in enumerate(ths):
        for j, nu in enumerate(nus):
            exists, physical = _physical_reference(float(th), float(nu), phi)
            where = (phi, float(th), float(nu), str(st[i, j]), str(err[i, j])[:300])
            if st[i, j] == "ok":
                assert physical, where
            elif st[i, j] == "not_converged":
                # only a flow that exists but is not resolved, with the scan's estimate
                assert exists, where
                assert "a steady flow exists" in err[i, j], where
            else:  # no_steady_flow or thin: none at least one diameter thick
                assert not physical, where
    return st


def test_map_decides_every_point_fast():
    """A 3 × 3 map at random points of the φ = 0.10 range (default suite)."""
    _check_map(0.10, 3, 3, seed=3)


@pytest.mark.slow
@pytest.mark.parametrize("phi", [0.05, 0.10])
def test_map_verdicts_agree_with_independent_shooting(phi):
    """6 × 5 random (θ, ν0(0)) per roughness (60 points in all), each verdict checked."""
    st = _check_map(phi, 6, 5, seed=int(phi * 1000))
    assert (st == "not_converged").sum() <= 1


def test_family_decides_every_point():
    """A family across the whole ν0(0) range at θ = 13° (φ = 0.05) crosses the lower
    existence boundary: no point is left unreached, the ones below it have the scan's
    verdict (or a covering one) and those above a converged flow."""
    nus = np.geomspace(0.01, 0.25, 12)
    ds = steady_family(13.0, nus, tangent=False)
    st = ds.status.values
    assert set(st) <= {"ok", "thin", "no_steady_flow"}
    ok = np.nonzero(st == "ok")[0]
    assert len(ok)
    assert (np.diff(ok) == 1).all()
    assert ok[-1] == len(nus) - 1
    for j in range(ok[0]):
        assert st[j] in ("thin", "no_steady_flow")
        assert "shooting" in ds.error.values[j] or "thickness" in ds.error.values[j]


def test_proof_quadrants():
    """A verdict 'too small' covers smaller θ and ν0(0); 'too large' larger ones."""
    low = Proof(14.0, 0.05, "too_small", "")
    assert low.covers(13.0, 0.04)
    assert low.covers(14.0, 0.05)
    assert not low.covers(14.5, 0.04)
    assert not low.covers(13.0, 0.06)
    high = Proof(17.0, 0.2, "too_large", "")
    assert high.covers(18.0, 0.25)
    assert not high.covers(16.0, 0.3)
    assert not high.covers(18.0, 0.1)
