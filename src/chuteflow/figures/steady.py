"""Steady-flow figures of §3.2: the (h, ν̄) map, Q0(ρ̄0), and the profiles ν0, u0, T0.

- :func:`plot_h_nubar` — figures 2(a) / 4(a): contour lines of θ in
  the (h, ν̄) plane (each θ row of a :func:`~chuteflow.steady.steady_map` is one line), the
  non-monotonic region shaded grey.
- :func:`plot_flux_density` — figures 2(b) / 4(b): Q0 against ρ̄0 for
  families at fixed θ, with the minimum marked where there is one.
- :func:`plot_profiles` — figures 3 / 5: ν0(y), u0(y), T0(y).
- :func:`steady_phase_figure`, :func:`profiles_figure` — the paper's panel layouts, saved.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .diagram import grid_triangulation

__all__ = ["plot_h_nubar", "plot_flux_density", "plot_profiles", "steady_phase_figure", "profiles_figure"]

_STYLES = ("-", "--", (0, (5, 2)), ":", "-.", (0, (1, 1)))


def plot_h_nubar(ds, ax=None, *, label_every: int | None = None, h_max: float | None = None):
    """Contour lines of θ in the (h, ν̄) plane with the non-monotonic region in grey.

    Parameters
    ----------
    ds : xarray.Dataset
        A map from :func:`chuteflow.steady.steady_map` (dims theta, nu0).
    ax : matplotlib Axes, optional
    label_every : int, optional
        Label every k-th drawn θ line (default 2). At most ~14 rows are drawn as lines
        (every k-th row of a finer map); the grey region uses every row.
    h_max : float, optional
        Upper limit of the h axis (default 50, as far as the paper's figures go).
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 4))
    h, nb = ds.h.values, ds.nu_mean.values
    valid = np.isfinite(h) & np.isfinite(nb)
    thetas = ds.theta.values
    if valid.any():
        tri = grid_triangulation(np.where(valid, h, 0.0), np.where(valid, nb, 0.0), valid)
        if tri is not None:
            nonmono = np.where(valid, 1.0 - np.nan_to_num(ds.monotonic.values, nan=1.0), 0.0)
            ax.tricontourf(tri, nonmono.ravel(), levels=[0.5, 1.5], colors=["0.8"])
    # at most ~14 lines (a fine map is shaded from every row but drawn every k-th row)
    stride = max(1, -(-len(thetas) // 14))
    k = label_every or 2
    drawn = 0
    for i, th in enumerate(thetas):
        ok = valid[i]
        if ok.sum() < 2 or i % stride:
            continue
        ax.plot(h[i, ok], nb[i, ok], "k-", lw=0.7)
        drawn += 1
        if (drawn - 1) % k == 0:
            j = np.nonzero(ok)[0][-1]
            ax.annotate(
                f"{th:g}°", (h[i, j], nb[i, j]), fontsize=7, xytext=(2, 2), textcoords="offset points"
            )
    ax.set_xlim(0, h_max or 50.0)
    ax.set_ylim(0, min(0.6, float(np.nanmax(nb)) * 1.05) if valid.any() else 0.6)
    ax.set_xlabel("thickness h (σ)")
    ax.set_ylabel("mean density ν̄")
    ax.set_title(
        f"φ = {ds.attrs.get('roughness', '?')}: contour lines of θ; grey: non-monotonic ν0", fontsize=8
    )
    return ax


def plot_flux_density(families, ax=None, *, minima: dict | None = None):
    """Q0 against ρ̄0 for families at fixed θ.

    Parameters
    ----------
    families : sequence of xarray.Dataset
        From :func:`chuteflow.steady.steady_family`; the line style cycles solid, dashed, ….
    minima : dict, optional
        θ → :class:`~chuteflow.steady.FluxMinimum` of :func:`chuteflow.steady.flux_minimum`
        (or None), marked with a dot.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 4))
    for k, fam in enumerate(families):
        ok = fam.status.values == "ok"
        th = float(fam.attrs["theta"])
        ax.plot(
            fam.rho_bar.values[ok],
            fam.Q.values[ok],
            color="k",
            linestyle=_STYLES[k % len(_STYLES)],
            label=f"θ = {th:g}°",
        )
        mn = (minima or {}).get(th)
        if mn:
            ax.plot([mn.rho_bar], [mn.Q], "ko", ms=4)
    ax.set_xlabel("one-dimensional density ρ̄0 (σ)")
    ax.set_ylabel("flux Q0")
    ax.legend(fontsize=8, frameon=False)
    return ax


def plot_profiles(flows, axes=None, *, y_max: float | None = None):
    """ν0(y), u0(y), T0(y) of steady flows, one line style per flow (figures 3, 5).

    Profiles are drawn from the spectral interpolant on a fine grid.
    """
    import matplotlib.pyplot as plt

    if axes is None:
        _, axes = plt.subplots(1, 3, figsize=(10, 3.4))
    flows = [f for f in flows if f is not None]
    top = y_max or max(1.2 * f.h for f in flows)
    for k, f in enumerate(flows):
        y = np.linspace(0.0, min(top, f.y_max), 400)
        pr = f.profiles(y)
        ls = _STYLES[k % len(_STYLES)]
        lab = f"ν0(0) = {f.nu0:g}"
        axes[0].plot(pr["nu"], y, color="k", linestyle=ls, label=lab)
        axes[1].plot(pr["u"], y, color="k", linestyle=ls, label=lab)
        axes[2].plot(pr["T"], y, color="k", linestyle=ls, label=lab)
    for ax, name in zip(axes, ("density ν0", "velocity u0", "temperature T0")):
        ax.set_xlabel(name)
        ax.set_ylim(0, top)
    axes[0].set_ylabel("height y (σ)")
    axes[0].legend(fontsize=7, frameon=False)
    return axes


def steady_phase_figure(map_ds, families, path: str | Path, *, minima=None, title=""):
    """Two panels as figures 2/4: (a) θ contours in (h, ν̄), (b) Q0(ρ̄0)."""
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    plot_h_nubar(map_ds, a)
    plot_flux_density(families, b, minima=minima)
    a.set_title("(a) " + a.get_title(), fontsize=8)
    b.set_title("(b) flux vs one-dimensional density", fontsize=8)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def profiles_figure(flows, path: str | Path, *, title: str = "", y_max=None):
    """Three panels as figures 3/5: (a) ν0, (b) u0, (c) T0 against y."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(10, 3.6))
    plot_profiles(flows, axes, y_max=y_max)
    for ax, lab in zip(axes, "abc"):
        ax.set_title(f"({lab})", fontsize=8)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
