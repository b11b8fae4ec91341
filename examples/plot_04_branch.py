"""
A periodic orbit, continued, with its Floquet multipliers
=========================================================

A period-1 orbit is a fixed point of the Poincaré return map.
:func:`stickslip_fast.find_orbit` finds it by Newton's method, starting from a
simulation, with the map's Jacobian from the variational equations; its
eigenvalues are the orbit's Floquet multipliers (stable when all lie inside the
unit circle). :func:`stickslip_fast.continue_orbit` then follows the orbit in η
by pseudo-arclength continuation, detecting folds, period-doublings and
Neimark–Sacker points on the way. The stable part of the Fig. 6 period-1
branch, from η = 2 up to just below its fold at η ≈ 3.3237 (where the orbit
turns back unstable; following it there takes the tighter stages described in
:doc:`/limits`):
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

s = ssf.System.preset("asymmetric", eta=2.0)
orbit = ssf.find_orbit(s, ssf.simulate(s, 3000, stop="converged"))
print(orbit)

branch = ssf.continue_orbit(orbit, "eta", (2.0, 3.3), ds=0.05, ds_max=0.1, max_points=60)
print(branch.summary())

# %%
# ``branch.points`` has one row per point of the branch (the orbit's Poincaré
# point with the smallest x₁), ``branch.multipliers`` its multipliers, largest
# modulus first; ``branch.stable`` says whether all lie inside the unit circle, and
# ``branch.bifurcations`` lists what was detected and located.

fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True, layout="constrained")
ax0.plot(branch.values, branch.points[:, 0], ".-")
ax0.set(ylabel="x₁ at the orbit's minimum", title=f"period-{branch.period} branch")
ax1.semilogy(branch.values, np.abs(branch.multipliers), ".-", ms=3)
ax1.axhline(1.0, color="k", lw=0.8)
ax1.set(xlabel="η", ylabel="|Floquet multipliers|")
for b in branch.bifurcations:
    for ax in (ax0, ax1):
        ax.axvline(b.value, color="C3", ls=":")
plt.show()
