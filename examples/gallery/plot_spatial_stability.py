"""
Spatial stability: inlet forcing and the growing wave packet
============================================================

The paper's analysis is temporal: a wave periodic in x grows in time. On a chute the flow
enters at one end, and two other questions matter (docs/spatial.md):

* forced at the inlet at a real angular frequency ω, a wave exp(−iωt + ikx) grows along the
  slope at the rate −Im k(ω) (:func:`~chuteflow.spatial.spatial_dispersion`); which
  frequency grows most?
* a local disturbance becomes a packet growing along the rays x = V t at the rate
  σ(V) = Re[α(k*) + i k* V] (k* the saddle point of α(k) + ikV,
  :func:`~chuteflow.spatial.absolute_instability`): it grows for V− < V < V+. If V− > 0 the
  packet is swept downstream while it grows — the instability is *convective* and the chute
  amplifies inlet noise; if V− < 0 < V+ it grows in place (*absolute*).

At P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05) both, and the packet measured on the simulation of
the full equations: a small Gaussian bump released in a long periodic domain
(:func:`chuteflow.dns.packet.simulate_pulse`), its growth along rays measured between two
times (:func:`chuteflow.dns.packet.ray_growth`).
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

from chuteflow import ChuteModel
from chuteflow.dns.packet import ray_growth, simulate_pulse
from chuteflow.spatial import absolute_instability, spatial_dispersion
from chuteflow.steady import solve_steady

flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
disp = spatial_dispersion(flow, num=16)
res = absolute_instability(flow)
print(
    f"most amplified: omega = {disp.attrs['omega_max']:.4f}, -Im k = {disp.attrs['spatial_growth_max']:.3e} "
    f"(cut-off omega_c = {disp.attrs['omega_c']:.4f})"
)
print(f"{res.verdict}: V- = {res.v_minus:.4f}, V+ = {res.v_plus:.4f}, fastest ray {res.v_peak:.3f}")

# %%
# The impulse response on the simulation: a 1e-6 bump of width 150 in ln ν, in the frame
# moving at (V− + V+)/2 so that the packet stays in the middle of the domain
# (L = 30000, N = 32, 128 Fourier modes, 150 steps: the linear phase is one chord step a
# step). σ(V) between t = 1500 and 3000, with the ½ ln 2/1500 of the saddle's t^{-1/2}.
frame = 0.5 * (res.v_minus + res.v_plus)
with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # the bump's own tail at the highest modes, decaying
    ds = simulate_pulse(
        flow, 30000.0, time=3000.0, width=150.0, frame_speed=frame, n=32, modes=128, dt=20.0, record_every=5
    )
V = np.linspace(3.0, 10.5, 301)
meas = ray_growth(
    ds["x"].values, ds["time"].values, ds["rho_bar"].values, V,
    t1=1500.0, t2=3000.0, x0=ds.attrs["pulse_centre"], frame=frame,
)  # fmt: skip
print(f"simulation: V- = {meas.v_minus:.3f}, V+ = {meas.v_plus:.4f}, peak growth {meas.growth_peak:.4e}")

# %%
# (a) The spatial growth of inlet forcing; (b) the growth along rays, the saddle points'
# and the simulation's; (c) the packet in space–time (the envelope of δρ̄ on a log scale)
# with the rays V−, V+. The lower edge is the kinematic-wave speed dQ0/dρ̄0, where σ(V)
# touches zero: the simulation reaches it only slowly (like 1/t). Beyond V+ the measured
# decay levels off where the packet's tail meets the floor of the envelope (≈ 1e-8.5 in
# (c): the analytic signal of the bump's net mass, docs/spatial.md); between the edges
# σ(V) follows the saddle points to the finite-time error (here +3 % at the peak, falling
# like 1/(t1 t2)).
fig, (ax, bx, cx) = plt.subplots(1, 3, figsize=(13, 3.8), layout="constrained")
ax.plot(disp["omega"], disp["spatial_growth"], "o-", ms=3)
ax.axvline(disp.attrs["omega_max"], color="0.6", ls=":")
ax.axhline(0, color="k", lw=0.5)
ax.set_xlabel("ω")
ax.set_ylabel("−Im k(ω)")
ax.set_title("(a) inlet forcing")
Vr, sr = res.rays[0], res.rays[1]
bx.plot(Vr, sr, "o-", ms=3, label="saddle points")
bx.plot(V, meas.growth, label="simulation, t = 1500 → 3000")
for v in (res.v_minus, res.v_plus):
    bx.axvline(v, color="0.6", ls=":")
bx.axhline(0, color="k", lw=0.5)
bx.set_ylim(-4e-4, 1.4e-3)
bx.set_xlabel("V")
bx.set_ylabel("σ(V)")
bx.set_title(f"(b) rays: {res.verdict}")
bx.legend(fontsize=8)
rho = ds["rho_bar"].values
# the envelope: |analytic signal| (the modes k > 0 of δρ̄, doubled)
spec = np.fft.fft(rho - rho.mean(axis=1, keepdims=True), axis=1)
env = np.abs(np.fft.ifft(spec * 2 * (np.fft.fftfreq(rho.shape[1]) > 0), axis=1))
x_lab = ds["x"].values[None, :] + frame * ds["time"].values[:, None] - ds.attrs["pulse_centre"]
t_grid = np.broadcast_to(ds["time"].values[:, None], x_lab.shape)
pm = cx.pcolormesh(x_lab, t_grid, np.log10(env + 1e-16), shading="nearest", vmin=-10)
t_end = ds["time"].values[-1]
for v in (res.v_minus, res.v_plus):
    cx.plot([0, v * t_end], [0, t_end], "w--", lw=1)
fig.colorbar(pm, ax=cx, label="log10 |envelope of δρ̄|")
cx.set_xlabel("x − x0 (lab)")
cx.set_ylabel("t")
cx.set_title("(c) the packet and the rays V−, V+")
plt.show()
