"""
The 1D model and a density wave
===============================

§5.1.2 reduces the layer to one-dimensional equations for the depth-averaged density
ρ̄(x, t) and velocity ū(x, t), with closures F(ρ̄), T̄(ρ̄), a(ρ̄) taken from the family of
steady flows at fixed θ. :func:`~chuteflow.reduced.reduced_model` builds them;
:func:`~chuteflow.reduced.local_coefficients` gives the linear theory of a uniform state
(the criterion (5.13) and the critical wavenumber from the dispersion relation (5.14),
with the errata correction of (5.12)); :func:`~chuteflow.reduced.simulate` integrates the
nonlinear equations on a periodic slope.
"""

import matplotlib.pyplot as plt

from chuteflow import ChuteModel
from chuteflow.reduced import reduced_model, simulate

rm = reduced_model(16.0, ChuteModel(roughness=0.05), nu0_min=0.08, nu0_max=0.16)
print(f"{len(rm.rho)} knots, rho in [{rm.rho.min():.3f}, {rm.rho.max():.3f}]")
errors = {k: f"{v:.1e}" for k, v in rm.accuracy.items() if k != "midpoints"}
print("largest relative interpolation error:", errors)

# %%
# The uniform state at ν0(0) = 0.12 is unstable in the 1D model: waves longer than
# L_c = 2π/k_c grow. A slope of length 40 (about 3 L_c) carries a few unstable modes.
ds = simulate(rm, 40.0, nu0=0.12, n_cells=128, time=300.0, amplitude=1e-3, snapshots=100, on_exit="stop")
print(f"status: {ds.attrs['status']}, L_c = {ds.attrs['L_c']:.2f}, mass drift {ds.attrs['mass_drift']:.1e}")

fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
pc = a.pcolormesh(ds.x, ds.t, ds.rho, shading="auto", cmap="viridis")
fig.colorbar(pc, ax=a, label="ρ̄")
a.set(xlabel="x (in the frame of the wave)", ylabel="t", title="ρ̄(x, t)")
b.semilogy(ds.t, ds.amplitude)
b.set(xlabel="t", ylabel="max |ρ̄ − ρ0|", title="growth, then steepening")
print("amplitude grew by", f"{float(ds.amplitude[-1] / ds.amplitude[0]):.3g}", "x")
