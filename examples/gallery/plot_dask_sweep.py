"""
A sweep on a Dask cluster
=========================

:func:`~chuteflow.sweep.run_sweep` runs the tasks of a sweep (rows of the θ grid, cut into
chunks of ν0(0)) on local processes by default; with ``client=`` it submits them to a Dask
cluster instead, and with ``scheduler="tcp://host:8786"`` it connects to a running one.
The result is the same Dataset either way, and finished tasks are saved as they arrive,
so an interrupted run resumes. Here a tiny in-process ``LocalCluster`` (install the extra
``chuteflow[dask]``); on a real cluster, the same code with ``distributed.Client(address)``.
"""

import tempfile
from pathlib import Path

from dask.distributed import Client, LocalCluster

from chuteflow.sweep import Sweep, SweepConfig

config = SweepConfig(
    theta=(15.0, 16.0), nu0=(0.04, 0.05, 0.06), roughness=0.05, chunk=2, metrics=("steady", "kinematic")
)
out = Path(tempfile.mkdtemp()) / "dask.nc"
with (
    LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster,
    Client(cluster) as client,
):
    sweep = Sweep(config, out)
    ds = sweep.run(client=client)
print(sweep.stats)
print(ds.dQ_drho.to_pandas().round(4))

# %%
# Running it again finds every task saved and computes nothing:
again = Sweep(config, out)
again.run(workers=1)
print("computed:", again.stats.computed, " reused:", again.stats.reused)
