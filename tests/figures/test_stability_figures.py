"""Stability figures (figs disp, dispmag, eigens/eigenu/eigenu01): files written, axes
labelled, the eigenfunction's phase convention and the diagnostics behind the paper's
qualitative statements."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import xarray as xr

from chuteflow.figures.stability import (
    default_height,
    dispersion_figure,
    eigenfunction_diagnostics,
    eigenfunction_fields,
    eigenfunction_figure,
    magnification_figure,
)


@pytest.fixture(scope="module")
def p1(p1_flow):
    from chuteflow.stability import least_stable

    return p1_flow, least_stable(p1_flow, 0.002)


def _synthetic(k, alpha, physical=None, **attrs):
    """A dataset shaped like chuteflow.stability.dispersion's output."""
    k = np.asarray(k, dtype=float)
    alpha = np.asarray(alpha, dtype=complex)
    phys = np.ones(len(k), bool) if physical is None else np.asarray(physical)
    return xr.Dataset(
        {"alpha_re": ("k", alpha.real), "alpha_im": ("k", alpha.imag), "physical": ("k", phys)},
        coords={"k": k},
        attrs={"theta": 16.0, "nu0": 0.05, "roughness": 0.05, **attrs},
    )


def _labels(ax):
    return ax.get_xlabel(), ax.get_ylabel(), ax.get_title()


def test_dispersion_figure_file_and_labels(tmp_path):
    k = np.linspace(0, 0.02, 11)
    a = 0.3 * k**2 * (1 - (k / 0.007) ** 2) - 4.15j * k
    ds = _synthetic(k, a, k_c=0.007)
    path = dispersion_figure(
        [("P1", ds), ("P2", _synthetic(k, -(k**2) - 7j * k))], tmp_path / "sub" / "disp.png", title="test"
    )
    assert path.exists()
    assert path.read_bytes()[:4] == b"\x89PNG"
    fig = dispersion_figure([("P1", ds)])
    top, bottom = fig.axes[0], fig.axes[1]
    assert "Re" in top.get_ylabel()
    assert "Im" in bottom.get_ylabel()
    assert "(g/\\sigma)" in top.get_ylabel()  # units of α
    assert "wavenumber" in bottom.get_xlabel()
    assert "sigma" in bottom.get_xlabel()
    assert "P1" in top.get_title()
    assert "16°" in top.get_title()
    assert "φ = 0.05" in top.get_title()
    # the critical wavenumber is marked by a vertical line at k_c
    xs = [ln.get_xdata()[0] for ln in top.get_lines() if len(set(ln.get_xdata())) == 1]
    assert 0.007 in xs
    with pytest.raises(ValueError, match="at least one"):
        dispersion_figure([])


def test_dispersion_figure_marks_unconverged_points():
    k = np.linspace(0, 0.01, 6)
    ds = _synthetic(k, -(k**2) - 1j * k, physical=[True] * 5 + [False])
    fig = dispersion_figure([("X", ds)])
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any("not converged" in s for s in labels)


def test_magnification_figure(tmp_path):
    k = np.unique(np.concatenate([np.linspace(0, 1e-4, 6), np.geomspace(1e-6, 1e-3, 5)]))
    a2 = 12460 - 1546j
    ds = _synthetic(k, a2 * k**2 / (1 + (k / 2e-4) ** 2) - 4.152j * k)
    path = magnification_figure(
        ds, tmp_path / "mag.png", alpha2=a2, dQ_drho=4.152, alpha2_uncertainty=0.07, k_mag=1e-4, label="P1"
    )
    assert path.exists()
    fig = magnification_figure(ds, alpha2=a2, dQ_drho=4.152, k_mag=1e-4)
    (ax1, ax2, ax3) = fig.axes[:3]
    assert "Re" in ax1.get_ylabel()
    assert "Im" in ax2.get_ylabel()
    assert "k^2" in ax3.get_ylabel()
    assert all("k" in ax.get_xlabel() for ax in (ax1, ax2, ax3))
    assert ax3.get_xscale() == "log"
    # the long-wave curves: α2 k² on (a), −(dQ0/dρ̄0) k on (b)
    kk, yy = ax1.get_lines()[1].get_data()
    np.testing.assert_allclose(yy, a2.real * kk**2)
    kk, yy = ax2.get_lines()[1].get_data()
    np.testing.assert_allclose(yy, -4.152 * kk)


def test_eigenfunction_fields_phase_and_scale(p1):
    flow, mode = p1
    F = eigenfunction_fields(mode, flow, y_top=5.0, nx=201, ny=51, x_peak=0.25)
    assert F["nu"].shape == (51, 201)
    assert F["x"][-1] == 1.0
    assert F["y"][-1] == 5.0
    assert F["lambda"] == pytest.approx(2 * math.pi / 0.002)
    # P1: |ν̂| is largest at the floor; scaled to 1 there, peaking at x = λ/4
    assert np.abs(F["nu"]).max() == pytest.approx(1.0, abs=1e-3)
    assert F["x"][np.argmax(F["nu"][0])] == pytest.approx(0.25, abs=0.006)
    # one wavelength: the two ends of x are the same phase
    np.testing.assert_allclose(F["T"][:, 0], F["T"][:, -1], atol=1e-12)


