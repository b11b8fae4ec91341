"""Where two disks on one DC motor can move in phase: the symmetry-breaking curve in (eta, k12).

Follows the in-phase period-1 orbit of two identical disks on one DC motor in eta at
k12 = 0 (the paper's symmetric set) from eta = 3, locates the symmetry-breaking point
where its transverse multiplier passes +1 (eta = 4.7639, docs/orbits.md, "In-phase
orbits"), and follows that point in k12 down to the bound -0.9 with
:func:`stickslip_fast.continue_bifurcation`. The curve passes the asymmetric set
(k12 = -0.8) at its upper SB point (eta = 2.6854), so one curve bounds the stable
in-phase motion of both of the paper's sets. Writes ``data/curves/sb_eta_k12.h5`` and
``docs/figures/sb_curve_eta_k12.png``; about 4 min on a 2-core machine (285 points).

    python3 scripts/sb_curve_k12.py [--points 500] [--out data/curves] [--figure PATH]
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import stickslip_fast as ssf  # noqa: E402


def in_phase_branch(preset: str, eta: float, bounds: tuple[float, float]) -> ssf.Branch:
    """The in-phase period-1 branch of two disks of ``preset`` on one DC motor."""
    two = ssf.System.preset(preset, drive="dc-motor", n_oscillators=2, eta=eta)
    with warnings.catch_warnings():  # from rest on purpose: the disks stay alike
        warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
        run = ssf.simulate(two, 3000, 2000)
    return ssf.continue_orbit(ssf.find_orbit(two, run), "eta", bounds, progress=False)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=500)
    ap.add_argument("--out", type=Path, default=Path("data/curves"))
    ap.add_argument("--figure", type=Path, default=Path("docs/figures/sb_curve_eta_k12.png"))
    args = ap.parse_args()
    t0 = time.time()
    sym = in_phase_branch("symmetric", 3.0, (3.0, 5.0))
    (sb,) = [b for b in sym.bifurcations if b.kind == "symmetry-breaking"]
    asym = in_phase_branch("asymmetric", 1.6, (1.6, 3.0))
    asym_sb = [b.value for b in asym.bifurcations if b.kind == "symmetry-breaking"]
    print(f"SB at k12 = 0: eta = {sb.value:.10g}; at k12 = -0.8: {asym_sb}")
    curve = ssf.continue_bifurcation(sym, sb, "k12", (-0.9, 0.0), direction=-1,
                                     max_points=args.points, progress=False)  # fmt: skip
    args.out.mkdir(parents=True, exist_ok=True)
    path = curve.to_hdf5(args.out / "sb_eta_k12.h5")
    v = curve.values
    cross = np.nonzero((v[:-1, 1] + 0.8) * (v[1:, 1] + 0.8) < 0)[0]
    for j in cross:
        a, b = v[j], v[j + 1]
        eta = a[0] + (b[0] - a[0]) * (-0.8 - a[1]) / (b[1] - a[1])
        print(f"the curve passes k12 = -0.8 at eta ~ {eta:.5f} (chord between its points)")
    print(f"{path}: {len(v)} points, ended {curve.status}, codim-2 "
          f"{[(p.kind, np.round(p.values, 6).tolist()) for p in curve.codim2]}, "
          f"{time.time() - t0:.0f} s")  # fmt: skip
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    ax.plot(v[:, 0], v[:, 1], "k-", lw=1.2, label="symmetry-breaking curve (SB)")
    ax.plot([sb.value], [0.0], "o", color="C0", label=f"symmetric set: SB at η = {sb.value:.4f}")
    ax.plot(asym_sb, [-0.8] * len(asym_sb), "s", color="C3",
            label="asymmetric set (k12 = −0.8): SB points")  # fmt: skip
    for p in curve.codim2:
        ax.plot(*p.values, "x", color="C2")
    ax.set(xlabel="η", ylabel="k12", title="two disks on one DC motor: in-phase period-1 orbit")
    ax.legend(loc="lower right", fontsize=8)
    args.figure.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.figure, dpi=120)
    print(f"figure: {args.figure}")


if __name__ == "__main__":
    main()
