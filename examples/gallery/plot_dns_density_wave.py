"""
A density wave of the full equations, from noise to saturation
===============================================================

:class:`~chuteflow.dns.DnsSimulation` integrates the time-dependent equations (2.1)–(2.3) on
a slope periodic in x, starting from a :class:`~chuteflow.steady.SteadyFlow`. At P1
(θ = 16°, ν0(0) = 0.05, roughness φ = 0.05) the uniform flow is unstable for L = 1000
(L_c ≈ 882): small noise in the density grows into one density wave that travels down the
slope and saturates. The trackers of :mod:`chuteflow.trackers` — the same as those of the 1D
model's :class:`~chuteflow.reduced.WaveSimulation` — watch the run: here a
:class:`~chuteflow.trackers.SaturationStop` ends it once the amplitude has settled and a
:class:`~chuteflow.trackers.ResolutionMonitor` records how much the highest modes carry.

The grid is deliberately coarse (nx = 7 Fourier unknowns, N = 24, Δt = 25) so that this
page builds in seconds: the wave's crest is steeper than nx = 7 resolves (the monitor says
so), and its amplitude, about −26 … +33 % in ρ̄, overshoots the resolved one (−23 … +29 % at
nx = 65, N = 80; docs/dns.md). ``chuteflow waves`` maps such runs over flows.
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

from chuteflow import ChuteModel
from chuteflow.dns import DnsSimulation
from chuteflow.steady import solve_steady
from chuteflow.trackers import ResolutionMonitor, ResolutionWarning, SaturationStop

flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
sim = DnsSimulation(
    flow,
    1000.0,
    time=30000.0,
    dt=25.0,
    modes=3,
    n=24,
    init="noise",
    amplitude=1e-2,
    snapshots=6,
    record_every=4,
)
print(f"linear theory at k = 2π/L: Re α = {sim.mode.alpha.real:.3g}, c = {sim.mode.wave_speed:.4g}")
stop = SaturationStop(0.05, interval=150.0, min_samples=20)
monitor = ResolutionMonitor(1e-4)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", ResolutionWarning)  # reported below
    warnings.simplefilter("ignore", RuntimeWarning)
    state = sim.run([stop, monitor])
ds = sim.dataset(state)
a = ds.attrs
print(
    f"{a['status']} at t = {a['time_end']:.0f}: {a['verdict']}, ρ̄ {100 * a['rho_min_rel']:+.1f} … "
    f"{100 * a['rho_max_rel']:+.1f} %, wave speed {a['wave_speed']:.3f}, wavelength {a['wavelength']:.0f}"
)
print(f"highest modes: x {monitor.x_tail:.1e}, y {monitor.y_tail:.1e} of the largest")
print(f"mass drift {a['mass_drift']:.1e}")

# %%
# The space–time diagram in the frame of the linear wave (ξ = x − c t) and the saturated
# profile, crest at L/2. The wave is asymmetric: a steep front ahead of the crest.
t, x = ds["time"].values, ds["x"].values
rho = ds["rho_bar"].values
rel = rho / rho.mean(axis=1, keepdims=True) - 1
fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
pm = ax.pcolormesh(x, t, rel, shading="nearest", cmap="RdBu_r", vmin=-0.35, vmax=0.35)
fig.colorbar(pm, ax=ax, label="ρ̄/⟨ρ̄⟩ − 1")
ax.set_xlabel(f"ξ = x − {a['frame_speed']:.3f} t")
ax.set_ylabel("t")
end = np.roll(rel[-1], len(x) // 2 - int(np.argmax(rel[-1])))
bx.plot(x, end, "o-")
bx.set_xlabel("ξ (crest at L/2)")
bx.set_ylabel("ρ̄/⟨ρ̄⟩ − 1")
bx.set_title(f"t = {t[-1]:.0f}: {a['verdict']}")
plt.show()
