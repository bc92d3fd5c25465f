"""The cost cuts of a family row's steady solves change no verdict and no value.

- :func:`chuteflow.steady.result._chebval1` is numpy's ``chebval`` on Python floats: the
  same Clenshaw recurrence, hence bit for bit the same value.
- ``Options.noise_exit`` stops a resolution ladder at the round-off floor; on rows of the
  φ = 0.05 stability diagrams with such ladders (θ = 12.77° and 14.28°, near the lower
  existence boundary, where thin layers are not resolved to 1e-8), the statuses and the
  values are those of the ladder run to n_max (measured on the whole 40 × 40 diagram of
  both φ: 0 status changes, values identical).
"""

from unittest import mock

import numpy as np
import pytest
from numpy.polynomial.chebyshev import chebval

from chuteflow.closures import ChuteModel
from chuteflow.steady import continuation_step, ladder, proofs, rows
from chuteflow.steady.options import Options
from chuteflow.steady.result import _chebval1, _series


@pytest.mark.parametrize("n", [1, 2, 3, 17, 217])
def test_chebval1_is_chebval(n):
    rng = np.random.default_rng(n)
    c = rng.standard_normal(n) * np.exp(-np.arange(n) / 20)
    for x in rng.uniform(-1, 1, 50):
        assert _chebval1(c.tolist(), float(x)) == float(chebval(np.asarray(x), c))


@pytest.mark.parametrize("n", [1, 2, 3, 17, 217])
def test_compiled_chebval1_is_the_same_float(n):
    """The series evaluator of derived_quantities (compiled where a C compiler is
    available, ``-ffp-contract=off``) gives :func:`_chebval1`'s float, bit for bit: h and
    the density peak do not depend on which road ran."""
    rng = np.random.default_rng(100 + n)
    c = rng.standard_normal(n) * np.exp(-np.arange(n) / 20)
    f = _series(c)
    for x in rng.uniform(-1, 1, 50):
        assert f(float(x)) == _chebval1(c.tolist(), float(x))


#: Rows near the lower existence boundary whose ladders reach the round-off floor. Which
#: points sit at the floor depends on round-off (the compiled closures or numpy's, the
#: machine's libm): on this machine the first row does with numpy's closures, the second
#: with the compiled ones; the test needs at least one of them to.
_FLOOR_ROWS = (
    (12.0 + 10.0 / 13.0, np.geomspace(0.005, 0.5, 40)[26:32]),
    (12.0 + 66.0 / 29.0, np.geomspace(0.01, 0.25, 30)[5:10]),
)


def test_noise_exit_keeps_statuses_and_values():
    model = ChuteModel(roughness=0.05)
    sizes: list[int] = []
    solve_state = ladder.solve_state

    def counted(*args, **kw):
        sizes.append(args[4])
        return solve_state(*args, **kw)

    floors = 0
    for theta, nus in _FLOOR_ROWS:
        out = {}
        with mock.patch.object(ladder, "solve_state", counted):
            for noise_exit in (False, True):
                sizes.clear()
                opts = Options(min_thickness=0.0, tangent=False, noise_exit=noise_exit)
                out[noise_exit] = (rows.continue_row(theta, nus, model, opts), max(sizes))
        (ref, n_ref), (new, n_new) = out[False], out[True]
        # the ladders at the round-off floor went up to n = 486 (> n_max = 384): with the
        # noise exit they stop before, where the change grows at the floor
        assert n_new <= n_ref
        floors += n_new < n_ref
        assert [p.status for p in new] == [p.status for p in ref]
        assert any(p.status == "ok" for p in ref)
        assert any(p.status != "ok" for p in ref)
        for p, q in zip(new, ref):
            if p.status == "ok":
                assert p.flow.Q == pytest.approx(q.flow.Q, rel=1e-12)
                assert p.flow.h == pytest.approx(q.flow.h, rel=1e-12)
    assert floors >= 1, "no ladder stopped at the round-off floor: the test does not test noise_exit"


