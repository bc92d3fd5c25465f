"""Figures of the linear stability analysis (paper §4.2) and the eigenfunction diagnostics.

- :func:`dispersion_figure` — figures 7, 9, 13: Re α(k) and Im α(k) of
  the least-stable (α(0) = 0) branch, one column per steady flow, critical k_c marked.
- :func:`magnification_figure` — figure 8: the branch near k = 0 with the long-wave
  expansion overlaid: Re α against α2 k², Im α against the slope −dQ0/dρ̄0, and Re α / k²
  against k, which shows how narrow the k² regime is (docs/errata.md, numerical notes).
- :func:`eigenfunction_figure` — figures 10, 11, 14: over one
  wavelength λ = 2π/k, grey-scale contours of Re[ν̂(y) e^{ikx}] (a) and Re[T̂(y) e^{ikx}] (b),
  the velocity perturbation (Re û e^{ikx}, Re v̂ e^{ikx}) as arrows on (a), and optionally a
  magnified part of (a) as panel (c).
- :func:`eigenfunction_fields`, :func:`eigenfunction_diagnostics` — the fields on a plotting
  grid, and the numbers behind the paper's qualitative statements about them.

Plots are drawn on :class:`matplotlib.figure.Figure` objects (no pyplot state), so they can
be made from worker threads and never leak figures.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..spectral import MappedChebyshevGrid
from ..stability.operator import equation_terms, stability_grid

__all__ = [
    "dispersion_figure",
    "magnification_figure",
    "eigenfunction_figure",
    "eigenfunction_fields",
    "default_height",
    "eigenfunction_diagnostics",
    "point_label",
]

#: Units of α (time scale sqrt(σ/g)) and k (1/σ), σ the grain diameter.
_ALPHA_UNIT = r"$(g/\sigma)^{1/2}$"
_K_UNIT = r"$\sigma^{-1}$"


def point_label(theta: float, nu0: float, roughness: float | None = None) -> str:
    """'θ = 16°, ν0(0) = 0.05, φ = 0.05' (φ left out when None)."""
    s = f"θ = {theta:g}°, ν0(0) = {nu0:g}"
    return s if roughness is None else s + f", φ = {roughness:g}"


def _new_figure(width, height):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _save(fig, path, dpi) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def _interp(grid, f, y):
    """Spectral interpolation of complex nodal values."""
    f = np.asarray(f)
    return grid.interpolate(f.real, y) + 1j * grid.interpolate(f.imag, y)


# -- dispersion relations -------------------------------------------------------------------
def _crossing_marks(ds, k_c):
    """k_c to mark: the given value(s), else the dataset's ``k_c`` attribute, else none."""
    if k_c is None:
        k_c = ds.attrs.get("k_c")
    if k_c is None:
        return []
    vals = np.atleast_1d(np.asarray(k_c, dtype=float))
    return [float(v) for v in vals if np.isfinite(v)]


