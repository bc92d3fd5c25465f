"""Figures of the reduced 1D model (§5.1.2, figure 15) and of its nonlinear density waves.

- :func:`plot_functions`: F, T̄, a, U, the flux q0 = ρ̄U next to the full model's Q0, and the
  criterion (ρ̄U')² − (ρ̄T̄)' along a steady family.
- :func:`plot_phase_diagrams`: 1D stability diagram(s) in the (h, ν̄) plane, unstable grey,
  unstable at every wavelength ((ρ̄T̄)' < 0) dark grey, non-monotonic boundary dashed; beside
  the full model's diagram when given, with the points where they disagree marked.
- :func:`plot_spacetime`: ρ̄(x, t) of a simulation, the wave amplitude against the linear
  growth, and late profiles.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .diagram import grid_triangulation

__all__ = ["plot_functions", "plot_phase_diagrams", "plot_spacetime", "save"]


def save(fig, path, dpi: int = 130) -> Path:
    """Save ``fig`` to ``path`` (format from the suffix) and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return path


def plot_functions(rm, n: int = 300):
    """The 1D model's functions along the family of ``rm`` (a ReducedModel)."""
    import matplotlib.pyplot as plt

    tab = rm.table(n)
    r = tab["rho"].values
    fig, axs = plt.subplots(2, 2, figsize=(10, 7.5))
    ax = axs[0, 0]
    ax.plot(r, tab["F"], "k-", label="F(ρ̄) = ν₀(0)")
    ax.plot(rm.rho, rm.nu0, "k.", ms=4)
    ax.set_ylabel("F")
    ax2 = ax.twinx()
    ax2.plot(r, tab["Tbar"], "C3-", label="T̄(ρ̄)")
    ax2.set_ylabel("T̄", color="C3")
    ax.legend(loc="upper left", fontsize=8)
    ax2.legend(loc="upper right", fontsize=8)
    ax = axs[0, 1]
    ax.plot(r, tab["U"], "k-", label="U(ρ̄) = ρ̄ sinθ / a")
    ax.set_ylabel("U")
    ax2 = ax.twinx()
    ax2.plot(r, tab["a"], "C0-", label="a(ρ̄) = η*(F, T̄)")
    ax2.set_ylabel("a", color="C0")
    ax.legend(loc="upper left", fontsize=8)
    ax2.legend(loc="upper right", fontsize=8)
    ax = axs[1, 0]
    ax.plot(r, tab["q"], "k-", label="q₀ = ρ̄ U(ρ̄) (1D model)")
    if rm.flux is not None:
        ax.plot(rm.rho, rm.flux, "C1o", ms=3, label="Q₀ of the steady flows")
    ax.set_xlabel("ρ̄")
    ax.set_ylabel("flux")
    ax.legend(fontsize=8)
    ax = axs[1, 1]
    m = tab["criterion_margin"].values
    dP = tab["dP"].values
    ax.plot(r, m, "k-", label="(ρ̄U′)² − (ρ̄T̄)′")
    ax.plot(r, dP, "C2--", label="(ρ̄T̄)′")
    ax.axhline(0, color="0.5", lw=0.6)
    ylim = np.nanpercentile(np.r_[m, dP], [2, 98])
    pad = 0.1 * (ylim[1] - ylim[0] + 1e-12)
    ax.set_ylim(ylim[0] - pad, ylim[1] + pad)
    ax.fill_between(r, *ax.get_ylim(), where=m > 0, color="0.85", label="unstable (eq. 5.13)")
    ax.fill_between(r, *ax.get_ylim(), where=dP < 0, color="0.6", alpha=0.5, label="(ρ̄T̄)′ < 0: all k grow")
    ax.set_xlabel("ρ̄")
    ax.legend(fontsize=8)
    phi = rm.model.roughness
    fig.suptitle(
        f"1D model functions, θ = {rm.theta:g}°, φ = {phi:g} "
        f"(knots: {len(rm.rho)}, interpolation error ≤ "
        f"{max(rm.accuracy.get(k, np.nan) for k in ('F', 'Tbar', 'a')):.1e})"
    )
    fig.tight_layout()
    return fig


