"""Figures of the three-dimensional analysis (the question of the paper's §5.3).

- :func:`cross_section_fields`, :func:`cross_section_figure` — a transverse or oblique mode
  in the (z, y) cross-section over one spanwise wavelength λz = 2π/k_z (at x = 0):
  grey-scale contours of Re[ν̂(y) e^{ik_z z}] (a) and Re[T̂(y) e^{ik_z z}] (b), the velocity
  perturbation (ŵ, v̂) as arrows on (a) — vortex rolls would show as closed circulation
  cells, lateral clustering as flow converging on the density maxima.
- :func:`plane_figure` — Re α of the least-stable mode over the (k_x, k_z) plane, with
  where its maximum lies (longitudinal, transverse or oblique).
- :func:`winner_figure` — which instability wins where over the (h, ν̄) plane (sweep metric
  ``transverse``): stable / longitudinal only / transverse only / both.

Drawn on :class:`matplotlib.figure.Figure` objects (no pyplot state).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..spectral import ChebyshevGrid
from .stability import default_height, point_label

__all__ = ["cross_section_fields", "cross_section_figure", "plane_figure", "winner_figure", "WINNER_CLASSES"]

#: Classes of the "which instability wins" diagram (the sweep metric's ``winner`` codes).
WINNER_CLASSES = {0: "stable", 1: "longitudinal only", 2: "transverse only", 3: "both"}


def _figure(width, height):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _save(fig, path, dpi) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def cross_section_fields(mode, flow, *, y_top: float | None = None, nz: int = 121, ny: int = 141) -> dict:
    """Perturbation fields of a mode with k_z ≠ 0 in the (z, y) cross-section at x = 0.

    Parameters
    ----------
    mode : chuteflow.stability.Mode
        A three-dimensional mode (fields ``nu``, ``u``, ``v``, ``w``, ``T``; k_z ≠ 0).
    flow : SteadyFlow
        Its base state.
    y_top : float, optional
        Top of the y range (default :func:`chuteflow.figures.stability.default_height`).

    Returns
    -------
    dict
        ``z`` (z/λz), ``y`` (1-D), ``nu``, ``u``, ``v``, ``w``, ``T`` (2-D, (ny, nz)):
        Re[f̂(y) e^{ik_z z}] with max |ν̂| = 1 and ν̂ real and positive where |ν̂| is largest
        (density maximum at z = 0); ``lambda`` = 2π/|k_z|.
    """
    if not mode.kz:
        raise ValueError("cross_section_fields: needs a mode with kz != 0")
    g = ChebyshevGrid(mode.n, 0.0, flow.y_max)
    y_top = float(min(flow.y_max, y_top if y_top is not None else default_height(flow)))
    if not y_top > 0:
        raise ValueError(f"y_top = {y_top!r}: need a positive height")
    nu = np.asarray(mode.fields["nu"])
    j = int(np.argmax(np.abs(nu)))
    c = np.conj(nu[j]) / abs(nu[j]) ** 2
    z = np.linspace(0.0, 1.0, nz)
    y = np.linspace(0.0, y_top, ny)
    phase = np.exp(2j * math.pi * z * math.copysign(1.0, mode.kz))[None, :]
    out = {"z": z, "y": y, "lambda": 2 * math.pi / abs(mode.kz)}
    for f, v in mode.fields.items():
        out[f] = (g.interpolate(c * np.asarray(v), y)[:, None] * phase).real
    return out


def _contours(fig, ax, x, y, Z, label):
    zmax = float(np.abs(Z).max()) or 1.0
    cs = ax.contourf(x, y, Z, levels=np.linspace(-zmax, zmax, 16), cmap="gray")
    if Z.min() < 0 < Z.max():
        ax.contour(x, y, Z, levels=[0.0], colors="k", linewidths=0.6, linestyles="--")
    fig.colorbar(cs, ax=ax, shrink=0.9).set_label(label, fontsize=8)
    ax.set_xlabel(r"$z/\lambda_z$")
    ax.set_ylabel(r"$y$ [$\sigma$]")


def cross_section_figure(mode, flow, path, *, y_top: float | None = None, dpi: int = 130) -> Path:
    """Save the (z, y) cross-section of a mode with k_z ≠ 0 (module docstring)."""
    F = cross_section_fields(mode, flow, y_top=y_top)
    fig = _figure(6.5, 6.2)
    ax1, ax2 = fig.subplots(2, 1)
    _contours(fig, ax1, F["z"], F["y"], F["nu"], r"Re $\hat\nu\,e^{ik_z z}$")
    _contours(fig, ax2, F["z"], F["y"], F["T"], r"Re $\hat T\,e^{ik_z z}$")
    # arrows (ŵ/λz, v̂) in the plot's (z/λz, y) coordinates: true directions in this plot
    nzq, nyq = 17, 12
    zi = np.linspace(0, 1, nzq + 2)[1:-1]
    yi = np.linspace(F["y"][0], F["y"][-1], nyq + 2)[1:-1]
    iz = np.clip(np.searchsorted(F["z"], zi), 0, len(F["z"]) - 1)
    iy = np.clip(np.searchsorted(F["y"], yi), 0, len(F["y"]) - 1)
    W = F["w"][np.ix_(iy, iz)] / F["lambda"]
    V = F["v"][np.ix_(iy, iz)]
    size = np.hypot(W, V / (F["y"][-1] - F["y"][0])).max()
    if size > 0:
        ax1.quiver(
            F["z"][iz],
            F["y"][iy],
            W,
            V,
            angles="xy",
            scale_units="xy",
            scale=size * max(nzq, nyq) / 0.9,
            color="tab:red",
            width=0.004,
        )
    kx = math.sqrt(max(mode.k**2 - mode.kz**2, 0.0))
    label = point_label(flow.theta, flow.nu0, flow.model.roughness)
    ax1.set_title(
        f"(a) density, arrows (ŵ, v̂); {label}\n"
        f"$k_x$ = {kx:.3g}, $k_z$ = {mode.kz:.3g} (λz = {F['lambda']:.4g} σ, not to scale), "
        f"α = {mode.alpha.real:.4g}{mode.alpha.imag:+.3g}i",
        fontsize=8,
    )
    ax2.set_title("(b) granular temperature", fontsize=8)
    return _save(fig, path, dpi)


def plane_figure(ds, path, *, dpi: int = 130) -> Path:
    """Save Re α over (k_x, k_z) (:func:`chuteflow.stability.transverse.growth_plane`), the
    maximum marked."""
    fig = _figure(5.6, 4.4)
    ax = fig.subplots()
    a = np.asarray(ds.alpha_re.values, dtype=float).T  # (kz, kx)
    kx, kz = np.asarray(ds.kx.values), np.asarray(ds.kz.values)
    amax = float(np.nanmax(np.abs(a))) or 1.0
    from matplotlib.colors import SymLogNorm

    norm = SymLogNorm(linthresh=max(amax * 1e-3, 1e-12), vmin=-amax, vmax=amax)
    pm = ax.pcolormesh(kx, kz, a, cmap="RdBu_r", norm=norm, shading="nearest")
    if np.nanmin(a) < 0 < np.nanmax(a):
        ax.contour(kx, kz, a, levels=[0.0], colors="k", linewidths=0.8)
    fig.colorbar(pm, ax=ax).set_label(r"Re α [$(g/\sigma)^{1/2}$]", fontsize=8)
    ax.plot([ds.attrs["kx_max"]], [ds.attrs["kz_max"]], "k*", ms=10)
    ax.set_xlabel(r"$k_x$ [$\sigma^{-1}$]")
    ax.set_ylabel(r"$k_z$ [$\sigma^{-1}$]")
    ax.set_title(
        f"{point_label(ds.attrs['theta'], ds.attrs['nu0'], ds.attrs.get('roughness'))}: max Re α = "
        f"{ds.attrs['growth_max']:.3g} ({ds.attrs['direction']})",
        fontsize=8,
    )
    return _save(fig, path, dpi)


def winner_figure(ds, path, *, x: str = "h", y: str = "nu_mean", dpi: int = 130) -> Path:
    """Save the "which instability wins" diagram of a sweep with the ``transverse`` metric:
    each computed point coloured by ``winner`` (:data:`WINNER_CLASSES`) over (``x``, ``y``)
    (default the layer thickness h and mean density ν̄, the paper's figure 6 axes); points
    unstable both ways where the transverse instability grows faster are crossed."""
    from matplotlib.colors import ListedColormap

    fig = _figure(5.6, 4.4)
    ax = fig.subplots()
    X = np.asarray(ds[x].values, dtype=float).ravel()
    Y = np.asarray(ds[y].values, dtype=float).ravel()
    C = np.asarray(ds["winner"].values, dtype=float).ravel()
    ok = np.isfinite(X) & np.isfinite(Y) & np.isfinite(C)
    colors = ["#d9d9d9", "#3182bd", "#e6550d", "#756bb1"]
    cmap = ListedColormap(colors)
    ax.scatter(X[ok], Y[ok], c=C[ok], cmap=cmap, vmin=-0.5, vmax=3.5, s=18, marker="s")
    for code, name in WINNER_CLASSES.items():
        ax.scatter([], [], c=colors[code], marker="s", label=name)
    if "fastest" in ds:
        F = np.asarray(ds["fastest"].values, dtype=float).ravel()
        t = ok & (F == 2) & (C == 3)
        ax.scatter(X[t], Y[t], marker="x", c="k", s=14, label="both, transverse faster")
    ax.legend(fontsize=7, loc="best")
    ax.set_xlabel("h [σ]" if x == "h" else x)
    ax.set_ylabel("ν̄" if y == "nu_mean" else y)
    ax.set_title(f"which instability wins (φ = {ds.attrs.get('roughness', float('nan')):g})", fontsize=9)
    return _save(fig, path, dpi)
