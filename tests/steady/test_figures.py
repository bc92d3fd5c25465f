"""Steady figures (figs steadyphase005/010, steady, steady01) draw from computed results."""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.figures.steady import plot_flux_density, plot_h_nubar, profiles_figure, steady_phase_figure
from chuteflow.steady import solve_steady, steady_family, steady_map


@pytest.fixture(scope="module")
def small():
    mp = steady_map([15.0, 16.0, 17.0], np.geomspace(0.02, 0.2, 6), workers=1)
    fam = steady_family(16.0, np.geomspace(0.02, 0.2, 6))
    return mp, fam


def test_phase_figure(tmp_path, small):
    mp, fam = small
    png = steady_phase_figure(mp, [fam], tmp_path / "phase.png", minima={16.0: None})
    assert png.exists()
    assert png.stat().st_size > 10_000


def test_h_nubar_lines_are_the_rows(small):
    """Each θ row of the map is one contour line of θ in the (h, ν̄) plane."""
    import matplotlib.pyplot as plt

    mp, _ = small
    ax = plot_h_nubar(mp)
    lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 1]
    assert len(lines) == 3
    h = mp.h.sel(theta=16.0).values
    assert np.allclose(lines[1].get_xdata(), h[np.isfinite(h)])
    plt.close(ax.figure)


def test_flux_density_plot(small):
    import matplotlib.pyplot as plt

    _, fam = small
    ax = plot_flux_density([fam])
    x, y = ax.get_lines()[0].get_data()
    ok = fam.status.values == "ok"
    assert np.allclose(x, fam.rho_bar.values[ok])
    assert np.allclose(y, fam.Q.values[ok])
    plt.close(ax.figure)


def test_profiles_figure(tmp_path):
    flows = [solve_steady(16.0, v) for v in (0.05, 0.15)]
    png = profiles_figure(flows + [None], tmp_path / "steady.png")
    assert png.exists()
    assert png.stat().st_size > 10_000
