"""
Another radial distribution function
====================================

The paper uses the Lun–Savage g0(ν) = (1 − ν/ν_m)^(−2.5 ν_m), which diverges at maximum
packing ν_m = 0.6 (§2.1). The Carnahan–Starling form g0 = (2 − ν)/(2(1 − ν)³) is also
registered (``radial="carnahan_starling"``); a closure is chosen by name in
:class:`~chuteflow.closures.ChuteModel`, and every derivative the equations need is
derived from its one sympy expression (see :doc:`../extending` for adding one). How much
does the choice matter at P1?
"""

import matplotlib.pyplot as plt
import numpy as np

from chuteflow import ChuteModel, solve_steady
from chuteflow.closures import RADIALS
from chuteflow.stability import least_stable

print("registered radial distributions:", RADIALS.names())
models = {name: ChuteModel(roughness=0.05, radial=name) for name in ("lun_savage", "carnahan_starling")}

nu = np.linspace(0, 0.58, 300)
fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
for name, model in models.items():
    g0, _, _ = model.g0(nu)
    a.semilogy(nu, g0, label=name)
a.set(xlabel="ν", ylabel="g0(ν)", title="radial distribution at contact")
a.legend()

# %%
# The steady flow and its least-stable mode at k = 0.002 with either closure. P1 is
# dilute (ν̄ ≈ 0.014), where the two g0 nearly agree, so the flows differ little.
for ls, (name, model) in zip(("-", "--"), models.items()):
    flow = solve_steady(theta=16, nu0=0.05, model=model)
    mode = least_stable(flow, 0.002)
    print(
        f"{name:>18}: h = {flow.h:.3f}, Q0 = {flow.Q:.4f}, alpha(k=0.002) = {mode.alpha:.5g} "
        f"(physical: {mode.physical})"
    )
    y = np.linspace(0, 40, 300)
    b.plot(flow.profiles(y)["nu"], y, ls, label=name)
b.set(xlabel="ν0", ylabel="y", title="P1: density profiles")
b.legend()
