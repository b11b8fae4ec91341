"""
Hysteresis: sweeping up and down
================================

In ``mode="continuation-both"`` a sweep follows the parameter up and then down,
each value starting from where the previous one ended, so an attractor is kept
for as long as it exists. Here the asymmetric set on η ∈ [1.9, 3.6], where the
period-1 stick-slip orbit and steady sliding (the disk at rest, the belt
slipping under it) coexist. Going up from the orbit at η = 1.9, the sweep stays
on it beyond where a restart from rest already slides; going down it stays on
steady sliding, which is stable over the whole range (see :doc:`/reproduction`).
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

system = ssf.System.preset("asymmetric")
start = ssf.simulate(system.replace(eta=2.0), 3000, stop="converged").final_state  # on the orbit
eta = np.linspace(1.9, 3.6, 35)
hyst = ssf.sweep(system, "eta", eta, t_end=3000, stop="converged", y0=start,
                 mode="continuation-both", progress=False)  # fmt: skip
rest = ssf.sweep(system, "eta", eta, t_end=3000, stop="converged", progress=False)
print(hyst.status.shape)  # (2, 35): [0] up, [1] down
print("last orbit going up: eta =", eta[hyst.status[0] == "ok"].max())
print("last orbit from rest: eta =", eta[rest.status == "ok"].max())

# %%
# x₁ at the Poincaré points where the disk oscillates, and x₁ of the rest state
# (crosses) where it slides steadily:

runs = [("restart from rest", rest.points, rest.status, rest.final_state)]
runs += [(label, hyst.points[k], hyst.status[k], hyst.final_state[k])
         for k, label in enumerate(("continuation, η up", "continuation, η down"))]  # fmt: skip
fig, axes = plt.subplots(1, 3, figsize=(10, 3.4), sharey=True, layout="constrained")
for ax, (label, points, status, final) in zip(axes, runs):
    x1 = points[:, :, 0]
    ax.plot(np.repeat(eta, x1.shape[1]), x1.ravel(), ".k", ms=2)
    sliding = status == "equilibrium"
    ax.plot(eta[sliding], final[sliding, 0], "x", color="C3", ms=4)
    ax.set(xlabel="η", title=label)
axes[0].set_ylabel("x₁")
plt.show()
