"""
Other kinetic theories: κ_h, MFiX's Lun and Garzó–Dufty
=======================================================

The paper uses Lun et al. (1984) without their density-gradient heat flux, q = −κ∇T
(``transport="lun"``). Registered beside it: ``lun_full`` (q = −κ∇T − κ_h∇ν, the paper's
footnote), ``lun_mfix`` (MFiX's ``LUN_1984``: viscosity × (2 + α)/3, α = 1.6) and
``garzo_dufty`` (Garzó & Dufty 1999, first Sonine approximation). Presets name the closure
sets of other codes: ``ChuteModel.preset("mfix-lun")``, ``preset("mfix-gd")``. See
:doc:`../closures` for the formulas and the comparison at the paper's points.
"""

import matplotlib.pyplot as plt
import numpy as np

from chuteflow import ChuteModel, solve_steady
from chuteflow.closures import TRANSPORTS
from chuteflow.longwave import longwave

print("registered transport closures:", TRANSPORTS.names())
models = {
    "lun (paper)": ChuteModel(),
    "lun_full": ChuteModel(transport="lun_full"),
    "mfix-lun": ChuteModel.preset("mfix-lun"),
    "garzo_dufty": ChuteModel(transport="garzo_dufty"),
}

# %%
# The transport coefficients at T = 1 (e_p = 0.7): shear viscosity μ, conductivity κ and
# the coefficient κ_h of ∇ν in the heat flux. Garzó–Dufty's κ_h = T κ0 μ*/ν grows like 1/ν
# in the dilute limit: its heat flux μ∇n = T κ0 μ* ∇ln n stays finite where ν → 0.
nu = np.linspace(0.005, 0.5, 200)
fig, axes = plt.subplots(1, 3, figsize=(11, 3.6), layout="constrained")
for label, model in models.items():
    ev = model.evaluate(nu, np.ones_like(nu))
    for ax, key in zip(axes, ("mu", "kappa", "kappa_h")):
        ax.plot(nu, ev[key][(0, 0)], label=label)
for ax, key in zip(axes, ("μ", "κ", "κ_h")):
    ax.set(xlabel="ν", title=f"{key} at T = 1", yscale="log" if key != "κ_h" else "symlog")
axes[0].legend()

# %%
# The steady flow P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05) and its long-wave coefficients
# α = α1 k + α2 k² (eq. 4.4). With ``garzo_dufty`` there is no steady flow at P1 (the
# solver raises ``NoSteadyFlowError`` after its shooting scan: the heat flux through the
# dilute top drains the layer), so it is left out here.
y = np.linspace(0, 40, 300)
fig, ax = plt.subplots(figsize=(5, 4), layout="constrained")
for label in ("lun (paper)", "lun_full", "mfix-lun"):
    flow = solve_steady(theta=16, nu0=0.05, model=models[label])
    lw = longwave(flow, rtol=0.2, strict=False)
    print(
        f"{label:>12}: h = {flow.h:.3f}, Q0 = {flow.Q:.4f}, Im α1 = {lw.alpha1.imag:.4f}, "
        f"Re α2 = {lw.alpha2.real:.1f} ({'unstable' if lw.unstable else 'stable'})"
    )
    ax.plot(flow.profiles(y)["T"], y, label=label)
ax.set(xlabel="T0", ylabel="y", title="P1: temperature profiles")
ax.legend()
plt.show()
