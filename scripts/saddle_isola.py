"""The saddle halves of the period-1 orbit just above where its region closes (issue 28).

At k12 = -0.8316, 1.1e-4 above the minimum of the fold curve in (eta, k12), the stable
period-1 orbit lives between two folds (eta = 2.5705528 and 2.6673481). From each fold a
saddle branch turns back into the interval. Were the two halves one closed curve (an
isola), they would meet inside it. This script follows both by multiple shooting with
re-meshing and reports, for each half:

* where it ends, its leading multiplier there, T and the stick phases per period;
* how fast log10(mu) grows with eta;
* where along the orbit the amplification happens (each segment's 2-norm, and disk 1's
  slip speed in units of eps there);
* an independent stick-phase count (SciPy's Radau on the reference model, sampled on the
  segments) at the two eta where the fixed-mesh runs reported a second stick phase.

    PYTHONPATH=. python3 scripts/saddle_isola.py [--out FILE]

About 2 min on a 2-core VM. docs/reproduction.md ("Where the period-1 region closes")
quotes the run of 2026-11-27.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "reference"))

import scipy_segments as sg  # noqa: E402

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.bifurcation.multishoot import MultiShooting  # noqa: E402
from stickslip_fast.bifurcation.stickphases import STICK_SPEED  # noqa: E402

K12 = -0.8316
#: The stable orbit at eta = 2.6 (tests/test_multishoot.py)
Y_STABLE = [0.11834572437245043, 0.0, 0.1459190815849308, -0.008125583378266665]
#: Where the fixed-mesh runs reported a second stick phase (docs until 2026-11-27)
OLD_STICK_ETA = {1: 2.6653695, -1: 2.5722440}


def amplification(branch, i: int) -> dict:
    """Where the multiplier of point ``i`` is made: the segments' norms and disk 1's slip."""
    mesh, Y = branch.segments[i]
    s = branch.system.replace(eta=float(branch.values[i]))
    ms = MultiShooting(s, mesh, 1e-11, 1e-13, 1e-13)
    T = float(branch.T[i])
    rows = []
    for k in range(mesh.size - 1):
        _, y1, Phi = ms.flow(Y[k], (mesh[k + 1] - mesh[k]) * T)
        slip = max(np.hypot(y[1] - s.vb, y[3]) / s.eps for y in (Y[k], y1))
        rows.append((mesh[k] * T, np.log10(np.linalg.norm(Phi[:, : s.n_state], 2)), slip))
    total = sum(r[1] for r in rows)
    top = sorted(rows, key=lambda r: -r[1])[:5]
    return {
        "eta": float(branch.values[i]),
        "mu": float(np.max(np.abs(branch.multipliers[i]))),
        "segments": int(mesh.size - 1),
        "log10_norms": total,
        "share_in_stick_band": sum(r[1] for r in rows if r[2] < STICK_SPEED) / total,
        "top_segments": [{"t": t, "log10_norm": a, "slip_over_eps": sl} for t, a, sl in top],
    }


def scipy_stick_count(branch, i: int) -> int:
    """Stick phases of point ``i`` by the reference model sampled on its segments."""
    mesh, Y = branch.segments[i]
    s = branch.system.replace(eta=float(branch.values[i]))
    p = {**s.to_dict(), "n_oscillators": s.n_oscillators}
    y = sg.sample_segments(p, mesh, Y, float(branch.T[i]))
    stick = np.hypot(y[:, 1] - s.vb, y[:, 3]) / s.eps < STICK_SPEED
    return int(np.sum(stick & ~np.roll(stick, 1)))


def half(orbit, direction: int) -> dict:
    t0 = time.perf_counter()
    br = ssf.continue_orbit(orbit, "eta", (2.5, 2.7), ds=1e-3, ds_max=5e-3, max_points=800,
                            direction=direction, shooting="auto", remesh=True)  # fmt: skip
    seconds = time.perf_counter() - t0
    lead = np.max(np.abs(br.multipliers), axis=1)
    have = np.array([seg is not None for seg in br.segments])
    fold = next(b.value for b in br.bifurcations if b.kind == "fold")
    i16 = int(np.flatnonzero(have & (lead >= 1e16))[0])
    last = int(np.flatnonzero(have)[-1])
    rate = (np.log10(lead[last]) - np.log10(lead[i16])) / abs(br.values[last] - br.values[i16])
    eta_old = OLD_STICK_ETA[direction]
    side = [i for i in range(br.values.size - 1) if have[i] and have[i + 1]
            and (br.values[i] - eta_old) * (br.values[i + 1] - eta_old) <= 0]  # fmt: skip
    checks = [{"eta": float(br.values[j]), "mu": float(lead[j]), "scipy_stick_phases":
               scipy_stick_count(br, j)} for j in (side[0], side[0] + 1)]  # fmt: skip
    out = {
        "direction": direction, "status": br.status, "points": int(br.values.size),
        "seconds": seconds, "fold": fold, "eta_end": float(br.values[last]),
        "mu_end": float(lead[last]), "T_fold_end": [float(br.T[0]), float(br.T[last])],
        "stick_counts": sorted({int(c) for c in br.stick_count}),
        "decades_per_unit_eta": float(rate),
        "amplification": [amplification(br, int(np.flatnonzero(have & (lead >= m))[0]))
                          for m in (1e8, 1e16, 1e30, 1e45) if np.any(have & (lead >= m))],
        "stick_check": checks,
    }  # fmt: skip
    print(json.dumps(out), flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", default=None, help="write the results as JSON here")
    args = p.parse_args(argv)
    s = ssf.System.preset("asymmetric", eta=2.6, k12=K12)
    orbit = ssf.find_orbit(s, np.array(Y_STABLE), 1)
    res = [half(orbit, d) for d in (-1, 1)]
    print(f"the halves end {res[1]['eta_end'] - res[0]['eta_end']:.4f} apart in eta")
    if args.out:
        Path(args.out).write_text(json.dumps(res, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
