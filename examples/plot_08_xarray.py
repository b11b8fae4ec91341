"""
Reading a result file with xarray
=================================

A sweep with ``out=`` streams its results into an HDF5 file (resumable: the
same call on the same file continues an interrupted sweep). The file has named
dimensions, so :mod:`xarray` opens it as a labelled dataset, and collaborators
can read it without stickslip_fast (:doc:`/file-format` describes every
dataset and attribute). Reading it needs ``pip install xarray h5netcdf``.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

import stickslip_fast as ssf

tmp = Path(tempfile.mkdtemp())
ssf.sweep(ssf.System.preset("asymmetric"), "eta", np.linspace(5, 10, 30), t_end=3000,
          stop="converged", out=tmp / "fig06.h5", progress=False)  # fmt: skip

ds = xr.open_dataset(tmp / "fig06.h5", engine="h5netcdf")
print(ds)

# %%
# The root attributes record what made the file: the package version, the
# full configuration (JSON) and the progress of the sweep.

attrs = ds.attrs
print("written by stickslip_fast", attrs["package_version"], "- schema", attrs["schema_version"])

# %%
# Labelled selection and plotting work as on any xarray dataset:

fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(7, 5), sharex=True, layout="constrained")
x1 = ds.points.sel(state="x1")
ax0.plot(np.repeat(ds.eta.values, x1.sizes["point"]), x1.values.ravel(), ".k", ms=2)
ax0.set(ylabel="x₁ at the minima of x₁")
ds.period.plot.step(ax=ax1, where="mid")
plt.show()
ds.close()
