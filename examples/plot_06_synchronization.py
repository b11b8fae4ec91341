"""
Two disks on one DC motor: synchronization
==========================================

With ``drive="dc-motor"`` the belts of all disks are driven by one DC motor,
whose speed is an extra state variable: the disks interact through the belt.
Here two disks of the asymmetric set at η = 2 and η = 8, from the paper's
initial state. :func:`stickslip_fast.phases_from_events` assigns each disk a
phase from its own minima of x and classifies the pair as in-phase, anti-phase
or desynchronized; :func:`stickslip_fast.sync_error` measures the distance
between the two disks at the Poincaré points.
"""

import matplotlib.pyplot as plt

import stickslip_fast as ssf

y0 = [0, 0, 0, 0, 0.01, 0.01, 0.01, 0.01, 0]  # x1, dx1, phi1, dphi1, x2, ..., vb
fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=False, layout="constrained")
for ax, eta in zip(axes, (2.0, 8.0)):
    two = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2, eta=eta)
    res = ssf.simulate(two, 3000, 2000, y0=y0, sample_dt=0.05)
    sync = ssf.phases_from_events(res.t, res.y, 2)
    err = ssf.sync_error(res.poincare, 2)
    print(f"eta {eta}: {res.status}, period {res.period}, {sync.classification}, "
          f"sync error {err:.3g}")  # fmt: skip
    i1, i2 = res.state_names.index("x1"), res.state_names.index("x2")
    ax.plot(res.t, res.y[:, i1], lw=0.9, label="x₁")
    ax.plot(res.t, res.y[:, i2], lw=0.9, label="x₂")
    ax.set(xlim=(res.t[0], res.t[0] + 200), ylabel="x",
           title=f"η = {eta}: {sync.classification}")  # fmt: skip
    ax.legend(loc="upper right")
axes[-1].set_xlabel("t")
plt.show()

# %%
# Stability across the disks
# --------------------------
# Disks started alike stay alike, so an in-phase orbit can be found from rest. Its
# Floquet multipliers split (:func:`stickslip_fast.sync_stability`) into those
# inside the in-phase subspace (one disk on the same motor) and the *transverse*
# ones, which decide whether a small difference between the disks dies out. They
# are the same for any number of disks. :func:`stickslip_fast.continue_orbit`
# follows the in-phase orbit of the symmetric set and marks where a transverse
# multiplier passes +1 ("SB", a symmetry-breaking pitchfork): beyond it the
# in-phase orbit is unstable across the disks.

import warnings  # noqa: E402

import numpy as np  # noqa: E402

sym = ssf.System.preset("symmetric", drive="dc-motor", n_oscillators=2, eta=3.0)
with warnings.catch_warnings():  # from rest, on purpose: the in-phase orbit
    warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
    orbit = ssf.find_orbit(sym, ssf.simulate(sym, 3000, 2000))
print(ssf.sync_stability(orbit))
branch = ssf.continue_orbit(orbit, "eta", (3.0, 5.5))
print(branch.summary())

transverse = [ssf.sync_stability(branch.orbit_at(i)).transverse[0].real
              for i in range(0, len(branch.values), 4)]  # fmt: skip
fig, ax = plt.subplots(figsize=(7, 3.2), layout="constrained")
ax.plot(branch.values[::4], transverse, ".-", label="leading transverse multiplier")
ax.axhline(1.0, color="k", lw=0.8)
for b in branch.bifurcations:
    ax.axvline(b.value, color="C3", ls="--", lw=0.8)
    ax.annotate(f"{b.label} η = {b.value:.5f}", (b.value, 1.0), xytext=(5, -30),
                textcoords="offset points", color="C3")  # fmt: skip
ax.set(xlabel="η", ylabel="μ", title="in-phase orbit of two disks (symmetric set)")
ax.legend(loc="upper left")
plt.show()
print(np.round(transverse, 4))

# %%
# At the SB point a pair of stable orbits with the disks slightly apart branches off
# (one is the other with the disks swapped). :func:`stickslip_fast.switch_branch`
# starts one of them along the transverse eigenvector; continued, the difference
# between the disks grows like the square root of η − η_SB (a supercritical
# pitchfork). At disk 1's minimum of x (ẋ₁ = 0) disk 2's velocity measures it.

(sb,) = [b for b in branch.bifurcations if b.kind == "symmetry-breaking"]
apart = ssf.switch_branch(branch, sb)
lagged = ssf.continue_orbit(apart, "eta", (apart.system.eta, 5.5))
gap = np.abs(lagged.points[:, sym.state_names.index("dx2")])
fig, ax = plt.subplots(figsize=(7, 3.2), layout="constrained")
ax.plot(lagged.values, gap, ".-", label="orbits with the disks apart")
ax.plot(lagged.values, gap[-1] * np.sqrt((lagged.values - sb.value) / (5.5 - sb.value)),
        "k:", label="√(η − η_SB), scaled")  # fmt: skip
ax.set(xlabel="η", ylabel="|ẋ₂| at the minimum of x₁", title="past the SB point")
ax.legend(loc="upper left")
plt.show()
