"""Is a Poincare point's error the interpolant's or the trajectory's? (issue 30, item 2; 2026-11-29)

For each point of a run (asymmetric preset, t 1500, points after 1000, the fair benchmark's
settings) the same run is repeated to end exactly at that point's time, so its last step
lands there (t_final == t): the same steps, then one step to the crossing. The minimum of
x1 from that stepped state (x1 - dx1^2 / (2 ddx1)) is set against the interpolated point,
both against the SciPy Radau rtol 1e-12 reference. Run from the repository root:
``python3 benchmarks/results/point_error_2026-11-29/clip_script.py ETA METHOD``.
"""

# ruff: noqa: E402 - the paths come first
import sys
import warnings

import numpy as np

warnings.simplefilter("ignore")
sys.path.insert(0, ".")
sys.path.insert(0, "tests/reference")
import scipy_model as sm

import stickslip_fast as ssf
from benchmarks.peer_precision import ATOL_FACTOR
from benchmarks.reference import asymmetric_params, trajectory_reference

eta = float(sys.argv[1])
method = sys.argv[2]
ref = trajectory_reference(eta, 1500.0, 1000.0, log=lambda *a: None)
p = asymmetric_params(eta)
tr, pr = np.asarray(ref["t"]), np.asarray(ref["points"])
system = ssf.System.preset("asymmetric", eta=eta)
for rtol in (1e-6, 3e-7, 1e-7):
    kw = dict(method=method, rtol=rtol, atol=ATOL_FACTOR * rtol, max_points=10000)
    r = ssf.simulate(system, 1500.0, 1000.0, **kw)
    te, pe = np.asarray(r.t_poincare), np.asarray(r.poincare)
    e_interp = np.abs(pe[:, 0] - pr[:, 0])
    e_step = []
    for k, t in enumerate(te):
        q = ssf.simulate(system, float(t), 0.0, **kw)
        assert abs(q.t_final - t) < 1e-12, (q.t_final, t)
        y = np.asarray(q.final_state)
        f = sm.rhs(0.0, y, p)
        x1min = y[0] - y[1] ** 2 / (2 * f[1])  # the minimum of x1 near t, from the stepped state
        e_step.append(abs(x1min - pr[k, 0]))
    e_step = np.array(e_step)
    print(
        f"eta={eta} {method} rtol={rtol:.0e}: x1-min error from the interpolant max {e_interp.max():.2e} median {np.median(e_interp):.1e};"
        f" from a step to the crossing max {e_step.max():.2e} median {np.median(e_step):.1e}  (n={len(te)})"
    )