def dispersion_figure(
    panels, path=None, *, title: str | None = None, dpi: int = 150, k_max: float | None = None
):
    """Dispersion relations α(k) of the least-stable branch (figures 7, 9, 13).

    Parameters
    ----------
    panels : sequence of (label, dataset) or (label, dataset, k_c)
        ``dataset``: output of :func:`chuteflow.stability.dispersion` (variables alpha_re,
        alpha_im, physical over k; attributes theta, nu0, roughness). ``label`` names the
        point (e.g. "P1"); ``k_c``, optional, the critical wavenumber(s) to mark (default:
        the dataset's ``k_c`` attribute, if any).
    path : path, optional
        Where to save (PNG); without it the figure is returned unsaved.
    title : str, optional
        Figure title (default: none beyond the panel titles).
    k_max : float, optional
        Upper limit of the k axes (default: each dataset's largest k).

    Returns
    -------
    pathlib.Path or matplotlib.figure.Figure
        The saved file, or the figure when ``path`` is None.

    Points that failed the drift or tail test (``physical`` false, only present when the
    dispersion relation was computed with ``strict=False``) are drawn as red crosses.
    """
    panels = [tuple(p) for p in panels]
    if not panels:
        raise ValueError("panels: need at least one (label, dataset) pair")
    ncol = len(panels)
    fig = _new_figure(3.6 * ncol + 0.4, 5.6)
    axes = fig.subplots(2, ncol, squeeze=False, sharex="col")
    for j, p in enumerate(panels):
        label, ds = p[0], p[1]
        marks = _crossing_marks(ds, p[2] if len(p) > 2 else None)
        k = np.asarray(ds["k"].values, dtype=float)
        order = np.argsort(k)
        k = k[order]
        re = np.asarray(ds["alpha_re"].values)[order]
        im = np.asarray(ds["alpha_im"].values)[order]
        phys = (
            np.asarray(ds["physical"].values, dtype=bool)[order]
            if "physical" in ds
            else np.ones(len(k), dtype=bool)
        )
        a = ds.attrs
        head = point_label(a.get("theta", math.nan), a.get("nu0", math.nan), a.get("roughness"))
        for i, (vals, name) in enumerate(((re, r"Re $\alpha$"), (im, r"Im $\alpha$"))):
            ax = axes[i, j]
            ax.plot(k, vals, "k-", lw=1.2)
            ax.plot(k[phys], vals[phys], "k.", ms=3.5)
            bad = ~phys & np.isfinite(vals)
            if bad.any():
                ax.plot(k[bad], vals[bad], "rx", ms=5, label="not converged (drift or tail > 1e-7)")
                ax.legend(fontsize=7, loc="best")
            if not np.all(np.isfinite(vals)):
                k_lost = float(k[~np.isfinite(vals)].min())
                ax.axvspan(k_lost, k.max(), color="mistyrose", zorder=0)
                ax.annotate(
                    f"branch lost from k = {k_lost:.3g}",
                    (0.98, 0.04),
                    xycoords="axes fraction",
                    ha="right",
                    fontsize=7,
                    color="red",
                )
            ax.axhline(0.0, color="0.5", lw=0.6)
            for kc in marks:
                ax.axvline(kc, color="0.3", ls=":", lw=1.0)
            ax.set_ylabel(f"{name} [{_ALPHA_UNIT}]")
            ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 3))
            ax.set_xlim(0.0, k_max or float(k.max()))
        if marks:
            axes[0, j].annotate(
                f"$k_c$ = {marks[0]:.4g}",
                (marks[0], 0.06),
                xycoords=axes[0, j].get_xaxis_transform(),
                xytext=(4, 0),
                textcoords="offset points",
                fontsize=8,
            )
        axes[0, j].set_title(f"({chr(97 + j)}) {label}: {head}", fontsize=9)
        axes[1, j].set_xlabel(f"wavenumber $k$ [{_K_UNIT}]")
        axes[1, j].ticklabel_format(axis="x", style="sci", scilimits=(-2, 3))
    if title:
        fig.suptitle(title, fontsize=10)
    return _save(fig, path, dpi) if path is not None else fig