def _row(theta, nus, model, opts):
    """continue_row with its cold starts and the Newton starts of its scans' flows counted."""
    colds, starts = [], []
    cold, attempt = rows._cold, continuation_step._attempt

    def counted_cold(*args, **kw):
        p = cold(*args, **kw)
        colds.append(p.usable)
        return p

    def counted_attempt(theta, nu0, model, opts, start, n, cold=False, **kw):
        starts.append((nu0, n))
        return attempt(theta, nu0, model, opts, start, n, cold, **kw)

    with (
        mock.patch.object(rows, "_cold", counted_cold),
        mock.patch.object(continuation_step, "_attempt", counted_attempt),
        mock.patch.object(proofs, "_attempt", counted_attempt),
    ):
        return rows.continue_row(theta, nus, model, opts), colds, starts


def test_cold_starts_wait_for_the_verdict_at_the_branch_end():
    """A row of the quick φ = 0.05 diagram grid whose flows lie at the dense end: once the
    cold start in the middle has found them, the scan at the end of that piece of the branch
    goes before any further cold start, and its verdict ('too small': no flow at any smaller
    θ and ν0(0), :class:`~chuteflow.steady.proofs.Proof`) covers the rest of the row. Before,
    three more cold starts below it failed there (~0.15 s each); statuses and values of the
    40 × 40 quick diagrams of both φ are unchanged (measured: 0 status changes)."""
    model = ChuteModel(roughness=0.05)
    nus = np.linspace(0.01, 0.25, 20)
    pts, colds, _ = _row(12.0 + 18.0 / 19.0, nus, model, Options(min_thickness=0.0, tangent=False))
    st = [p.status for p in pts]
    ok = [j for j, s in enumerate(st) if s == "ok"]
    assert ok
    assert ok == list(range(ok[0], len(nus)))
    assert all(s == "no_steady_flow" for s in st[: ok[0]])
    assert sum(not u for u in colds) <= 1, colds
    assert any("too small" in p.error or "heats up" in p.error for p in pts[: ok[0]])


def test_layer_below_a_diameter_gets_two_newton_starts():
    """The scan finds a layer of h = 0.16 (θ = 13.26°, ν0(0) = 0.098, φ = 0.05: below one
    diameter, outside the hydrodynamics, §3.2). Where Newton from the shot profile does not
    resolve it to 1e-8, it is tried from n and 2n, not also from 4n (~0.5 s more; on the
    quick diagrams of both φ no such layer converged from 4n only). Whether Newton converges
    at this layer from n = 64 depends on round-off (it did before the barycentric
    interpolation, not since): the attempts are made to fail here, so that the rule itself
    is what is tested."""
    model = ChuteModel(roughness=0.05)
    opts = Options(min_thickness=0.0, tangent=False)
    starts = []

    def failing(theta, nu0, model, opts, start, n, cold=False):
        starts.append(n)
        assert start is not None
        assert start.n == n
        return continuation_step._Point("not_converged", None, "Newton stalled (made to fail by the test)")

    with mock.patch.object(proofs, "_attempt", failing):
        p, v = proofs._decide(13.263157894737, 0.098421052632, model, opts)
    assert v.exists
    assert v.h < 1.0
    assert starts == [64, 128]
    assert p.status == "no_steady_flow"
    assert "thinner than one diameter" in p.error


def test_layer_below_a_diameter_is_solved_from_the_shot_profile():
    """The same layer with min_thickness = 1 (a map's default): whatever the route, the
    point is a thin layer — with its flow where Newton from the shot profile resolves it,
    without one (the scan's solution) where it does not; the label does not depend on which
    of the two found it (it did: one route said 'thin', the other 'no_steady_flow', and a
    change of round-off flipped 6 such points of the 60 × 60 paper map)."""
    model = ChuteModel(roughness=0.05)
    opts = Options(min_thickness=1.0, tangent=False)
    p, v = proofs._decide(13.263157894737, 0.098421052632, model, opts)
    assert v.exists
    assert not v.physical
    assert 0.1 < v.h < 0.2
    assert p.status == "thin"
    assert "below 1 particle diameter" in p.error
    if p.flow is not None:
        assert abs(p.flow.h - v.h) < 1e-3 * v.h

    def failing(theta, nu0, model, opts, start, n, cold=False):
        return continuation_step._Point("not_converged", None, "Newton stalled (made to fail by the test)")

    with mock.patch.object(proofs, "_attempt", failing):
        q, _ = proofs._decide(13.263157894737, 0.098421052632, model, opts)
    assert q.status == "thin"
    assert q.flow is None
    assert not q.usable
    assert "below 1 particle diameter" in q.error
