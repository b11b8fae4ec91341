"""
Hysteresis: sweeping up and down
================================

In ``mode="continuation-both"`` a sweep follows the parameter up and then down,
each value starting from where the previous one ended, so an attractor is kept
for as long as it exists. Where the two directions disagree the system is
bistable: here the stick-slip orbit and steady sliding of the asymmetric set on
η ∈ [1, 4] (the paper's "simple periodic" segments; see :doc:`/reproduction`).
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

eta = np.linspace(1, 4, 40)
hyst = ssf.sweep(ssf.System.preset("asymmetric"), "eta", eta, t_end=3000, stop="converged",
                 mode="continuation-both", progress=False)  # fmt: skip
print(hyst.status.shape)  # (2, 40): [0] up, [1] down

# %%
# Each direction's diagram: x₁ at the Poincaré points where the disk
# oscillates, and x₁ of the rest state (crosses) where it slides steadily.

fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), sharey=True, layout="constrained")
for k, (ax, label) in enumerate(zip(axes, ("η going up", "η going down"))):
    x1 = hyst.points[k, :, :, 0]
    ax.plot(np.repeat(eta, x1.shape[1]), x1.ravel(), ".k", ms=2)
    rest = hyst.status[k] == "equilibrium"
    ax.plot(eta[rest], hyst.final_state[k, rest, 0], "x", color="C3", ms=4)
    ax.set(xlabel="η", title=label)
axes[0].set_ylabel("x₁")
plt.show()
