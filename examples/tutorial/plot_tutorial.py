"""
From a steady flow to its density waves (P1)
============================================

The paper's point P1 — θ = 16°, floor packing fraction ν0(0) = 0.05, roughness φ = 0.05 —
is unstable to long waves: perturbations with wavelengths longer than about 900 particle
diameters grow (§4.2, figure 7). This tutorial computes that statement step by step.
"""

# %%
# 1. The steady flow
# ------------------
# :class:`~chuteflow.closures.ChuteModel` holds the parameters and closures (here the
# paper's defaults, e_p = 0.7, ν_m = 0.6, Φ = 0.39, with φ = 0.05).
# :func:`~chuteflow.steady.solve_steady` solves the steady equations (3.8)–(3.13) on
# Chebyshev nodes of [0, y_max], where ν0(y_max) = ``nu_top`` = 1e-9, and raises the
# resolution until the scalar results have converged; ``convergence`` is the estimated
# relative error.
import matplotlib.pyplot as plt
import numpy as np

from chuteflow import ChuteModel, solve_steady
from chuteflow.figures.stability import eigenfunction_figure
from chuteflow.longwave import longwave
from chuteflow.stability import critical_k, dispersion, least_stable

model = ChuteModel(roughness=0.05)
flow = solve_steady(theta=16, nu0=0.05, model=model)
print(f"h = {flow.h:.4f}, mean density = {flow.nu_mean:.5f}, Q0 = {flow.Q:.5f}")
print(f"N = {flow.n}, y_max = {flow.y_max:.2f}, convergence = {flow.convergence:.1e}")

y = np.linspace(0, 45, 400)
prof = flow.profiles(y)
fig, axes = plt.subplots(1, 3, figsize=(9, 3.2), sharey=True, layout="constrained")
for ax, key, label in zip(axes, ("nu", "u", "T"), ("ν0", "u0", "T0")):
    ax.plot(prof[key], y)
    ax.set_xlabel(label)
axes[0].set_ylabel("y (particle diameters)")
axes[0].axhline(flow.h, ls=":", c="grey")
fig.suptitle("P1: steady profiles (dotted: thickness h)")

# %%
# 2. The dispersion relation
# --------------------------
# Normal modes ∝ exp(αt + ikx) (eq. (4.4)). :func:`~chuteflow.stability.dispersion`
# follows the branch with α(0) = 0 (the kinematic-wave mode of Appendix B) in k and
# returns an :class:`xarray.Dataset`; every point carries its convergence estimates
# (``drift``, ``tail``) and whether it passed the paper's tests (``physical``).
ks = np.geomspace(1e-4, 2e-2, 14)
ds = dispersion(flow, ks)
print("all points physical:", bool(ds.physical.all()), " largest drift:", float(ds.drift.max()))

fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.4), layout="constrained")
a.plot(ds.k, ds.alpha_re, "o-")
a.axhline(0, c="k", lw=0.8)
a.set(xscale="log", xlabel="k", ylabel="Re α (growth rate)")
b.plot(ds.k, -ds.alpha_im / ds.k, "o-")
b.set(xscale="log", xlabel="k", ylabel="c = −Im α / k")

# %%
# 3. The critical wavenumber
# --------------------------
# :func:`~chuteflow.stability.critical_k` finds where Re α changes sign on the tracked
# branch (Brent's method); the paper reads k_c ≈ 0.007 off figure 7 (λ_c ≈ 900).
k_c = critical_k(flow)
print(f"k_c = {k_c:.6f}, critical wavelength 2π/k_c = {2 * np.pi / k_c:.1f} diameters")

fig, ax = plt.subplots(figsize=(6, 3.4), layout="constrained")
ax.plot(ds.k, ds.alpha_re, "o-")
ax.axhline(0, c="k", lw=0.8)
ax.axvline(k_c, ls=":", c="C3")
ax.annotate(f"k_c = {k_c:.5f}", (k_c, 0), xytext=(6, 20), textcoords="offset points", color="C3")
ax.set(xlabel="k", ylabel="Re α", xlim=(0, 0.012), ylim=(-0.002, 0.0025), title="unstable for 0 < k < k_c")

# %%
# 4. The eigenfunction
# --------------------
# :func:`~chuteflow.stability.least_stable` returns a :class:`~chuteflow.stability.Mode`
# with its eigenvalue, eigenfunctions and convergence estimates;
# :func:`~chuteflow.figures.stability.eigenfunction_figure` draws the density and
# temperature perturbations over one wavelength, with the velocity perturbation as arrows
# (figure 11 of the paper).
mode = least_stable(flow, 0.002)
print(f"alpha = {mode.alpha:.6g}, drift = {mode.drift:.1e}, tail = {mode.tail:.1e}")
print(f"physical (passes both tests) = {mode.physical}, N = {mode.n}")
fig = eigenfunction_figure(mode, flow, label="P1")
plt.figure(fig)  # chuteflow.figures returns a Figure: show it through pyplot

# %%
# 5. The long-wave coefficients
# -----------------------------
# α(k) = α1 k + α2 k² + O(k³). :func:`~chuteflow.longwave.longwave` computes α1 by
# perturbation theory at k = 0 (Appendix B), α1 = −i dQ0/dρ̄0 (eq. (B 2)), and α2 as the
# dispersion relation's k² coefficient, (α(k) − α1 k)/k² from the eigenvalue at k = 1e-5:
# the sign of Re α2 decides long-wave stability. Because the k² regime is narrow (docs:
# errata, numerical note 4), the strict Taylor α2 of perturbation theory, which feels the
# dilute top, is only a diagnostic (``lw.alpha2_taylor``).
lw = longwave(flow)
print(f"alpha1 = {lw.alpha1:.6g}   -i dQ0/drho = {-1j * lw.dQ_drho:.6g}")
print(
    f"alpha2 = {lw.alpha2:.6g} (relative change {lw.alpha2_convergence:.1e}), Taylor: {lw.alpha2_taylor:.6g}"
)

kk = np.geomspace(1e-4, 3e-3, 30)
fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
ax.plot(ds.k, ds.alpha_re, "o", label="eigenvalues")
ax.plot(kk, lw.alpha2.real * kk**2, "--", label="Re α ≈ Re α2 k² (α2 at k = 1e-5)")
ax.set(xscale="log", yscale="log", xlabel="k", ylabel="Re α", xlim=(8e-5, 3e-3), ylim=(1e-5, 5e-3))
ax.legend()
ax.set_title("The k² law holds only at the smallest k")
