"""
A sweep on a Dask cluster
=========================

``backend="dask"`` runs the same sweep on a Dask cluster: an existing one
(``scheduler="tcp://host:8786"``) or a local one it starts (``n_workers=4``).
The result is the same bit for bit as on the local backend, and only the
calling process writes the result file. Here a cluster of one in-process worker
(``processes=False``), which needs no new Python processes; on real machines
the workers are ``dask worker`` processes (:doc:`/distributed`).
"""

import numpy as np
from dask.distributed import LocalCluster

import stickslip_fast as ssf

system = ssf.System.preset("asymmetric")
eta = np.linspace(1, 10, 16)
with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                  dashboard_address=":0") as cluster:  # fmt: skip
    on_dask = ssf.sweep(system, "eta", eta, t_end=3000, stop="converged", backend="dask",
                        scheduler=cluster.scheduler_address, progress=False)  # fmt: skip

local = ssf.sweep(system, "eta", eta, t_end=3000, stop="converged", progress=False)

# %%
# The two results are identical, point for point:

same = np.array_equal(on_dask.points, local.points, equal_nan=True)
print("periods:", on_dask.period)
print("bit-identical to the local backend:", same)