def magnification_figure(
    ds,
    path=None,
    *,
    alpha2: complex,
    dQ_drho: float,
    alpha2_uncertainty: float | None = None,
    k_mag: float | None = None,
    label: str = "",
    title: str | None = None,
    dpi: int = 150,
):
    """The least-stable branch near k = 0 with the long-wave expansion (figure 8).

    Parameters
    ----------
    ds : xarray.Dataset
        Dispersion relation (:func:`chuteflow.stability.dispersion`) sampled at small k, both
        on a uniform grid up to ``k_mag`` (panels a, b) and geometrically (panel c).
    alpha2 : complex
        Long-wave coefficient of α = α1 k + α2 k² + … (:func:`chuteflow.longwave.longwave`).
    dQ_drho : float
        dQ0/dρ̄0 along the steady family (eq. B 6); Im α / k → −dQ0/dρ̄0 (Appendix B).
    alpha2_uncertainty : float, optional
        Relative uncertainty of Re α2 (its convergence estimate), drawn as a band in (c).
    k_mag : float, optional
        Upper k of the linear panels (default: a fifth of the largest k of ``ds``).
    """
    k = np.asarray(ds["k"].values, dtype=float)
    order = np.argsort(k)
    k = k[order]
    re = np.asarray(ds["alpha_re"].values)[order]
    im = np.asarray(ds["alpha_im"].values)[order]
    k_mag = float(k_mag or 0.2 * k.max())
    a = ds.attrs
    head = (
        f"{label + ': ' if label else ''}"
        f"{point_label(a.get('theta', math.nan), a.get('nu0', math.nan), a.get('roughness'))}"
    )
    fig = _new_figure(12.0, 3.9)
    ax1, ax2, ax3 = fig.subplots(1, 3)
    lin = k <= k_mag * (1 + 1e-12)
    kk = np.linspace(0.0, k_mag, 200)
    ax1.plot(k[lin], re[lin], "ko-", ms=3, lw=1.0, label=r"Re $\alpha$ (eigenvalue)")
    ax1.plot(
        kk,
        alpha2.real * kk**2,
        "k--",
        lw=1.0,
        label=rf"Re $\alpha_2\,k^2$, Re $\alpha_2$ = {alpha2.real:.4g}",
    )
    ax1.set_ylabel(rf"Re $\alpha$ [{_ALPHA_UNIT}]")
    ax1.set_title("(a) growth rate", fontsize=9)
    ax2.plot(k[lin], im[lin], "ko-", ms=3, lw=1.0, label=r"Im $\alpha$ (eigenvalue)")
    ax2.plot(
        kk,
        -dQ_drho * kk,
        "k--",
        lw=1.0,
        label=rf"$-(dQ_0/d\bar\rho_0)\,k$, $dQ_0/d\bar\rho_0$ = {dQ_drho:.5g}",
    )
    ax2.set_ylabel(rf"Im $\alpha$ [{_ALPHA_UNIT}]")
    ax2.set_title("(b) frequency", fontsize=9)
    for ax in (ax1, ax2):
        ax.set_xlim(0.0, k_mag)
        ax.set_xlabel(f"$k$ [{_K_UNIT}]")
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.ticklabel_format(style="sci", scilimits=(-2, 3))
        ax.legend(fontsize=7, loc="best")
    pos = k > 0
    ax3.semilogx(k[pos], re[pos] / k[pos] ** 2, "ko-", ms=3, lw=1.0, label=r"Re $\alpha / k^2$ (eigenvalues)")
    ax3.axhline(alpha2.real, color="k", ls="--", lw=1.0, label=r"Re $\alpha_2$ (long-wave)")
    if alpha2_uncertainty:
        d = abs(alpha2.real) * alpha2_uncertainty
        ax3.axhspan(
            alpha2.real - d,
            alpha2.real + d,
            color="0.85",
            zorder=0,
            label=f"± {alpha2_uncertainty:.1%} (convergence of α2)",
        )
    ax3.axhline(0.0, color="0.5", lw=0.6)
    ax3.set_xlabel(f"$k$ [{_K_UNIT}]")
    ax3.set_ylabel(r"Re $\alpha / k^2$ [$\sigma^{2}\,(g/\sigma)^{1/2}$]")
    ax3.set_title(r"(c) approach to the $k^2$ regime", fontsize=9)
    ax3.legend(fontsize=7, loc="best")
    fig.suptitle(title or f"Least-stable branch near k = 0 — {head}", fontsize=10)
    return _save(fig, path, dpi) if path is not None else fig


# -- eigenfunctions -------------------------------------------------------------------------
def _mode_grid(mode, flow):

    # the grid the mode was computed on (sinh-mapped by default), rebuilt from ``flow``
    mapped = isinstance(getattr(mode, "grid", None), MappedChebyshevGrid)
    g = stability_grid(flow, mode.n, mapped)
    if len(mode.y) != len(g.y) or not np.allclose(mode.y, g.y, rtol=1e-10, atol=1e-10):
        raise ValueError(
            "mode and flow do not match: the mode's nodes are not the "
            "collocation nodes of the flow's domain [0, y_max]"
        )
    return g


def _aligned(mode, x_peak: float):
    """Fields multiplied by one complex constant: max |ν̂| = 1, and Re[ν̂ e^{ikx}] largest at
    x = x_peak λ at the height where |ν̂| is largest (the eigenvector's phase is arbitrary)."""
    nu = np.asarray(mode.fields["nu"])
    j = int(np.argmax(np.abs(nu)))
    c = np.conj(nu[j]) / abs(nu[j]) ** 2 * np.exp(-2j * math.pi * x_peak)
    return {f: c * np.asarray(v) for f, v in mode.fields.items()}, j


