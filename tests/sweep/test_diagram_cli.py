"""Diagram figure (grid triangulation) and the ``diagram`` / ``plot`` commands."""

from __future__ import annotations

import numpy as np
import xarray as xr

from chuteflow.cli import main
from chuteflow.figures.diagram import _boundary_segments, grid_triangulation, plot_diagram
from chuteflow.sweep import load_sweep


def test_grid_triangulation_follows_the_grid():
    """Two triangles per cell with four valid corners, one with three, none otherwise;
    the outline of a full m×n grid has 2(m−1) + 2(n−1) edges."""
    x, y = np.meshgrid(np.arange(4.0), np.arange(3.0), indexing="ij")
    x = x + 0.3 * y  # a sheared (non-rectangular) image of the grid
    valid = np.ones((4, 3), bool)
    tri = grid_triangulation(x, y, valid)
    assert len(tri.triangles) == 2 * 3 * 2
    assert len(_boundary_segments(tri)) == 2 * 3 + 2 * 2
    valid[0, 0] = False
    assert len(grid_triangulation(x, y, valid).triangles) == 2 * 3 * 2 - 1
    valid[:] = False
    assert grid_triangulation(x, y, valid) is None


def _synthetic():
    """A 6×5 sweep-like Dataset: h, ν̄ a smooth image of (θ, ν0); unstable for ν0 < 0.3."""
    th = np.linspace(14, 17, 6)
    nu = np.linspace(0.1, 0.5, 5)
    T, N = np.meshgrid(th, nu, indexing="ij")
    h = 3 * (T - 13) / N**0.5
    nb = N * 0.5
    st = np.zeros(T.shape, np.int8)
    st[0, 0] = 1
    d = ("theta", "nu0")
    return xr.Dataset(
        {
            "h": (d, np.where(st == 0, h, np.nan)),
            "nu_mean": (d, np.where(st == 0, nb, np.nan)),
            "status": (d, st),
            "monotonic": (d, (N < 0.35).astype(np.int8)),
            "unstable": (d, (N < 0.3).astype(np.int8)),
            "regime": (d, np.where(N < 0.3, 2, 0).astype(np.int8)),
            "finite_k_disagrees": (d, np.zeros(T.shape, np.int8)),
        },
        coords={"theta": th, "nu0": nu},
        attrs={"roughness": 0.05},
    )


def test_plot_diagram_draws_unstable_fill():
    import matplotlib.pyplot as plt

    ds = _synthetic()
    fig = plot_diagram(ds)
    ax = fig.axes[0]
    # the grey fill covers exactly the mapped region ν0 < 0.3 (ν̄ < 0.15): its vertices
    # stay below the 0.5 level crossing between ν0 = 0.2 and 0.3 (ν̄ = 0.125)
    fills = [
        c for c in ax.collections if type(c).__name__ in ("QuadContourSet", "TriContourSet", "PathCollection")
    ]
    verts = np.concatenate(
        [
            p.vertices
            for c in ax.collections
            if hasattr(c, "get_paths")
            and c.get_facecolor().size
            and np.allclose(c.get_facecolor()[0][:3], 0.72)
            for p in c.get_paths()
        ]
    )
    assert fills
    assert verts[:, 1].max() <= 0.125 + 1e-9
    assert verts[:, 1].min() >= 0.05 - 1e-9
    plt.close(fig)


def test_cli_diagram_then_plot(tmp_path, capsys):
    out = tmp_path / "d.nc"
    rc = main(
        [
            "diagram",
            "--grid",
            "2x2",
            "--theta-range",
            "15",
            "16",
            "--nu0-range",
            "0.05",
            "0.06",
            "--metrics",
            "steady,kinematic",
            "--out",
            str(out),
            "-j",
            "1",
            "--no-progress",
            "--no-markers",
        ]
    )
    assert rc == 0
    assert out.exists()
    assert out.with_suffix(".png").stat().st_size > 10_000
    ds = load_sweep(out)
    assert ds.attrs["roughness"] == 0.05
    assert dict(ds.sizes) == {"theta": 2, "nu0": 2}
    png = tmp_path / "again.png"
    assert main(["plot", str(out), "--out", str(png)]) == 0
    assert png.stat().st_size > 10_000
    # same command: resumes from the final file (nothing recomputed)
    capsys.readouterr()
    assert (
        main(
            [
                "diagram",
                "--grid",
                "2x2",
                "--theta-range",
                "15",
                "16",
                "--nu0-range",
                "0.05",
                "0.06",
                "--metrics",
                "steady,kinematic",
                "--out",
                str(out),
                "-j",
                "1",
                "--no-progress",
                "--no-markers",
            ]
        )
        == 0
    )
    assert "0 / 2" in capsys.readouterr().err  # tasks computed / reused


def test_cli_errors_are_one_line(tmp_path, capsys):
    assert main(["plot", str(tmp_path / "missing.nc")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: file:")
    assert err.count("\n") == 1
    assert main(["diagram", "--grid", "0x3", "--out", str(tmp_path / "x.nc")]) == 2
    assert "grid" in capsys.readouterr().err
    assert (
        main(["diagram", "--grid", "2x2", "--nu0-range", "0.05", "0.9", "--out", str(tmp_path / "y.nc")]) == 2
    )
    assert "nu0" in capsys.readouterr().err


def test_plot_of_a_file_that_is_not_netcdf_is_one_line(tmp_path, capsys):
    """``chuteflow plot`` on a text file, a folder or an unrelated NetCDF file: a one-line
    error naming the file and why (no HDF5 traceback)."""
    text = tmp_path / "notes.nc"
    text.write_text("not a NetCDF file\n")
    for path, why in ((text, "is not a NetCDF-4 file"), (tmp_path, "is a directory")):
        assert main(["plot", str(path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: file: {path} ")
        assert why in err
        assert err.count("\n") == 1
        assert "Traceback" not in err
