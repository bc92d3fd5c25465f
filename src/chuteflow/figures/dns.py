"""Figures of the time-dependent simulation (:mod:`chuteflow.dns`).

- :func:`plot_dns`: space–time plot of ρ̄(x, t), the amplitude of the k = 2π/L wave against
  the linear eigenvalue's growth, and a snapshot of ν(x, y) with velocity arrows (the
  velocity relative to the x-averaged profile, so that the wave's circulation shows).
- :func:`plot_wave_profile`: the wave at the end of one or more runs (e.g. two resolutions):
  ρ̄(ξ) with the crests aligned, and Q against ρ̄, a straight line of slope c for a wave
  travelling unchanged at speed c (∂_t ρ̄ + ∂_x Q = 0).
"""

from __future__ import annotations

import numpy as np

from .reduced import save

__all__ = ["plot_dns", "plot_wave_profile", "wave_speed_from_flux", "save"]


def wave_speed_from_flux(ds, index: int = -1) -> tuple[float, float]:
    """Speed c and intercept q of the least-squares line Q = c ρ̄ + q through one record.

    A wave that travels unchanged at speed c satisfies ∂_t ρ̄ + ∂_x Q = 0 with ρ̄(x − ct),
    hence Q − c ρ̄ = const (Q is the flux in the floor's frame, so c is the lab speed).
    """
    rho = np.asarray(ds["rho_bar"].values[index], dtype=float)
    Q = np.asarray(ds["Q"].values[index], dtype=float)
    c, q = np.polyfit(rho, Q, 1)
    return float(c), float(q)


def plot_wave_profile(datasets, labels=None, *, family=None):
    """ρ̄(ξ) at the last record of each run (crests aligned at L/2), and Q against ρ̄.

    Parameters
    ----------
    datasets : sequence of xarray.Dataset
        Results of :func:`chuteflow.dns.simulate` (e.g. one wave at two resolutions).
    labels : sequence of str, optional
        Legend entries (default nx × ny).
    family : tuple of arrays, optional
        (ρ̄0, Q0) of the steady family at the same θ, drawn for comparison (its slope
        dQ0/dρ̄0 is the kinematic-wave speed).
    """
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 2, figsize=(12, 4.4))
    labels = labels or [f"nx = {d.attrs['nx']}, ny = {d.attrs['ny']}" for d in datasets]
    for i, (ds, lab) in enumerate(zip(datasets, labels)):
        L = float(ds.attrs["length"])
        x = ds["x"].values
        rho, Q = ds["rho_bar"].values[-1], ds["Q"].values[-1]
        shift = L / 2 - x[int(np.argmax(rho))]
        xs = np.mod(x + shift, L)
        o = np.argsort(xs)
        t_end = float(ds["time"].values[-1])
        axs[0].plot(xs[o], rho[o], f"C{i}-", label=f"{lab}, t = {t_end:.5g}")
        c, q = wave_speed_from_flux(ds)
        axs[1].plot(rho, Q, f"C{i}.", ms=3, label=f"{lab}: slope c = {c:.4g}")
        r = np.linspace(rho.min(), rho.max(), 2)
        axs[1].plot(r, c * r + q, f"C{i}-", lw=0.8)
    if family is not None:
        r0, q0 = (np.asarray(a, dtype=float) for a in family)
        axs[1].plot(r0, q0, "k--", lw=1, label="steady family Q0(ρ̄0)")
    axs[0].set_xlabel("ξ (crest at L/2, σ)")
    axs[0].set_ylabel("ρ̄ = ∫ν dy")
    axs[0].legend(fontsize=8)
    axs[0].set_title("the wave's depth-integrated density", fontsize=10)
    axs[1].set_xlabel("ρ̄")
    axs[1].set_ylabel("Q = ∫νu dy")
    axs[1].legend(fontsize=8)
    axs[1].set_title("Q − c ρ̄ = const for a wave travelling unchanged at c", fontsize=10)
    a = datasets[0].attrs
    fig.suptitle(
        f"θ = {float(a['theta']):g}°, ν₀(0) = {float(a['nu0']):g}, L = {float(a['length']):.5g}",
        fontsize=11,
    )
    fig.tight_layout()
    return fig


