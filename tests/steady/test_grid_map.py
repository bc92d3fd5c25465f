"""One sinh map at the layer's edge for the steady and the stability grid
(:func:`chuteflow.spectral.layer_edge_map`), with one fallback rule: no map (plain
Chebyshev nodes) where the width is not a positive number at most half the domain, or the
edge is not inside it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.spectral import (
    LAYER_MAP_MAX,
    LAYER_MAP_WIDTH,
    ChebyshevGrid,
    MappedChebyshevGrid,
    layer_edge_map,
)
from chuteflow.stability.operator import layer_map, stability_grid
from chuteflow.steady import solve_steady
from chuteflow.steady.grid import layer_grid_map
from chuteflow.steady.state import state_of


def test_width_is_the_scale_height_of_the_dilute_top():
    c = math.cos(math.radians(16.0))
    assert layer_edge_map(3.0, 0.5, 16.0, 40.0) == (3.0, LAYER_MAP_WIDTH * 0.5 / c)


@pytest.mark.parametrize(
    ("edge", "T_edge", "y_max"),
    [
        (3.0, 0.5, 2.0 * LAYER_MAP_WIDTH * 0.5 / math.cos(math.radians(16.0)) * 0.99),  # too wide
        (0.0, 0.5, 40.0),  # edge at the floor
        (40.0, 0.5, 40.0),  # edge at the top
        (3.0, 0.0, 40.0),  # no width
        (3.0, -0.5, 40.0),  # negative temperature
        (3.0, math.nan, 40.0),
        (3.0, math.inf, 40.0),
    ],
)
def test_fallback_is_the_plain_grid(edge, T_edge, y_max):
    assert layer_edge_map(edge, T_edge, 16.0, y_max) is None


def test_widest_map_is_half_the_domain():
    c = math.cos(math.radians(16.0))
    width = LAYER_MAP_WIDTH * 0.5 / c
    assert layer_edge_map(1.0, 0.5, 16.0, width / LAYER_MAP_MAX) is not None
    assert layer_edge_map(1.0, 0.5, 16.0, 0.999 * width / LAYER_MAP_MAX) is None


@pytest.mark.parametrize("name", ["P1", "P4", "P5"])
def test_steady_and_stability_grids_use_the_same_map(name):
    """Both grids centre the map at the layer's edge (the steady grid at its sampled edge of
    the state, the stability grid at the flow's h) with the same width rule."""
    p = POINTS[name]
    flow = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
    yc, eps = layer_map(flow)
    T_h = float(flow.grid.interpolate(flow.T, np.array([flow.h]))[0])
    assert (yc, eps) == layer_edge_map(flow.h, T_h, flow.theta, flow.y_max)
    xc, xw = layer_grid_map(state_of(flow), flow.theta)
    # the same rule at the steady grid's own (sampled) edge: its T0 there, in units of y_max
    T_c = float(flow.grid.interpolate(flow.T, np.array([xc * flow.y_max]))[0])
    assert xw == pytest.approx(
        LAYER_MAP_WIDTH * T_c / math.cos(math.radians(flow.theta)) / flow.y_max, rel=1e-9
    )
    assert abs(xc * flow.y_max - flow.h) < flow.y_max / (4 * flow.n)  # the sampled edge
    assert isinstance(stability_grid(flow, 48), MappedChebyshevGrid)


def test_stability_grid_falls_back_like_the_steady_grid(monkeypatch):
    """Where the shared map gives none, the stability grid is the plain Chebyshev grid."""
    p = POINTS["P1"]
    flow = solve_steady(p.theta, p.nu0)
    monkeypatch.setattr("chuteflow.stability.operator.layer_map", lambda f: None)
    g = stability_grid(flow, 48)
    assert type(g) is ChebyshevGrid
    assert (g.y[0], g.y[-1]) == (0.0, flow.y_max)
