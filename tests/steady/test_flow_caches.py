"""What a steady flow caches, and that no cache keeps a flow alive.

A flow builds its grid (D and, on first use, D2: O(n³)) once and keeps it; the package's
per-flow caches (Newton's dX/dβ, :func:`~chuteflow.steady.steady_tangent`, the stability
grid's :func:`~chuteflow.stability.operator.layer_map`) hold flows by weak reference. Before
(up to commit fb0a9ce) the tangent caches kept the last 256 flows alive, which with cached
grids would have held ~3 MB per flow at N = 432.
"""

from __future__ import annotations

import gc
import pickle
import weakref

import numpy as np

from chuteflow.stability.operator import layer_map
from chuteflow.steady import solve_steady, steady_tangent


def test_grid_is_built_once_and_not_pickled():
    flow = solve_steady(16.0, 0.05)
    g = flow.grid
    assert flow.grid is g
    d = flow.derivatives()
    assert np.array_equal(d["u_yy"], g.D2 @ flow.u)
    copy = pickle.loads(pickle.dumps(flow))
    assert "grid" not in vars(copy)
    assert copy == flow
    # rebuilt on demand: the same nodes and matrices
    assert np.array_equal(copy.grid.y, g.y)
    assert np.array_equal(copy.grid.D2, g.D2)


def test_per_flow_caches_do_not_keep_flows_alive():
    flow = solve_steady(16.0, 0.05)
    steady_tangent(flow)
    layer_map(flow)
    flow.grid.D2  # noqa: B018  (the cached grid with its D2)
    ref = weakref.ref(flow)
    del flow
    gc.collect()
    assert ref() is None
