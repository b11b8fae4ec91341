"""
The largest Lyapunov exponent
=============================

:func:`stickslip_fast.largest_lyapunov` integrates the state together with a
tangent vector (the variational equations with the analytic Jacobian, by the
same compiled Rosenbrock method) and averages the tangent's log growth
(Benettin's algorithm). A periodic orbit gives an exponent that tends to zero
(the direction along the flow neither grows nor shrinks); chaos would give a
positive one. The literature parameter set at η = 2.7 (the paper's Fig. 3,
period 11):
"""

import matplotlib.pyplot as plt

import stickslip_fast as ssf

system = ssf.System.preset("literature", eta=2.7)
lyap = ssf.largest_lyapunov(system, t_end=3000, t_transient=1000)
print(lyap)

# %%
# ``lyap.convergence`` holds the running estimate, (time, exponent) pairs:
# the estimate decays like 1/t towards zero.

t, est = lyap.convergence[:, 0], lyap.convergence[:, 1]
fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
ax.plot(t, est)
ax.axhline(0, color="k", lw=0.8)
ax.set(xlabel="t", ylabel="running estimate of λ₁",
       title=f"λ₁ = {lyap.exponent:.2e} (fit {lyap.exponent_fit:.2e})")  # fmt: skip
plt.show()
