"""
Every attractor: a census with basin fractions
==============================================

The system is multistable, so a diagram computed from one initial state shows
where that state settles. :func:`stickslip_fast.census` runs many starts at
every value (the zero state and random ones in a physical box), groups the runs
into attractors, gives each its basin fraction and follows the attractors over
the parameter as tracks. A small census: 10 values of η, 12 starts each.
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

eta = np.linspace(5.0, 9.5, 10)
res = ssf.census(ssf.System.preset("asymmetric"), "eta", eta, n_starts=12, t_end=3000,
                 stop="converged", seed=1, progress=False)  # fmt: skip
for a in res.attractors[-1]:
    print(f"track {a.id}: {a.kind}, period {a.period}, basin {a.fraction:.2f}")

# %%
# ``res.fractions()`` is the basin fraction of every track at every value
# (values × tracks);
# ``res.labels`` the track each start reached. Below: each track's Poincaré
# points of x₁ (marker size by basin), and the fractions stacked.

frac = res.fractions()
fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, layout="constrained",
                               height_ratios=(3, 2))  # fmt: skip
for i, atts in enumerate(res.attractors):
    for a in atts:
        x1 = a.points[:, 0]  # an equilibrium: its one state
        ax0.scatter(np.full(len(x1), eta[i]), x1, s=8 + 60 * a.fraction,
                    color=f"C{a.id % 10}", alpha=0.8)  # fmt: skip
ax0.set(ylabel="x₁ at the minima of x₁", title="attractors (colour: track)")
ax1.stackplot(eta, frac.T, colors=[f"C{k % 10}" for k in range(frac.shape[1])])
ax1.set(xlabel="η", ylabel="basin fraction", ylim=(0, 1))
plt.show()
