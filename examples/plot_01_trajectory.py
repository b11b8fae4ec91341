"""
A trajectory and its Poincaré points
====================================

One disk on a constant-speed belt (the paper's asymmetric parameter set at
η = 9.99). :func:`stickslip_fast.simulate` integrates the stiff model with the
Rosenbrock method Rodas5P and records the state at every local minimum of x₁
(the Poincaré section ẋ₁ = 0, crossed upwards). ``sample_dt`` also samples the
trajectory on a uniform time grid, for the phase portrait.
"""

import matplotlib.pyplot as plt

import stickslip_fast as ssf

system = ssf.System.preset("asymmetric", eta=9.99)
res = ssf.simulate(system, t_end=2600, t_transient=2000, sample_dt=0.05)
print(res.status, "period", res.period, "-", len(res.poincare), "Poincaré points")
print(res.state_names)

# %%
# The period is the number of distinct Poincaré points the orbit cycles
# through: here two, so the orbit closes after two turns in the (x₁, ẋ₁) plane.

x1, dx1 = res.y[:, 0], res.y[:, 1]
fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9, 3.6), layout="constrained")
ax0.plot(res.t, x1, lw=0.8)
ax0.plot(res.t_poincare, res.poincare[:, 0], "o", ms=4, color="C3", label="Poincaré points")
ax0.set(xlabel="t", ylabel="x₁", xlim=(res.t[0], res.t[0] + 150))
ax0.legend(loc="upper right")
ax1.plot(x1, dx1, lw=0.6)
ax1.plot(res.poincare[:, 0], res.poincare[:, 1], "o", ms=5, color="C3")
ax1.set(xlabel="x₁", ylabel="ẋ₁", title=f"η = {system.eta}, period {res.period}")
plt.show()
