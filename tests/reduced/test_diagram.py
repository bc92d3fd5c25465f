"""1D stability diagrams (fig phaseoned) and their agreement with a full-model Dataset."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import xarray as xr

from chuteflow.errors import ParameterError
from chuteflow.reduced import agreement, local_coefficients, reduced_diagram


def _full(theta, nu0, unstable):
    return xr.Dataset(
        {"unstable": (("theta", "nu0"), np.asarray(unstable, dtype=np.int8))},
        coords={"theta": theta, "nu0": nu0},
    )


def _red(theta, nu0, unstable, short=None):
    u = np.asarray(unstable, dtype=np.int8)
    s = np.zeros_like(u) if short is None else np.asarray(short, dtype=np.int8)
    return xr.Dataset(
        {"r1d_unstable": (("theta", "nu0"), u), "r1d_short_wave": (("theta", "nu0"), s)},
        coords={"theta": theta, "nu0": nu0},
    )


def test_agreement_counts_on_a_sub_grid():
    th, nu = np.linspace(12, 18, 5), np.linspace(0.01, 0.25, 5)
    full = _full(th, nu, np.tile([1, 0, 1, 0, -1], (5, 1)))
    red = _red(th[::2], nu[::2], [[1, 1, -1], [0, 0, 1], [1, 0, 1]])
    a = agreement(red, full)
    # full on the sub-grid (columns 0, 2, 4) is [1, 1, −1] in every row: the third column is
    # unknown there, so 3 × 2 points compare; red agrees at (0,0), (0,1), (2,0)
    assert a["compared"] == 6
    assert a["agree"] == 3
    assert a["fraction"] == pytest.approx(0.5)
    assert a["both_unstable"] == 3
    assert a["only_full_unstable"] == 3
    assert a["only_1d_unstable"] == 0
    assert a["both_stable"] == 0


def test_agreement_leaves_out_thin_layers():
    th, nu = np.array([12.0, 13.0]), np.array([0.1, 0.2])
    full = _full(th, nu, [[1, 0], [0, 1]])
    red = _red(th, nu, [[0, 0], [0, 1]])
    red["h"] = (("theta", "nu0"), np.array([[0.5, 3.0], [4.0, 5.0]]))
    a = agreement(red, full)  # h < 1 not examined (paper, fig phase005)
    assert a["compared"] == 3
    assert a["thin_excluded"] == 1
    assert a["fraction"] == 1.0
    b = agreement(red, full, h_min=0)
    assert b["compared"] == 4
    assert b["only_full_unstable"] == 1


def test_agreement_rejects_foreign_grids_and_missing_variables():
    th, nu = np.array([12.0, 13.0]), np.array([0.1, 0.2])
    full = _full(th, nu, [[1, 0], [0, 1]])
    with pytest.raises(ParameterError, match="sub-grid"):
        agreement(_red(th + 0.5, nu, [[1, 0], [0, 1]]), full)
    with pytest.raises(ParameterError, match="unstable"):
        agreement(_red(th, nu, [[1, 0], [0, 1]]), full.rename(unstable="other"))
    with pytest.raises(ParameterError, match="r1d_unstable"):
        agreement(full, full)


@pytest.fixture(scope="module")
def tiny():
    """The same 2 × 3 diagram from both engines."""
    kw = dict(shape=(2, 3), theta_range=(15.0, 16.0), nu0_range=(0.05, 0.15))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return {e: reduced_diagram(0.05, engine=e, **kw) for e in ("sweep", "walk")}


@pytest.mark.parametrize("engine", ["sweep", "walk"])
def test_diagram_values_are_the_local_coefficients(tiny, engine):
    from chuteflow.closures import ChuteModel
    from chuteflow.steady import solve_steady

    ds = tiny[engine]
    assert (ds["status"].values == 0).all()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        f = solve_steady(16.0, 0.1, ChuteModel())
    c = local_coefficients(f)
    i, j = 1, 1
    # both engines converge every flow to rtol 1e-8 between resolutions
    assert ds["rho_bar"].values[i, j] == pytest.approx(f.rho_bar, rel=1e-7)
    assert ds["r1d_margin"].values[i, j] == pytest.approx(c.criterion_margin, rel=1e-5)
    assert ds["r1d_unstable"].values[i, j] == int(c.unstable)
    assert ds["r1d_dq0"].values[i, j] == pytest.approx(c.dq0, rel=1e-6)
    # (θ, ν0) = (16°, 0.05): the paper's P1 — unstable in the 1D model, at every k
    assert ds["r1d_unstable"].values[1, 0] == 1
    assert ds["r1d_short_wave"].values[1, 0] == 1


def test_engines_agree(tiny):
    a, b = tiny["sweep"], tiny["walk"]
    for v in ("h", "nu_mean", "r1d_margin", "r1d_alpha2", "r1d_dq0"):
        assert np.allclose(a[v].values, b[v].values, rtol=1e-5), v
    assert np.array_equal(a["r1d_unstable"].values, b["r1d_unstable"].values)


def test_bad_diagram_arguments():
    with pytest.raises(ParameterError, match="engine"):
        reduced_diagram(0.05, engine="magic")
    with pytest.raises(ParameterError, match="full"):
        reduced_diagram(0.05, engine="walk", full=True)
    with pytest.raises(ParameterError, match="shape"):
        reduced_diagram(0.05, shape=(1, 1))
    with pytest.raises(ParameterError, match="grid"):
        reduced_diagram(0.05, grid=([16.0], [0.2, 0.1]))
