"""
A small stability diagram
=========================

The paper's stability diagrams (figures 6 and 12) classify every steady flow of a
(θ, ν0(0)) grid by the sign of Re α2, the long-wave growth coefficient. This is the same
computation on a 3 × 3 grid around P1 — enough to see the unstable dilute flows and the
stable denser ones at θ = 16° (P2, P3 of the paper). A full diagram is the same call with
a larger grid, run on several processes or a Dask cluster (see :doc:`../numerics`).
"""

import matplotlib.pyplot as plt
import numpy as np

from chuteflow.figures.diagram import plot_diagram
from chuteflow.sweep import SweepConfig, classify, run_sweep

config = SweepConfig(
    theta=(15.0, 16.0, 17.0),
    nu0=(0.05, 0.08, 0.12),
    roughness=0.05,
    metrics=("steady", "kinematic", "longwave"),
    markers=(("P1", 16.0, 0.05),),
)
ds = classify(run_sweep(config, workers=1))
print(ds[["h", "nu_mean", "alpha2_re", "unstable"]].to_dataframe().round(4))

# %%
# ``unstable`` is 1 where Re α2 > 0; ``regime`` (A, B, C of §4.2) needs dU/dρ̄ (metric
# ``kinematic``). In the (h, ν̄) plane:
fig = plot_diagram(ds, grid_panel=True, title="φ = 0.05, 3 × 3 points")
plt.figure(fig)  # a Figure made by chuteflow.figures, shown through pyplot
print("unstable points:", int(np.nansum(ds.unstable.values == 1)), "of", ds.unstable.size)
