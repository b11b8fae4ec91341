"""
Lyapunov exponents
==================

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

# %%
# The spectrum
# ------------
# :func:`stickslip_fast.lyapunov_spectrum` carries k tangent vectors and keeps them
# orthonormal (Gram-Schmidt, the QR method): exponent j is the growth rate left to
# the j-th vector once the faster ones are taken out. On the period-1 orbit of the
# asymmetric set at η = 2.0 the first two are 0 (along the flow) and log|μ| / T of
# the orbit's Floquet multiplier μ = -0.0969, T = 9.64.
#
# The other two belong to the directions a stick phase locks. There the friction
# slope is of order μ/ε (ε = 1e-5) and the divergence (trace of the Jacobian, in
# ``spec.divergence``) averages about -9000: those exponents are about -2570 and
# -6430, and ``k = 4`` resolves them with steps on their time scale (85 s for
# t = 1300 instead of 0.2 s). Here the two leading ones:

low = ssf.System.preset("asymmetric", eta=2.0)
spec = ssf.lyapunov_spectrum(low, t_end=3000, t_transient=1000, k=2)
print(spec)
print("least-squares fits:", spec.exponents_fit, "Kaplan-Yorke dimension:", spec.kaplan_yorke)

fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
for j, label in enumerate(["λ₁", "λ₂"]):
    ax.plot(spec.convergence[:, 0], spec.convergence[:, 1 + j], label=label)
ax.axhline(0, color="k", lw=0.8)
ax.set(xlabel="t", ylabel="running estimate", title="The two leading exponents at η = 2.0")
ax.legend()
plt.show()
