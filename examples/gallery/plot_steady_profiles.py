"""
Steady profiles
===============

Steady flows at θ = 16°, φ = 0.05 for increasing floor density ν0(0), as in figure 3 of
the paper: dilute flows decay monotonically from the floor; at ν0(0) = 0.15 the density
maximum lifts off the floor, above a hot, dilute, fast-sheared layer.
"""

import matplotlib.pyplot as plt

from chuteflow import ChuteModel, solve_steady
from chuteflow.figures.steady import plot_profiles

model = ChuteModel(roughness=0.05)
flows = [solve_steady(theta=16, nu0=nu0, model=model) for nu0 in (0.04, 0.05, 0.08, 0.1, 0.15)]
for f in flows:
    peak = "monotonic" if f.monotonic else f"maximum {f.nu_peak:.3f} at y = {f.y_peak:.2f}"
    print(f"nu0(0) = {f.nu0:<5}  h = {f.h:7.3f}  mean density = {f.nu_mean:.4f}  {peak}")

fig, axes = plt.subplots(1, 3, figsize=(10, 3.6), layout="constrained")
plot_profiles(flows, axes, y_max=40)