def default_height(flow, fraction: float = 0.1) -> float:
    """Height above the density peak where ν0 has fallen to ``fraction`` of its peak value.

    The eigenfunction plots stop there by default: the density perturbation lives in the
    dense layer, and the much larger velocity perturbations of the dilute top would
    otherwise dominate the arrows (the paper's statements refer to y ≈ 1–3).
    """

    g = flow.grid
    y = np.linspace(flow.y_peak, flow.y_max, 4001)
    s = g.interpolate(np.asarray(flow.log_nu), y)
    below = np.nonzero(s < s[0] + math.log(fraction))[0]
    return float(y[below[0]]) if len(below) else float(flow.y_max)


def eigenfunction_fields(
    mode, flow, *, y_top: float | None = None, nx: int = 121, ny: int = 161, x_peak: float = 0.0
) -> dict:
    """Perturbation fields over one wavelength, on a regular (x/λ, y) grid.

    Parameters
    ----------
    mode : chuteflow.stability.Mode
        An eigenmode at wavenumber k > 0 (fields on the Chebyshev nodes of ``flow``).
    flow : SteadyFlow
        Its base state.
    y_top : float, optional
        Upper end of the y range (default :func:`default_height`, at most y_max).
    x_peak : float
        Phase convention: the density perturbation peaks at x = x_peak λ.

    Returns
    -------
    dict
        ``x`` (x/λ, 1-D), ``y`` (1-D), ``nu``, ``u``, ``v``, ``T`` (2-D, shape (ny, nx)):
        Re[f̂(y) e^{ikx}] with the eigenvector scaled so that max |ν̂| = 1; ``lambda`` = 2π/k.
    """
    if not mode.k > 0:
        raise ValueError(f"k = {mode.k!r}: the eigenfunction over one wavelength needs k > 0")
    g = _mode_grid(mode, flow)
    y_top = float(min(flow.y_max, y_top if y_top is not None else default_height(flow)))
    if not y_top > 0:
        raise ValueError(f"y_top = {y_top!r}: need a positive height")
    fields, _ = _aligned(mode, x_peak)
    x = np.linspace(0.0, 1.0, nx)
    y = np.linspace(0.0, y_top, ny)
    phase = np.exp(2j * math.pi * x)[None, :]
    out = {"x": x, "y": y, "lambda": 2 * math.pi / mode.k}
    for f, v in fields.items():
        out[f] = (_interp(g, v, y)[:, None] * phase).real
    return out


def eigenfunction_diagnostics(mode, flow) -> dict:
    """Numbers behind the paper's statements about an eigenfunction (§4.2, figs 10, 11, 14).

    With perturbations ∝ e^{αt + ikx}, the linearised mass balance (eq. A 1),
    α ν̂ + ik u0 ν̂ + ν0' v̂ + ν0 (ik û + v̂') = 0, multiplied by ν̂* and integrated over y gives

        Re α ∫|ν̂|² dy = ∫ Re[ν̂* (−ν0 ∇·û)] dy + ∫ Re[ν̂* (−ν0' v̂)] dy,

    (the advection term is imaginary): growth comes from grains converging (−ν0 ∇·û > 0) where
    the density perturbation is positive, plus the vertical advection of the base density.
    The terms are those of the derived mass balance
    (:func:`chuteflow.stability.equation_terms`): the ones acting on a velocity derivative
    make up −ν0 ∇·û, the ones acting on the velocity itself −ν0' v̂.

    Returns
    -------
    dict
        ``compression``: the first integral over ∫|ν̂|² (> 0: the grains flow into the region
        of positive density perturbation); ``vertical_advection``: the second;
        ``identity_residual``: |compression + vertical_advection − Re α| relative to
        |compression| + |vertical_advection| (how well the eigenvector satisfies the mass
        balance); ``temperature_density``: ∫Re(T̂ ν̂*) dy / ∫|T̂||ν̂| dy, the |T̂||ν̂|-weighted
        mean cosine of the phase difference (< 0: temperature low where density high);
        ``temperature_at_peak``: that cosine at the height of largest |ν̂|;
        ``floor_velocity_density``: cosine of the phase difference of û(0) and ν̂(0) (> 0:
        the floor velocity perturbation is positive where the density perturbation is);
        ``velocity_density``: ∫Re(û ν̂*) dy / ∫|û||ν̂| dy (> 0: the dense parts move faster);
        ``y_peak``: height of largest |ν̂|.
    """

    g = _mode_grid(mode, flow)
    f, j = _aligned(mode, 0.0)
    nu, u, T = f["nu"], f["u"], f["T"]
    compression = np.zeros(len(nu), complex)  # −ν0 ∇·û
    vertical = np.zeros(len(nu), complex)  # −ν0' v̂ (advection of the base density)
    for t, term in equation_terms(flow, "mass", f, mode.k, mode.kz, mode.alpha, grid=g):
        if t.field in ("u", "v", "w"):
            if t.b or t.c or t.d:
                compression += term
            else:
                vertical += term
    norm = float(g.integrate(np.abs(nu) ** 2))
    comp = float(g.integrate((np.conj(nu) * compression).real)) / norm
    vert = float(g.integrate((np.conj(nu) * vertical).real)) / norm
    growth = float(mode.alpha.real)
    scale = abs(comp) + abs(vert)
    tnu = float(g.integrate((T * np.conj(nu)).real)) / float(g.integrate(np.abs(T) * np.abs(nu)))
    unu = float(g.integrate((u * np.conj(nu)).real)) / float(g.integrate(np.abs(u) * np.abs(nu)))

    def cos(a, b):
        d = abs(a) * abs(b)
        return float((a * np.conj(b)).real / d) if d > 0 else math.nan

    return {
        "compression": comp,
        "vertical_advection": vert,
        "identity_residual": abs(comp + vert - growth) / scale if scale > 0 else math.nan,
        "growth_rate": growth,
        "temperature_density": tnu,
        "temperature_at_peak": cos(T[j], nu[j]),
        "floor_velocity_density": cos(u[0], nu[0]),
        "velocity_density": unu,
        "y_peak": float(g.y[j]),
    }


