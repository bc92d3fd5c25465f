"""The resolution ladder of one point (paper §3): :func:`chuteflow.steady.ladder.solve_point`
takes its settings as one :class:`~chuteflow.steady.Options`, and its errors are those of
:mod:`chuteflow.errors`."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from chuteflow import errors
from chuteflow.closures import ChuteModel
from chuteflow.steady import Options, solve_steady
from chuteflow.steady.ladder import solve_point


def test_solve_point_with_options_is_solve_steady():
    """solve_steady's first road is solve_point from the cold start with the isolated
    Newton settings: the same flow, bit for bit."""
    model = ChuteModel()
    a = solve_point(16.0, 0.05, model, None, Options(noise_exit=False).isolated())
    b = solve_steady(16.0, 0.05, model)
    assert a == b
    assert np.array_equal(a.log_nu, b.log_nu)
    assert a.converged


def test_isolated_settings():
    o = Options().isolated()
    assert (o.maxiter, o.lam_min) == (60, 1e-6)
    assert (Options().maxiter, Options().lam_min) == (10, 1.0 / 16)
    assert dataclasses.replace(o, n=96).n == 96


def test_thin_layer_error_keeps_the_flow():
    opts = Options(min_thickness=100.0, noise_exit=False).isolated()
    with pytest.raises(errors.ThinLayerError) as info:
        solve_point(16.0, 0.05, ChuteModel(), None, opts)
    assert isinstance(info.value, errors.NoSteadyFlowError)
    assert info.value.flow.h == pytest.approx(19.5197, rel=1e-4)
    assert "below 100 particle diameter" in str(info.value)


def test_resolution_error_keeps_the_flagged_flow():
    """A ladder that ends at n_max above rtol raises ResolutionError with the flow there,
    flagged (converged False, its change as the estimate)."""
    opts = Options(rtol=1e-15, n_max=96, noise_exit=False).isolated()
    with pytest.raises(errors.ResolutionError) as info:
        solve_point(16.0, 0.05, ChuteModel(), None, opts)
    exc = info.value
    assert isinstance(exc, errors.ConvergenceError)
    assert exc.flow is not None
    assert not exc.flow.converged
    assert exc.flow.n == 96
    assert exc.flow.convergence > 1e-15
    assert exc.h == exc.flow.h