def _panel(ax, ds, var, title, *, short_var=None, disagree=None):
    from matplotlib.artist import Artist
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    h, nb = ds["h"].values, ds["nu_mean"].values
    ok = (ds["status"].values == 0) & np.isfinite(h) & np.isfinite(nb)
    tri = grid_triangulation(h, nb, ok)
    handles: list[Artist] = []
    if tri is not None:
        for name, colour, label in (
            (var, "0.72", "unstable"),
            (short_var, "0.4", "unstable at every k ((ρ̄T̄)′ < 0)"),
        ):
            if name is None or name not in ds:
                continue
            u = ds[name].values.astype(float)
            u = np.where(u < 0, np.nan, u).ravel()
            if not np.nansum(u):
                continue
            tri.set_mask(np.isnan(u)[tri.triangles].any(axis=1))
            ax.tricontourf(tri, np.nan_to_num(u), levels=[0.5, 1.5], colors=[colour])
            handles.append(Patch(facecolor=colour, label=label))
            tri.set_mask(None)
        mono = ds["monotonic"].values.astype(float).ravel()
        if (mono[ok.ravel()] == 0).any() and (mono[ok.ravel()] == 1).any():
            ax.tricontour(tri, mono, levels=[0.5], colors="k", linestyles="--", linewidths=1.3)
            handles.append(Line2D([], [], color="k", ls="--", label="non-monotonic boundary"))
    ax.plot(h[ok], nb[ok], ".", color="0.3", ms=2)
    if disagree is not None and disagree.any():
        ax.plot(h[disagree], nb[disagree], "x", color="crimson", ms=6, mew=1.4)
        handles.append(Line2D([], [], marker="x", color="crimson", ls="", label="classified differently"))
    if ok.any():
        ax.set_xlim(0, min(60.0, 1.05 * float(np.nanmax(h[ok]))))
        ax.set_ylim(0, 1.05 * float(np.nanmax(nb[ok])))
    ax.set_xlabel("thickness h")
    ax.set_ylabel("mean density ν̄")
    ax.set_title(title, fontsize=10)
    ax.legend(handles=handles, fontsize=7, loc="upper right", framealpha=0.85)


def plot_phase_diagrams(reduced, full=None, *, agreement=None):
    """1D diagram(s) (figure 15); ``reduced`` is one Dataset or a list (one per φ).

    ``full``: matching full-model sweep Dataset(s) (``unstable`` from
    :func:`chuteflow.sweep.classify`), drawn in a second row; points the two classify
    differently are marked on the 1D panel. ``agreement``: matching dicts from
    :func:`chuteflow.reduced.agreement`, quoted in the titles.
    """
    import matplotlib.pyplot as plt

    red = list(reduced) if isinstance(reduced, (list, tuple)) else [reduced]
    fulls = list(full) if isinstance(full, (list, tuple)) else ([full] if full is not None else [])
    agr = (
        list(agreement)
        if isinstance(agreement, (list, tuple))
        else ([agreement] if agreement is not None else [])
    )
    rows = 2 if fulls else 1
    fig, axs = plt.subplots(rows, len(red), figsize=(5.6 * len(red), 4.8 * rows), squeeze=False)
    for c, ds in enumerate(red):
        phi = ds.attrs.get("roughness", float("nan"))
        fds = fulls[c] if c < len(fulls) else None
        dis = None
        if fds is not None and "unstable" in fds:
            dis = _disagreement(ds, fds)
        title = f"1D model, φ = {phi:g}"
        if c < len(agr) and agr[c]:
            a = agr[c]
            title += f": {100 * a['fraction']:.0f} % of {a['compared']} points as full model"
        _panel(axs[0, c], ds, "r1d_unstable", title, short_var="r1d_short_wave", disagree=dis)
        if fds is not None:
            _panel(axs[1, c], fds, "unstable", f"full model (Re α₂ > 0), φ = {phi:g}")
    fig.tight_layout()
    return fig