def _contour_panel(fig, ax, F, key, cbar_label, levels=15):
    x, y, Z = F["x"], F["y"], F[key]
    zmax = float(np.abs(Z).max()) or 1.0
    lev = np.linspace(-zmax, zmax, 2 * (levels // 2) + 2)
    cs = ax.contourf(x, y, Z, levels=lev, cmap="gray")
    if Z.min() < 0 < Z.max():
        ax.contour(x, y, Z, levels=[0.0], colors="k", linewidths=0.6, linestyles="--")
    cb = fig.colorbar(cs, ax=ax, shrink=0.9)
    from matplotlib.ticker import MaxNLocator

    cb.locator = MaxNLocator(7, symmetric=True)
    cb.update_ticks()
    cb.set_label(cbar_label, fontsize=8)
    ax.set_xlabel(r"$x/\lambda$")
    ax.set_ylabel(r"$y$ [$\sigma$]")
    return cs


def _arrows(ax, F, xlim=(0.0, 1.0), ylim=None, nxq=17, nyq=12):
    """Velocity perturbation as arrows, (û/λ, v̂) in the plot's (x/λ, y) coordinates: their
    directions are the true directions of motion in this plot, so that converging arrows
    are a negative divergence ∂u1/∂x + ∂v1/∂y."""
    x, y = F["x"], F["y"]
    ylim = ylim or (y[0], y[-1])
    xi = np.linspace(xlim[0], xlim[1], nxq + 2)[1:-1]
    yi = np.linspace(ylim[0], ylim[1], nyq + 2)[1:-1]
    ix = np.clip(np.searchsorted(x, xi), 0, len(x) - 1)
    iy = np.clip(np.searchsorted(y, yi), 0, len(y) - 1)
    U = F["u"][np.ix_(iy, ix)] / F["lambda"]
    V = F["v"][np.ix_(iy, ix)]
    wx, wy = xlim[1] - xlim[0], ylim[1] - ylim[0]
    size = np.hypot(U / wx, V / wy).max()
    if not size > 0:
        return
    # with scale_units="xy" an arrow spans (U, V)/scale data units, i.e. `size`/scale axes
    # fractions at most: make the longest arrow 0.9 of a cell
    scale = size * max(nxq, nyq) / 0.9
    ax.quiver(
        x[ix],
        y[iy],
        U,
        V,
        angles="xy",
        scale_units="xy",
        scale=scale,
        color="tab:red",
        width=0.004,
        headwidth=3.5,
    )


def eigenfunction_figure(
    mode,
    flow,
    path=None,
    *,
    label: str = "",
    y_top: float | None = None,
    x_peak: float = 0.0,
    magnify: tuple | None = None,
    title: str | None = None,
    dpi: int = 150,
):
    """Eigenfunction over one wavelength (figures 10, 11, 14).

    Parameters
    ----------
    mode : chuteflow.stability.Mode
        The eigenmode (k > 0), e.g. :func:`chuteflow.stability.least_stable` at k = 0.002.
    flow : SteadyFlow
        Its base state.
    path : path, optional
        Where to save; without it the figure is returned.
    label : str
        Name of the point (e.g. "P1"), for the title.
    y_top : float, optional
        Upper end of the y axis (default: where ν0 has fallen to a tenth of its peak,
        :func:`default_height`).
    x_peak : float
        The density perturbation peaks at x = x_peak λ (the eigenvector's phase is arbitrary).
    magnify : (x0, x1, y0, y1), optional
        Add panel (c): panel (a) on x/λ ∈ [x0, x1], y ∈ [y0, y1].

    Panel (a): Re[ν̂ e^{ikx}] in grey scale (brighter = larger), the zero contour dashed, and the
    velocity perturbation as arrows (their convergence in the plot is the true ∇·u1 < 0);
    panel (b): Re[T̂ e^{ikx}] with the zero contour of the density perturbation dotted. The
    eigenvector is scaled so that max |ν̂| = 1.
    """
    F = eigenfunction_fields(mode, flow, y_top=y_top, x_peak=x_peak)
    ncol = 3 if magnify else 2
    fig = _new_figure(5.0 * ncol, 4.3)
    axes = fig.subplots(1, ncol)
    ax_a, ax_b = axes[0], axes[1]
    _contour_panel(fig, ax_a, F, "nu", r"Re$[\hat\nu\,e^{ikx}]$ / max$|\hat\nu|$")
    _arrows(ax_a, F)
    ax_a.set_title(r"(a) density $\nu_1$ and velocity $(u_1, v_1)$", fontsize=9)
    _contour_panel(fig, ax_b, F, "T", r"Re$[\hat T\,e^{ikx}]$ / max$|\hat\nu|$")
    if F["nu"].min() < 0 < F["nu"].max():
        ax_b.contour(F["x"], F["y"], F["nu"], levels=[0.0], colors="tab:blue", linewidths=0.8, linestyles=":")
    ax_b.set_title(r"(b) temperature $T_1$ (dotted: $\nu_1 = 0$)", fontsize=9)
    if magnify:
        x0, x1, y0, y1 = (float(v) for v in magnify)
        G = eigenfunction_fields(mode, flow, y_top=y1, x_peak=x_peak, nx=161, ny=121)
        sel_x = (G["x"] >= x0) & (G["x"] <= x1)
        sel_y = G["y"] >= y0
        H = dict(G, x=G["x"][sel_x], y=G["y"][sel_y], **{f: G[f][np.ix_(sel_y, sel_x)] for f in mode.fields})
        ax_c = axes[2]
        _contour_panel(fig, ax_c, H, "nu", r"Re$[\hat\nu\,e^{ikx}]$ / max$|\hat\nu|$")
        _arrows(ax_c, H, xlim=(H["x"][0], H["x"][-1]), ylim=(H["y"][0], H["y"][-1]), nxq=11, nyq=9)
        ax_c.set_title(f"(c) (a) magnified: x/λ ∈ [{x0:g}, {x1:g}], y ∈ [{y0:g}, {y1:g}]", fontsize=9)
        ax_a.add_patch(_rect(x0, x1, y0, min(y1, F["y"][-1])))
    a = mode.alpha
    lam = 2 * math.pi / mode.k
    head = point_label(mode.theta, mode.nu0, getattr(flow.model, "roughness", None))
    fig.suptitle(
        title
        or (
            f"{label + ': ' if label else ''}{head}, k = {mode.k:g} "
            f"(λ = {lam:.0f}), α = {a.real:.4g} {a.imag:+.4g}i "
            f"({'unstable' if a.real > 0 else 'stable'})"
        ),
        fontsize=10,
    )
    return _save(fig, path, dpi) if path is not None else fig


def _rect(x0, x1, y0, y1):
    from matplotlib.patches import Rectangle

    return Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="tab:blue", lw=1.0)