def test_default_height_is_a_tenth_of_the_peak(p1):
    flow, _ = p1
    y = default_height(flow)
    assert 0 < y < flow.y_max
    nu = np.exp(flow.grid.interpolate(flow.log_nu, np.array([y])))[0]
    assert nu == pytest.approx(0.1 * flow.nu_peak, rel=1e-2)


def test_eigenfunction_diagnostics_mass_balance(p1):
    """Re α ∫|ν̂|² = ∫Re[ν̂*(−ν0∇·û)] + ∫Re[ν̂*(−ν0'v̂)] (eq:leqnu times ν̂*, integrated)."""
    flow, mode = p1
    d = eigenfunction_diagnostics(mode, flow)
    assert d["identity_residual"] < 1e-6
    assert d["compression"] + d["vertical_advection"] == pytest.approx(mode.alpha.real, rel=1e-6)
    for key in ("temperature_density", "temperature_at_peak", "floor_velocity_density", "velocity_density"):
        assert -1 <= d[key] <= 1
    # paper §4.2, fig eigenu: P1 grains flow into the positive density region, T̂ < 0 there
    assert d["compression"] > 0
    assert d["temperature_at_peak"] < 0


def test_eigenfunction_figure(tmp_path, p1):
    flow, mode = p1
    path = eigenfunction_figure(mode, flow, tmp_path / "eig.png", label="P1")
    assert path.read_bytes()[:4] == b"\x89PNG"
    fig = eigenfunction_figure(mode, flow, label="P1", magnify=(0.3, 0.7, 0.0, 3.0))
    panels = [ax for ax in fig.axes if ax.get_xlabel() == r"$x/\lambda$"]
    assert len(panels) == 3
    for ax in panels:
        assert "y" in ax.get_ylabel()
        assert "sigma" in ax.get_ylabel()
    assert "density" in panels[0].get_title()
    assert "temperature" in panels[1].get_title()
    assert panels[2].get_xlim() == pytest.approx((0.3, 0.7), abs=0.01)
    colorbar_labels = [ax.get_ylabel() for ax in fig.axes if ax not in panels]
    assert any("nu" in s for s in colorbar_labels)
    assert any("T" in s for s in colorbar_labels)
    assert len(panels[0].collections) > 0  # contours and arrows drawn
    title = fig._suptitle.get_text()
    assert "P1" in title
    assert "k = 0.002" in title
    assert "unstable" in title


def test_eigenfunction_errors(p1):
    from dataclasses import replace

    from chuteflow.steady import solve_steady

    flow, mode = p1
    with pytest.raises(ValueError, match="k > 0"):
        eigenfunction_fields(replace(mode, k=0.0), flow)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        other = solve_steady(16.0, 0.10)
    with pytest.raises(ValueError, match="do not match"):
        eigenfunction_fields(mode, other)
    with pytest.raises(ValueError, match="y_top"):
        eigenfunction_fields(mode, flow, y_top=-1.0)


def test_dispersion_figure_shows_where_the_branch_was_lost():
    k = np.linspace(0, 0.01, 6)
    a = -(k**2) - 1j * k
    a[4:] = np.nan
    fig = dispersion_figure([("X", _synthetic(k, a, physical=[True] * 4 + [False] * 2))])
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert any("branch lost from k = 0.008" in t for t in texts)


def test_refined_triangulation_is_bilinear():
    """Sub-cells carry the bilinear interpolant of the grid data (exact for a bilinear
    field), and a cell with a missing corner stays one triangle on its valid corners."""
    from chuteflow.figures.diagram import refined_triangulation

    i, j = np.meshgrid(np.arange(3.0), np.arange(4.0), indexing="ij")
    X, Y = 2.0 * j + 0.3 * i, i + 0.1 * j  # an affine image of the grid
    Z = (i - 0.7) * (j - 1.3)  # bilinear in (i, j)
    valid = np.ones(i.shape, dtype=bool)
    valid[2, 3] = False
    tri, (z,) = refined_triangulation(X, Y, [Z], valid, n=4)
    assert tri.triangles.shape[0] == 5 * 2 * 16 + 1
    # every point of the triangulation carries the bilinear value at its (i, j)
    A = np.array([[0.3, 2.0], [1.0, 0.1]])  # (x, y) = A @ (i, j)
    ii, jj = np.linalg.solve(A, np.vstack([tri.x, tri.y]))
    used = np.unique(tri.triangles)
    np.testing.assert_allclose(z[used], ((ii - 0.7) * (jj - 1.3))[used], atol=1e-12)
    assert len(np.unique(np.round(ii[used] * 4, 9))) == 9  # quarter steps in i
