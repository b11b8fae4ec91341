"""
Where the period-1 orbit ends: a fold curve, and a walk past the fold
======================================================================

The period-1 orbit of Fig. 6 exists between two folds in η, and both folds move
with the spring asymmetry k₁₂. Near k₁₂ = −0.8316 the stable period-1 orbit
lives only between a lower fold at η ≈ 2.571 and an upper one at η ≈ 2.667.
:func:`stickslip_fast.continue_bifurcation` follows such a fold in the second
parameter: here from the lower fold, down through the smallest k₁₂ at which the
two folds exist (an "extremum" of the curve: below it, the period-1 orbit is
gone), and back up to k₁₂ = −0.8316 on the upper fold. The fold is sharp, so
the curve takes a smaller difference step ``h`` for its test function and a
smaller tolerance than the defaults: with ``h = 1e-7`` it stalls 0.02–0.04 short
of the extremum (:doc:`/orbits`; ``scripts/fold_curves_eta_k12.py closing``
writes the same curve to ``data/curves/``).
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

# a point near the stable period-1 orbit at eta = 2.6, k12 = -0.8316, on the section
z = np.array([0.11834572437245043, 0.0, 0.1459190815849308, -0.008125583378266665])
s = ssf.System.preset("asymmetric", eta=2.6, k12=-0.8316)
orbit = ssf.find_orbit(s, z, 1)
down = ssf.continue_orbit(orbit, "eta", (2.4, 2.6), ds=1e-3, ds_max=5e-3, direction=-1,
                          stick_events=False, progress=False)  # fmt: skip
fold = next(b for b in down.bifurcations if b.kind == "fold")
print(f"lower fold at eta = {fold.value:.10f}")

curve = ssf.continue_bifurcation(down, fold, "k12", (-0.95, -0.8316), direction=-1, ds=0.005,
                                 ds_max=0.05, max_points=100, tol=1e-9, h=1e-9,
                                 progress=False)  # fmt: skip
print(
    f"{len(curve.values)} points, status {curve.status!r}, ends at (eta, k12) = "
    f"({curve.values[-1, 0]:.8f}, {curve.values[-1, 1]:.6f})"
)

# %%
# ``curve.values`` holds (η, k₁₂) at every point; ``curve.codim2`` the points of
# codimension two it met, here the extremum in k₁₂ where the two folds meet.

extremum = next(p for p in curve.codim2 if p.kind == "extremum")
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
ax.plot(curve.values[:, 0], curve.values[:, 1], ".-", ms=3, label="fold of the period-1 orbit")
ax.plot(*extremum.values, "C3o", label="extremum: the two folds meet")
ax.set(xlabel="η", ylabel="k₁₂", title="the period-1 region closes")
ax.legend(loc="upper center")
plt.show()

# %%
# Past a sharp fold single shooting stops
# ---------------------------------------
# On the unstable side of a fold the orbit's leading multiplier μ grows by a
# factor of ten per ~2e-5 in η. The return map of one whole period then amplifies
# rounding beyond Newton's reach, and single shooting ends with status
# "precision-limit" at μ of a few thousand (docs/limits.md). ``shooting="auto"``
# goes on from there by multiple shooting: the period is cut into segments, each
# amplifying little, and ``remesh=True`` cuts them again as the orbit changes. Here
# the upper fold of the paper's set (k₁₂ = −0.8), from the stable orbit just below
# it, up through the fold and along the unstable side:

z_up = np.array([0.07259589657661687, 0.0, 0.1221705830435874, -0.006666575275298541])
s_up = ssf.System.preset("asymmetric", eta=3.323525498113908)
stable = ssf.find_orbit(s_up, z_up)
far = ssf.continue_orbit(stable, "eta", (3.3, 3.33), ds=1e-5, ds_max=1e-4, max_points=140,
                         shooting="auto", remesh=True, progress=False)  # fmt: skip
print(far.status)
mu = np.abs(far.multipliers[:, 0])
by_ms = np.array([seg is not None for seg in far.segments])
print(
    f"single shooting: {np.sum(~by_ms)} points to mu = {mu[~by_ms].max():.3g}; "
    f"multiple shooting: {np.sum(by_ms)} more, to mu = {mu[by_ms].max():.3g}"
)

eta_fold = next(b.value for b in far.bifurcations if b.kind == "fold")
d_eta = (far.values - eta_fold) * 1e5
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
ax.semilogy(d_eta[~by_ms], mu[~by_ms], ".", ms=4, label="single shooting")
ax.semilogy(d_eta[by_ms], mu[by_ms], ".", ms=4, label="multiple shooting")
ax.axvline(0.0, color="k", ls=":", lw=0.8)
ax.set(xlabel=f"(η − {eta_fold:.10f}) × 1e5, the fold at 0", ylabel="leading |multiplier| μ",
       title="the stable side (μ < 1) and the unstable side of the upper fold")  # fmt: skip
ax.legend()
plt.show()
