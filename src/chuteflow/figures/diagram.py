"""Stability diagram in the (h, ν̄) plane from a sweep Dataset (paper figures 6, 12).

Every grid point (θ, ν0(0)) with a steady flow is mapped to (h, ν̄). The grid's own connectivity
gives a triangulation of the mapped plane (two triangles per grid cell whose corners all have a
flow), so fields defined on the grid are contoured exactly where the flows are, with no
Delaunay triangles bridging regions without flows:

- unstable regions (Re α2 > 0) grey: the 0.5 level of the 0/1 field ``unstable``;
- boundary of the non-monotonic region dashed (0.5 level of ``monotonic``);
- contour lines of θ thin, labelled in degrees;
- edge of the swept domain (where flows exist) thin solid;
- h < 1 hatched (paper: "not examined": decay length below one diameter);
- regimes A, B, C labelled, the paper's points P1–P5 / Q1–Q3 marked (filled: unstable);
- points where the sampled dispersion relation disagrees with the long-wave criterion: red ×.

A second panel (optional) shows the same classification on the (θ, ν0) grid, with the points
where no steady flow was found or a solver did not converge.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["grid_triangulation", "plot_diagram", "refined_triangulation", "save_diagram"]

_REGIME_COLOURS = {0: "white", 1: "0.55", 2: "0.7", 3: "0.4"}


def grid_triangulation(x, y, valid):
    """Triangulation of points on a structured grid, from the grid's connectivity.

    Parameters
    ----------
    x, y : ndarray (ni, nj)
        Coordinates of the grid points in the target plane.
    valid : ndarray of bool (ni, nj)
        Points that exist (a steady flow was found).

    Returns
    -------
    matplotlib.tri.Triangulation or None
        Two triangles per cell with four valid corners, one per cell with three. Degenerate
        (zero-area) triangles are dropped. None if there are no triangles.
    """
    import matplotlib.tri as mtri

    ni, nj = valid.shape
    idx = np.arange(ni * nj).reshape(ni, nj)
    tris = []
    for i in range(ni - 1):
        for j in range(nj - 1):
            c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            ok = [bool(valid[p]) for p in c]
            if all(ok):
                tris.append([idx[c[0]], idx[c[1]], idx[c[2]]])
                tris.append([idx[c[0]], idx[c[2]], idx[c[3]]])
            elif sum(ok) == 3:
                tris.append([idx[p] for p, o in zip(c, ok) if o])
    if not tris:
        return None
    tri = np.array(tris)
    xf, yf = np.nan_to_num(x.ravel()), np.nan_to_num(y.ravel())
    area = 0.5 * (
        (xf[tri[:, 1]] - xf[tri[:, 0]]) * (yf[tri[:, 2]] - yf[tri[:, 0]])
        - (xf[tri[:, 2]] - xf[tri[:, 0]]) * (yf[tri[:, 1]] - yf[tri[:, 0]])
    )
    tri = tri[np.abs(area) > 1e-14 * (np.ptp(xf) * np.ptp(yf) + 1e-300)]
    if len(tri) == 0:
        return None
    return mtri.Triangulation(xf, yf, tri)


def refined_triangulation(X, Y, fields, valid, n: int = 4):
    """A triangulation of a structured grid's image (X, Y) with each cell subdivided.

    Each cell with four valid corners becomes an ``n`` × ``n`` lattice of sub-cells in index
    space, mapped to the plane by the bilinear interpolation of X and Y; ``fields`` are
    interpolated bilinearly too. Cells with three valid corners stay one triangle. Contours
    over it follow the bilinear interpolant of the grid data instead of zigzagging along
    the diagonals of the cells, which are long and thin where the (θ, ν0(0)) → (h, ν̄) map
    is stretched.

    Parameters
    ----------
    X, Y : ndarray (ni, nj)
        Coordinates of the grid points in the target plane.
    fields : sequence of ndarray (ni, nj)
        Data on the grid (NaN allowed where ``valid``: triangles touching it are masked).
    valid : ndarray of bool (ni, nj)
        Points that exist.
    n : int
        Subdivisions per cell side.

    Returns
    -------
    (matplotlib.tri.Triangulation, list of ndarray) or (None, [])
        The triangulation and each field at its points (NaN replaced by 0, masked).
    """
    import matplotlib.tri as mtri

    valid = np.asarray(valid, dtype=bool)
    quad = valid[:-1, :-1] & valid[1:, :-1] & valid[:-1, 1:] & valid[1:, 1:]
    ci, cj = np.nonzero(quad)
    t = np.arange(n + 1) / n
    gi, gj = np.meshgrid(t, t, indexing="ij")
    fi, fj = gi.ravel(), gj.ravel()

    def bilinear(F):
        c00, c01 = F[ci, cj][:, None], F[ci, cj + 1][:, None]
        c10, c11 = F[ci + 1, cj][:, None], F[ci + 1, cj + 1][:, None]
        return ((1 - fi) * ((1 - fj) * c00 + fj * c01) + fi * ((1 - fj) * c10 + fj * c11)).ravel()

    xs, ys = [bilinear(X)], [bilinear(Y)]
    zs = [[bilinear(np.asarray(F, dtype=float))] for F in fields]
    loc = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b_, c, d = loc[:-1, :-1].ravel(), loc[1:, :-1].ravel(), loc[1:, 1:].ravel(), loc[:-1, 1:].ravel()
    local = np.concatenate([np.c_[a, b_, c], np.c_[a, c, d]])
    tris = [(np.arange(len(ci))[:, None, None] * (n + 1) ** 2 + local[None]).reshape(-1, 3)]
    # cells with three valid corners: one triangle on the original points
    base = len(ci) * (n + 1) ** 2
    ni, nj = valid.shape
    xs.append(np.asarray(X, dtype=float).ravel())
    ys.append(np.asarray(Y, dtype=float).ravel())
    for k, F in enumerate(fields):
        zs[k].append(np.asarray(F, dtype=float).ravel())
    idx = np.arange(ni * nj).reshape(ni, nj) + base
    corners = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1)
    ok = np.stack([valid[:-1, :-1], valid[1:, :-1], valid[1:, 1:], valid[:-1, 1:]], axis=-1)
    three = ok.sum(axis=-1) == 3
    if three.any():
        cs, oks = corners[three], ok[three]
        tris.append(np.array([c[o] for c, o in zip(cs, oks)]))
    tri_arr = np.concatenate(tris) if tris else np.zeros((0, 3), dtype=int)
    if len(tri_arr) == 0:
        return None, []
    x, y = np.concatenate(xs), np.concatenate(ys)
    xf, yf = np.nan_to_num(x), np.nan_to_num(y)
    area = 0.5 * (
        (xf[tri_arr[:, 1]] - xf[tri_arr[:, 0]]) * (yf[tri_arr[:, 2]] - yf[tri_arr[:, 0]])
        - (xf[tri_arr[:, 2]] - xf[tri_arr[:, 0]]) * (yf[tri_arr[:, 1]] - yf[tri_arr[:, 0]])
    )
    tri_arr = tri_arr[np.abs(area) > 1e-14 * (np.ptp(xf) * np.ptp(yf) + 1e-300)]
    if len(tri_arr) == 0:
        return None, []
    z_out = [np.concatenate(z) for z in zs]
    tri = mtri.Triangulation(xf, yf, tri_arr)
    bad = np.zeros(len(tri_arr), dtype=bool)
    for z in z_out:
        bad |= np.isnan(z)[tri_arr].any(axis=1)
    tri.set_mask(bad)
    return tri, [np.nan_to_num(z) for z in z_out]


def _unstable_field(ds):
    """A continuous field whose sign is that of ``unstable`` (flattened; NaN: unknown).

    The signed ``log10(1 + |Re α2|)`` where ``alpha2_re`` is known and agrees with the
    flag (Re α2 spans 10–10⁴ over a diagram; compressed so that the zero level, linearly
    interpolated between grid points of opposite sign, falls inside the cell rather than
    on the corner of smaller magnitude), else ±1/2 from the flag: the filled region's
    edge then runs through the cells instead of along a staircase of grid cells.
    """
    flag = ds["unstable"].values.astype(float)
    flag = np.where(flag < 0, np.nan, flag)
    u = flag - 0.5
    if "alpha2_re" in ds:
        a = ds["alpha2_re"].values.astype(float)
        s = np.sign(a) * np.log10(1.0 + np.abs(a))
        use = np.isfinite(s) & np.isfinite(flag) & ((s > 0) == (flag == 1)) & (s != 0)
        u = np.where(use, s, u)
    return u.ravel()


def _boundary_segments(tri):
    """Edges used by exactly one triangle: the outline of the triangulated domain."""
    edges = np.sort(
        np.concatenate([tri.triangles[:, [0, 1]], tri.triangles[:, [1, 2]], tri.triangles[:, [2, 0]]]), axis=1
    )
    uniq, counts = np.unique(edges, axis=0, return_counts=True)
    b = uniq[counts == 1]
    return np.stack([np.c_[tri.x[b[:, 0]], tri.y[b[:, 0]]], np.c_[tri.x[b[:, 1]], tri.y[b[:, 1]]]], axis=1)


def _label_position(x, y, sel, xlim, ylim):
    """A grid point of the region ``sel`` near its median, inside the axes."""
    xs, ys = x[sel], y[sel]
    inside = (xs > xlim[0]) & (xs < xlim[1]) & (ys > ylim[0]) & (ys < ylim[1])
    if not inside.any():
        return None
    xs, ys = xs[inside], ys[inside]
    sx, sy = xlim[1] - xlim[0], ylim[1] - ylim[0]
    mx, my = np.median(xs), np.median(ys)
    k = int(np.argmin(((xs - mx) / sx) ** 2 + ((ys - my) / sy) ** 2))
    return xs[k], ys[k]


def plot_diagram(
    ds,
    *,
    ax=None,
    grid_panel: bool = True,
    h_max: float | None = None,
    nu_max: float | None = None,
    theta_step: float | None = None,
    title: str | None = None,
):
    """Draw the stability diagram of a sweep Dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        From :func:`chuteflow.sweep.run_sweep` or :func:`chuteflow.sweep.load_sweep`.
    ax : matplotlib Axes, optional
        Draw the (h, ν̄) diagram here (no grid panel).
    grid_panel : bool
        Add a second panel with the classification on the (θ, ν0) grid.
    h_max, nu_max : float, optional
        Axis limits (default: the extent of the flows, h at most 60).
    theta_step : float, optional
        Spacing of the θ contour lines in degrees (default: about eight lines).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if ax is None:
        if grid_panel:
            fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12.5, 5.2), gridspec_kw={"width_ratios": [1.35, 1]})
        else:
            fig, ax = plt.subplots(figsize=(7.2, 5.4))
            ax2 = None
    else:
        fig, ax2 = ax.figure, None
    th = ds["theta"].values
    T = np.broadcast_to(th[:, None], ds["h"].shape)
    h = ds["h"].values
    nb = ds["nu_mean"].values
    ok = (ds["status"].values == 0) & np.isfinite(h) & np.isfinite(nb)
    tri = grid_triangulation(h, nb, ok)
    handles: list[Artist] = []
    if ok.any():
        hx = float(np.nanmax(h[ok]))
        xlim = (0.0, h_max if h_max is not None else min(60.0, 1.03 * hx))
        ylim = (0.0, nu_max if nu_max is not None else 1.05 * float(np.nanmax(nb[ok])))
    else:
        xlim, ylim = (0.0, 1.0), (0.0, 1.0)
    have_stab = "unstable" in ds
    if tri is not None:
        if have_stab:
            u = _unstable_field(ds).reshape(h.shape)
            ftri, (fu,) = refined_triangulation(h, nb, [u], ok)
            if ftri is not None:
                ax.tricontourf(ftri, fu, levels=[0.0, np.inf], colors=["0.72"])
            handles.append(Patch(facecolor="0.72", label="unstable (Re α₂ > 0)"))
        if "monotonic" in ds:
            mono = ds["monotonic"].values.astype(float).ravel()
            if (mono[ok.ravel()] == 0).any() and (mono[ok.ravel()] == 1).any():
                ax.tricontour(tri, mono, levels=[0.5], colors="k", linestyles="--", linewidths=1.3)
                handles.append(Line2D([], [], color="k", ls="--", label="monotonic / non-monotonic ν₀(y)"))
        tf = T.ravel().astype(float)
        step = theta_step or _nice_step(np.ptp(th) / 8 if len(th) > 1 else 1.0)
        lev = np.arange(np.ceil(th.min() / step) * step, th.max() + 1e-9, step)
        if len(lev):
            cs = ax.tricontour(tri, tf, levels=lev, colors="0.35", linewidths=0.6)
            ax.clabel(cs, fmt=lambda v: f"{v:g}°", fontsize=7, inline=True)
            handles.append(Line2D([], [], color="0.35", lw=0.6, label="θ contours"))
        seg = _boundary_segments(tri)
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(seg, colors="0.25", linewidths=0.8))
        handles.append(Line2D([], [], color="0.25", lw=0.8, label="edge of swept flows"))
    ax.axvspan(0.0, 1.0, facecolor="none", edgecolor="0.45", hatch="....", lw=0)
    handles.append(Patch(facecolor="none", edgecolor="0.45", hatch="....", label="h < 1: not examined"))
    if "regime" in ds:
        reg = ds["regime"].values
        for name, code in (("A", 1), ("B", 2), ("C", 3)):
            pos = _label_position(h, nb, (reg == code) & ok, xlim, ylim)
            if pos is not None:
                ax.text(
                    *pos,
                    name,
                    fontsize=17,
                    fontweight="bold",
                    ha="center",
                    va="center",
                    color="k",
                    bbox=dict(boxstyle="circle,pad=0.15", fc="white", ec="none", alpha=0.65),
                )
    if "finite_k_disagrees" in ds:
        bad = (ds["finite_k_disagrees"].values == 1) & ok
        if bad.any():
            ax.plot(h[bad], nb[bad], "x", color="crimson", ms=7, mew=1.6)
            handles.append(
                Line2D([], [], marker="x", color="crimson", ls="", label="dispersion sample disagrees")
            )
    if "spatial_verdict" in ds:
        handles += _spatial_marks(ax, h, nb, np.where(ok, ds["spatial_verdict"].values, -1))
    if "marker" in ds.dims:
        mh, mn = ds["marker_h"].values, ds["marker_nu_mean"].values
        mu = ds["marker_unstable"].values if "marker_unstable" in ds else np.full(len(mh), -1)
        for name, x, y, uu in zip(ds["marker"].values, mh, mn, mu):
            if not (np.isfinite(x) and np.isfinite(y)):
                continue
            ax.plot(x, y, "o", ms=6, mec="k", mfc="k" if uu == 1 else "white", zorder=5)
            ax.annotate(str(name), (x, y), xytext=(4, 4), textcoords="offset points", fontsize=9, zorder=6)
        handles.append(Line2D([], [], marker="o", color="k", ls="", mfc="k", label="marked point, unstable"))
        handles.append(
            Line2D([], [], marker="o", color="k", ls="", mfc="white", label="marked point, stable")
        )
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_xlabel("thickness h (particle diameters)")
    ax.set_ylabel("mean density ν̄")
    phi = ds.attrs.get("roughness", float("nan"))
    ax.set_title(
        title or f"Stability diagram, φ = {phi:g}" + ("" if have_stab else " (steady quantities only)")
    )
    ax.legend(handles=handles, fontsize=7, loc="upper right", framealpha=0.85)
    if ax2 is not None:
        _grid_panel(ax2, ds)
    fig.tight_layout()
    return fig


