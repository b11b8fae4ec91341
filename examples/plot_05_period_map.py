"""
A two-parameter period map
==========================

A sweep over two parameters, here η (static/kinetic friction ratio) and the
spring coupling k₁₂, gives a period at every grid point. This is a coarse
16 × 10 version of the 1000 × 1000 map the GPU backend computes in under two
minutes (``backend="cuda"``, see :doc:`/gpu`).
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

eta = np.linspace(1, 10, 16)
k12 = np.linspace(-0.9, 0.9, 10)
pmap = ssf.sweep(ssf.System.preset("asymmetric"), ("eta", "k12"), (eta, k12), t_end=3000,
                 stop="converged", progress=False)  # fmt: skip
print(pmap.period.shape, pmap.summary())

# %%
# Values without an orbit (steady sliding, mostly) are shown in grey.

period = np.where(pmap.status == "ok", pmap.period, np.nan).astype(float)
fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
ax.set_facecolor("0.85")
m = ax.pcolormesh(eta, k12, period.T, cmap="viridis", shading="nearest")
fig.colorbar(m, ax=ax, label="period")
ax.set(xlabel="η", ylabel="k₁₂")
plt.show()
