"""
The bifurcation diagram of Fig. 6
=================================

:func:`stickslip_fast.sweep` runs one simulation per parameter value, in
parallel on all cores, and keeps each value's Poincaré points. This is the
paper's Fig. 6 (asymmetric springs, constant belt) on a coarse grid of 60
values of η; the full figure uses 1000 values
(``stickslip-fast sweep data/fig06_asymmetric_constant.toml``).

``stop="converged"`` ends each run as soon as its Poincaré points repeat (or it
has come to rest), with ``t_end`` as the cap: several times faster than
integrating every value over a fixed window, with the same status and period on
this diagram.
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

eta = np.linspace(1, 10, 60)
diag = ssf.sweep(ssf.System.preset("asymmetric"), "eta", eta, t_end=3000, stop="converged",
                 progress=False)  # fmt: skip
print(diag.summary())

# %%
# ``diag.points`` holds every value's points, NaN-padded to a common length;
# ``diag.period`` the period found (0 for none within the recorded points), and
# ``diag.status`` why a value gave no orbit (``"equilibrium"``: steady sliding,
# the disk at rest while the belt slips under it).

x1 = diag.points[:, :, 0]
fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 5), sharex=True, layout="constrained",
                               height_ratios=(3, 1))  # fmt: skip
ax0.plot(np.repeat(eta, x1.shape[1]), x1.ravel(), ".k", ms=1.5)
ax0.set(ylabel="x₁ at the minima of x₁")
ax1.step(eta, diag.period, where="mid")
ax1.set(xlabel="η", ylabel="period")
plt.show()
