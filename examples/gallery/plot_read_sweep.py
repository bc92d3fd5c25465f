"""
Reading a saved sweep with xarray
=================================

A sweep writes one NetCDF file (and, while it runs, a ``.parts`` folder of finished tasks,
so an interrupted sweep resumes where it stopped). The file is an ordinary
:class:`xarray.Dataset` over (θ, ν0(0)) with units and sources on every variable and the
model in its attributes; ``ds.chute`` adds chuteflow's operations to it.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import xarray as xr

from chuteflow.sweep import SweepConfig, load_sweep, run_sweep

out = Path(tempfile.mkdtemp()) / "phi005.nc"
config = SweepConfig(
    theta=(15.0, 16.0, 17.0), nu0=(0.03, 0.05, 0.08, 0.12), roughness=0.05, metrics=("steady", "kinematic")
)
run_sweep(config, out, workers=1)

# %%
# Plain xarray reads it (``load_sweep`` does the same and checks the file):
ds = xr.open_dataset(out)
print(ds)
print(ds.Q.attrs)

# %%
# The model it was computed with, and a selection:
ds = load_sweep(out)
print(ds.chute.model)
row = ds.sel(theta=16.0)
print(row[["h", "nu_mean", "Q", "dQ_drho"]].to_dataframe().round(4))

fig, ax = plt.subplots(figsize=(5.5, 4), layout="constrained")
for theta in ds.theta.values:
    r = ds.sel(theta=theta)
    ax.plot(r.rho_bar, r.Q, "o-", label=f"θ = {theta:g}°")
ax.set(xlabel="ρ̄0", ylabel="Q0", title="flux–density from the saved sweep")
ax.legend()
