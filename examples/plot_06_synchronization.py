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