def _disagreement(ds, fds):
    """Boolean (theta, nu0) map of ``ds`` where the 1D and full classifications differ."""
    out = np.zeros(ds["r1d_unstable"].shape, dtype=bool)
    th_f, nu_f = fds["theta"].values, fds["nu0"].values
    uf = fds["unstable"].values
    for i, th in enumerate(ds["theta"].values):
        ii = np.nonzero(np.isclose(th_f, th, rtol=1e-9, atol=1e-12))[0]
        if not len(ii):
            continue
        for j, nu in enumerate(ds["nu0"].values):
            jj = np.nonzero(np.isclose(nu_f, nu, rtol=1e-9, atol=1e-12))[0]
            if not len(jj):
                continue
            a, b = ds["r1d_unstable"].values[i, j], uf[ii[0], jj[0]]
            out[i, j] = a >= 0 and b >= 0 and a != b
    return out


def plot_spacetime(ds, *, profiles: int = 3):
    """Space–time plot of ρ̄(x, t), amplitude vs time with the linear growth, late profiles."""
    import matplotlib.pyplot as plt

    t, x = ds["t"].values, ds["x"].values
    rho = ds["rho"].values
    rho0 = float(ds.attrs["rho0"])
    fig, axs = plt.subplots(1, 3, figsize=(15, 4.8), gridspec_kw={"width_ratios": [1.3, 1, 1]})
    ax = axs[0]
    dev = rho - rho0
    lim = float(np.nanpercentile(np.abs(dev[-max(len(t) // 5, 1) :]), 99.5)) or 1e-12
    pm = ax.pcolormesh(x, t, dev, shading="auto", cmap="RdBu_r", vmin=-lim, vmax=lim, rasterized=True)
    fig.colorbar(pm, ax=ax, label="ρ̄ − ρ₀")
    c = float(ds.attrs.get("frame_speed", 0.0))
    ax.set_xlabel("x (down the slope, σ)" if c == 0 else f"ξ = x − {c:.3g} t (σ)")
    ax.set_ylabel("t (√(σ/g))")
    ax.set_title("density wave formation", fontsize=10)
    ax = axs[1]
    amp = ds["amplitude"].values
    ax.semilogy(t, amp, "k-", label="max |ρ̄ − ρ₀|")
    sigma = float(ds.attrs.get("max_growth_rate", np.nan))
    if np.isfinite(sigma) and "mode_amplitude" in ds:
        ma = ds["mode_amplitude"].values
        n_best = int(np.nanargmax(ds["growth_discrete"].values))
        mode = int(ds["mode"].values[n_best])
        ax.semilogy(t, ma[:, n_best], "C0-", lw=1, label=f"|ρ̂| of mode {mode}")
        ref = ma[0, n_best] * np.exp(sigma * t)
        keep = ref < 10 * amp.max()
        ax.semilogy(t[keep], ref[keep], "C3--", lw=1, label=f"linear theory, Re α = {sigma:.3g}")
    ax.set_xlabel("t")
    ax.legend(fontsize=8)
    ax.set_title(f"status: {ds.attrs.get('status', '?')}", fontsize=10)
    ax = axs[2]
    idx = np.unique(np.linspace(len(t) // 2, len(t) - 1, profiles).astype(int))
    for i in idx:
        ax.plot(x, rho[i], lw=1, label=f"t = {t[i]:.4g}")
    ax.axhline(rho0, color="0.5", lw=0.6)
    ax.set_xlabel("x")
    ax.set_ylabel("ρ̄")
    ax.legend(fontsize=8)
    ax.set_title("wave profiles", fontsize=10)
    fig.suptitle(
        f"1D model, θ = {ds.attrs['theta']:g}°, φ = {ds.attrs['roughness']:g}, "
        f"ρ₀ = {rho0:.4g} (ν₀(0) = {ds.attrs['nu0']:.4g}), L = {ds.attrs['length']:g}, "
        f"N = {ds.attrs['n_cells']}; "
        + (
            "(ρ̄T̄)′ < 0: every k grows, no L_c"
            if str(ds.attrs.get("short_wave_unstable")) == "True"
            else f"L_c = {ds.attrs['L_c']:.4g}"
        ),
        fontsize=11,
    )
    fig.tight_layout()
    return fig
