"""The one convention for results (chuteflow.results, docs/extending.md "Results"): every
solver's result has ``converged``, ``note`` and ``to_dict()``; solvers default to
``strict=False`` (a flagged result) and raise with ``strict=True``."""

from __future__ import annotations

import inspect
import json
import math

import numpy as np
import pytest

from chuteflow.longwave import longwave
from chuteflow.longwave.spanwise import transverse, transverse_longwave
from chuteflow.results import Result
from chuteflow.stability import (
    BranchScan,
    Crossings,
    RejectionPolicy,
    branch_scan,
    critical_k,
    crossings,
    dispersion,
    least_stable,
    least_stable_3d,
    transverse_dispersion,
)


def _check(result) -> None:
    assert isinstance(result, Result), type(result)
    assert isinstance(result.converged, bool)
    assert isinstance(result.note, str)
    assert (result.note == "") == result.converged or not result.converged
    json.dumps(result.to_dict(), allow_nan=True)  # JSON-ready


def test_results_of_the_solvers_follow_the_convention(p1_flow):
    _check(p1_flow)
    _check(least_stable(p1_flow, 0.002))
    scan = branch_scan(p1_flow, k_max=0.02, num=8, refine_peak=False)
    _check(scan)
    _check(scan.to_crossings())
    _check(transverse_longwave(p1_flow, 60, rtol=1e-2))
    res = transverse(p1_flow, num=8)
    _check(res)
    _check(res.dispersion)
    _check(longwave(p1_flow, n=60, rtol=0.5, eig_ks=(1e-5,)))


def test_a_result_that_misses_its_tolerance_is_flagged_with_a_note():
    # a scan whose points failed the tests (synthetic: no solve needed)
    scan = BranchScan.from_samples(
        [0.01, 0.02, 0.03], [0.1, -0.1, -0.2], physical=[True, False, True], note=""
    )
    assert not scan.converged
    c = Crossings((0.015,), converged=False, note="branch lost near k = 0.02")
    assert list(c) == [0.015]
    assert len(c) == 1
    assert c[0] == 0.015
    assert c.to_dict()["ks"] == [0.015]
    assert not c.converged
    assert c.note


def test_strict_defaults_to_false_everywhere():
    """Every solver that takes ``strict`` returns a flagged result by default."""
    from chuteflow.steady import solve_steady

    for fn in (
        solve_steady,
        least_stable,
        least_stable_3d,
        dispersion,
        branch_scan,
        critical_k,
        crossings,
        longwave,
        transverse_longwave,
        transverse_dispersion,
    ):
        params = inspect.signature(fn).parameters
        if "strict" in params:
            assert params["strict"].default is False, fn.__qualname__


def test_strict_true_raises_where_the_default_flags(p1_flow):
    from chuteflow.errors import ConvergenceError

    lw = transverse_longwave(p1_flow, 40, rtol=1e-14, n_max=40)
    assert not lw.converged
    assert "alpha2_z changed" in lw.note
    assert math.isfinite(lw.alpha2_z.real)
    with pytest.raises(ConvergenceError):
        transverse_longwave(p1_flow, 40, rtol=1e-14, n_max=40, strict=True)
    tight = RejectionPolicy(drift_tol=1e-15, tail_tol=1e-15, n_start=48, n_max=48)
    ds = dispersion(p1_flow, [0.002], policy=tight)
    assert not bool(np.asarray(ds["physical"]).all())
    with pytest.raises(ConvergenceError):
        dispersion(p1_flow, [0.002], policy=tight, strict=True)
