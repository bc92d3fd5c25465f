"""The cost cuts of a family row's steady solves change no verdict and no value.

- :func:`chuteflow.steady.result._chebval1` is numpy's ``chebval`` on Python floats: the
  same Clenshaw recurrence, hence bit for bit the same value.
- ``Options.noise_exit`` stops a resolution ladder at the round-off floor; on a row of the
  quick φ = 0.05 stability diagram with such ladders (θ = 12.77°, near the lower existence
  boundary, where thin layers h < 0.3 are not resolved to 1e-8), the statuses and the
  values are those of the ladder run to n_max (measured on the whole 40 × 40 diagram of
  both φ: 0 status changes, values identical).
"""

from unittest import mock

import numpy as np
import pytest
from numpy.polynomial.chebyshev import chebval

from chuteflow.closures import ChuteModel
from chuteflow.steady import api, family
from chuteflow.steady.result import _chebval1


@pytest.mark.parametrize("n", [1, 2, 3, 17, 217])
def test_chebval1_is_chebval(n):
    rng = np.random.default_rng(n)
    c = rng.standard_normal(n) * np.exp(-np.arange(n) / 20)
    for x in rng.uniform(-1, 1, 50):
        assert _chebval1(c.tolist(), float(x)) == float(chebval(np.asarray(x), c))


def test_noise_exit_keeps_statuses_and_values():
    model = ChuteModel(roughness=0.05)
    theta = 12.0 + 10.0 / 13.0
    nus = np.geomspace(0.005, 0.5, 40)[26:32]
    sizes: list[int] = []
    solve_state = api.solve_state

    def counted(*args, **kw):
        sizes.append(args[4])
        return solve_state(*args, **kw)

    out = {}
    with np.errstate(all="ignore"), mock.patch.object(api, "solve_state", counted):
        for noise_exit in (False, True):
            sizes.clear()
            opts = family.Options(min_thickness=0.0, tangent=False, noise_exit=noise_exit)
            out[noise_exit] = (family.continue_row(theta, nus, model, opts), max(sizes))
    (ref, n_ref), (new, n_new) = out[False], out[True]
    # the ladders at the round-off floor went up to n = 486 (> n_max = 384): now they stop
    assert n_new < n_ref
    assert [p.status for p in new] == [p.status for p in ref]
    assert any(p.status == "ok" for p in ref) and any(p.status != "ok" for p in ref)
    for p, q in zip(new, ref):
        if p.status == "ok":
            assert p.flow.Q == pytest.approx(q.flow.Q, rel=1e-12)
            assert p.flow.h == pytest.approx(q.flow.h, rel=1e-12)