def plot_dns(ds, *, snapshot: int = -1, y_top: float | None = None):
    """Space–time ρ̄(x, t), |ρ̂_1|(t) with exp(Re α t), and ν(x, y) with arrows at one snapshot.

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`chuteflow.dns.simulate`.
    snapshot : int
        Index of the snapshot drawn (default the last).
    y_top : float, optional
        Upper limit of the snapshot's y axis (default 2.5 × the height where the x-averaged
        ν falls below 1 % of its maximum).
    """
    import matplotlib.pyplot as plt

    a = ds.attrs
    t, x = ds["time"].values, ds["x"].values
    rho = ds["rho_bar"].values
    fig, axs = plt.subplots(1, 3, figsize=(16, 4.8), gridspec_kw={"width_ratios": [1.2, 1, 1.4]})
    ax = axs[0]
    dev = rho - rho.mean(axis=-1, keepdims=True)
    if 0 < x.size < 96:  # few collocation points: draw the trigonometric interpolant
        from scipy.signal import resample

        dev = resample(dev, 96, axis=-1)
        x = np.arange(96) * float(a["length"]) / 96
    lim = float(np.nanmax(np.abs(dev))) or 1e-300
    pm = ax.pcolormesh(x, t, dev, shading="auto", cmap="RdBu_r", vmin=-lim, vmax=lim, rasterized=True)
    fig.colorbar(pm, ax=ax, label="ρ̄ − ⟨ρ̄⟩ₓ")
    c = float(a.get("frame_speed", 0.0))
    ax.set_xlabel("x (down the slope, σ)" if c == 0 else f"ξ = x − {c:.4g} t (σ)")
    ax.set_ylabel("t (√(σ/g))")
    ax.set_title("ρ̄(x, t) = ∫ν dy", fontsize=10)
    ax = axs[1]
    A = np.hypot(ds["amplitude_re"].values, ds["amplitude_im"].values)
    ax.semilogy(t, A, "k-", label="|ρ̂₁| (k = 2π/L)")
    ar = float(a["alpha_re"])
    if A.size and A[0] > 0:
        ax.semilogy(t, A[0] * np.exp(ar * t), "C3--", lw=1, label=f"linear theory, Re α = {ar:.3g}")
    ax.set_xlabel("t")
    ax.legend(fontsize=8)
    ax.set_title(
        f"measured {float(a['growth_rate']):.4g}, c = {float(a['phase_velocity']):.4g}; status {a['status']}",
        fontsize=9,
    )
    ax = axs[2]
    if ds.sizes.get("snapshot_time", 0):
        y = ds["y"].values
        nu = ds["nu"].values[snapshot]
        u = ds["u"].values[snapshot]
        v = ds["v"].values[snapshot]
        prof = nu.mean(axis=-1)
        if y_top is None:
            above = np.nonzero(prof > 0.01 * prof.max())[0]
            y_top = min(float(y[-1]), 2.5 * float(y[above[-1]]) if above.size else float(y[-1]))
        x = ds["x"].values
        pm = ax.pcolormesh(x, y, nu, shading="auto", cmap="viridis", rasterized=True)
        fig.colorbar(pm, ax=ax, label="ν")
        yi = np.linspace(0, y_top, 14)
        xi = np.arange(0, x.size, max(x.size // 24, 1))
        ui = np.array([np.interp(yi, y, (u - u.mean(axis=-1, keepdims=True))[:, j]) for j in xi]).T
        vi = np.array([np.interp(yi, y, v[:, j]) for j in xi]).T
        ax.quiver(x[xi], yi, ui, vi, color="w", scale_units="xy", angles="uv", width=0.003)
        ax.set_ylim(0, y_top)
        ax.set_xlabel("x" if c == 0 else "ξ")
        ax.set_ylabel("y")
        ts = float(ds["snapshot_time"].values[snapshot])
        ax.set_title(f"ν(x, y) at t = {ts:.4g}; arrows (u − ⟨u⟩ₓ, v)", fontsize=10)
    fig.suptitle(
        f"time-dependent simulation, θ = {float(a['theta']):g}°, ν₀(0) = {float(a['nu0']):g}, "
        f"L = {float(a['length']):.5g}, nx = {a['nx']}, ny = {a['ny']}, Δt = {float(a['dt']):.3g}; "
        f"eigenvalue α = {ar:.4g}{float(a['alpha_im']):+.4g}i",
        fontsize=11,
    )
    fig.tight_layout()
    return fig