def _grid_panel(ax, ds):
    """Classification and status on the (θ, ν0) grid."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    th, nu = ds["theta"].values, ds["nu0"].values
    st = ds["status"].values
    # codes: 0 no flow, 1 not converged/error, 2 stable, 3 A, 4 B, 5 C, 6 ok (unclassified),
    # 7 not attempted (beyond the continuation from the row's flows)
    code = np.full(st.shape, 6, dtype=int)
    if "regime" in ds:
        reg = ds["regime"].values
        code = np.where(reg == 0, 2, np.where(reg == 1, 3, np.where(reg == 2, 4, np.where(reg == 3, 5, 6))))
    skipped = (
        np.char.find(ds["message"].values.astype(str), "not attempted") >= 0
        if "message" in ds
        else np.zeros(st.shape, bool)
    )
    code = np.where(st == 1, 0, np.where(skipped, 7, np.where(st >= 2, 1, code)))
    colours = ["white", "#e8a0a0", "#f4f4f4", "#9ecae1", "#fdae6b", "#a1d99b", "#dddddd", "#f6e0e0"]
    names = [
        "no steady flow",
        "not converged / error",
        "stable",
        "A",
        "B",
        "C",
        "steady only",
        "not attempted",
    ]
    ax.pcolormesh(
        _edges(nu),
        _edges(th),
        code,
        cmap=ListedColormap(colours),
        vmin=-0.5,
        vmax=7.5,
        shading="flat",
        edgecolors="0.85",
        linewidth=0.2,
    )
    if "monotonic" in ds and len(th) > 1 and len(nu) > 1:
        mono = np.where(
            (st == 0) & (ds["monotonic"].values >= 0), ds["monotonic"].values.astype(float), np.nan
        )
        if (mono == 0).any() and (mono == 1).any():
            ax.contour(nu, th, mono, levels=[0.5], colors="k", linestyles="--", linewidths=1)
    if "finite_k_disagrees" in ds:
        bad = ds["finite_k_disagrees"].values == 1
        if bad.any():
            Ti, Nj = np.meshgrid(th, nu, indexing="ij")
            ax.plot(Nj[bad], Ti[bad], "x", color="crimson", ms=6)
    if "spatial_verdict" in ds:
        Ti, Nj = np.meshgrid(th, nu, indexing="ij")
        _spatial_marks(ax, Nj, Ti, np.where(st == 0, ds["spatial_verdict"].values, -1))
    if "marker" in ds.dims:
        for name, t, n in zip(ds["marker"].values, ds["marker_theta"].values, ds["marker_nu0"].values):
            ax.plot(n, t, "ko", ms=4)
            ax.annotate(str(name), (n, t), xytext=(3, 3), textcoords="offset points", fontsize=8)
    present = sorted(set(np.unique(code)))
    ax.legend(
        handles=[Patch(facecolor=colours[c], edgecolor="0.6", label=names[c]) for c in present],
        fontsize=7,
        loc="lower right",
        framealpha=0.9,
    )
    ax.set_xlabel("floor density ν₀(0)")
    ax.set_ylabel("inclination θ (degrees)")
    ax.set_title("classification on the (θ, ν₀(0)) grid")


#: How the verdicts of the sweep metric ``spatial`` (chuteflow.sweep.spatial.VERDICT_CODES) are
#: marked: code → (marker, colour, label). Stable points (0) and unclassified ones (1) are not.
SPATIAL_MARKS = {
    2: (">", "#08519c", "convective (swept down the slope)"),
    3: ("*", "#cb181d", "absolute (grows in place)"),
    4: ("$?$", "0.3", "convective/absolute undetermined"),
}


def _spatial_marks(ax, x, y, verdict) -> list:
    """Mark the points of each spatial verdict (metric ``spatial``); legend handles of those present."""
    from matplotlib.lines import Line2D

    handles = []
    x, y, v = np.asarray(x), np.asarray(y), np.asarray(verdict)
    for code, (m, c, label) in SPATIAL_MARKS.items():
        sel = v == code
        if sel.any():
            ax.plot(x[sel], y[sel], marker=m, color=c, ms=5, ls="", zorder=4)
            handles.append(Line2D([], [], marker=m, color=c, ls="", label=label))
    return handles


def _edges(c):
    c = np.asarray(c, dtype=float)
    if len(c) == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


def _nice_step(x):
    x = max(float(x), 1e-9)
    e = 10 ** np.floor(np.log10(x))
    for m in (1, 2, 2.5, 5, 10):
        if m * e >= x:
            return m * e
    return 10 * e


def save_diagram(ds, path, *, dpi: int = 150, **kw) -> Path:
    """Draw with :func:`plot_diagram` and save to ``path`` (format from the suffix)."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = plot_diagram(ds, **kw)
    try:
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return path
