"""
Flux–density curves
===================

Along a family of steady flows at fixed θ (the floor density ν0(0) varies), the flux
Q0 = ∫ν0 u0 dy and the one-dimensional density ρ̄0 = ∫ν0 dy (eq. (3.15)) trace a curve
Q0(ρ̄0). Its slope dQ0/dρ̄0 is the speed of kinematic waves (§5.1.1, Appendix B). At
θ = 14° the flux grows with the density; at θ = 16° it has a minimum (figure 2(b)).
:func:`~chuteflow.steady.steady_family` computes the slope exactly, from the tangent of
the family (``dQ_drho``), not by finite differences.
"""

import matplotlib.pyplot as plt
import numpy as np

from chuteflow import ChuteModel
from chuteflow.figures.steady import plot_flux_density
from chuteflow.steady import steady_family

model = ChuteModel(roughness=0.05)
nu0 = np.geomspace(0.012, 0.3, 14)
families = {theta: steady_family(theta, nu0, model) for theta in (14.0, 16.0)}
for theta, fam in families.items():
    ok = fam.status == "ok"
    print(
        f"theta = {theta}: {int(ok.sum())} of {fam.sizes['nu0']} flows, "
        f"dQ0/drho in [{float(fam.dQ_drho.where(ok).min()):.3f}, {float(fam.dQ_drho.where(ok).max()):.3f}]"
    )

fig, ax = plt.subplots(figsize=(5.5, 4), layout="constrained")
plot_flux_density(list(families.values()), ax)
