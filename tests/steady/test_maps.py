"""How :func:`chuteflow.steady.steady_map` splits a map into chains of rows (issue 9, item 4:
the two processes share the work): the chains cover every row once, and the numbers do not
depend on how many processes run them."""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.steady import maps, steady_family, steady_map


@pytest.mark.parametrize(
    ("n", "starts"),
    [(9, [4]), (12, [3, 8]), (60, [15, 44]), (13, [3, 4]), (2, [0]), (2, [1]), (1, [0])],
)
def test_chains_cover_every_row_once(n, starts):
    chains = maps._chains(n, starts)
    rows = [i for _, chain in chains for i in chain]
    assert sorted(rows + starts) == list(range(n))
    for start, chain in chains:
        # contiguous, going away from the start row, each row seeded by the one before
        steps = np.diff([start, *chain])
        assert (steps == steps[0]).all()
        assert abs(steps[0]) == 1
    # two starts: four chains; the two between the starts meet in the middle
    if len(starts) == 2 and starts[1] - starts[0] > 1:
        a, b = starts
        mid = (a + b) // 2
        assert (a, list(range(a + 1, mid + 1))) in chains
        assert (b, list(range(b - 1, mid, -1))) in chains


def test_two_starts_on_large_maps(monkeypatch):
    """A map of TWO_STARTS rows starts from two rows (near 25 % and 75 %), four chains; the
    same numbers, bit for bit, with one process and with two."""
    ths = np.linspace(14.5, 17.0, maps.TWO_STARTS)
    nus = np.geomspace(0.03, 0.12, 3)
    seen = []
    start_rows = maps._start_rows

    def spy(*args, **kwargs):
        out = start_rows(*args, **kwargs)
        seen.append(sorted(out[0]))
        return out

    monkeypatch.setattr(maps, "_start_rows", spy)
    a = steady_map(ths, nus, workers=1)
    b = steady_map(ths, nus, workers=2)
    assert seen == [[3, 8], [3, 8]]
    assert (a.status.values == "ok").all()
    assert (a.status.values == b.status.values).all()
    for v in ("h", "Q", "rho_bar", "u_floor", "convergence"):
        np.testing.assert_array_equal(a[v].values, b[v].values)
    # and the flows are those of a family solved on its own (another road to each point:
    # equal within the resolution check, rtol = 1e-8 between n and 3n/2; over the 60 × 60
    # paper map the one-start and two-start roads differ by at most 2.4e-8 in h)
    fam = steady_family(float(ths[-1]), nus)
    np.testing.assert_allclose(a.h.values[-1], fam.h.values, rtol=1e-7)


def test_start_theta_gives_one_start():
    """``start_theta``: that row alone starts the chains (two of them)."""
    ths = np.linspace(14.5, 17.0, maps.TWO_STARTS)
    nus = np.geomspace(0.03, 0.12, 2)
    ds = steady_map(ths, nus, workers=1, start_theta=15.0)
    assert (ds.status.values == "ok").all()
