"""Two disks of the symmetric set on one DC motor: the anti-phase branch and its branch points.

Follows the period-1 orbit that the paper's start of Figs. 14-15 (disk 2 displaced)
settles on at eta = 3, disk 2 about half a period behind disk 1, in eta in both
directions; marks its branch points (a real multiplier through +1 with no fold:
pitchforks of an orbit with the disks swapped half a period later, docs/orbits.md,
"Branch points"); switches at the upper one (eta = 1.5727) to the crossing branch and
follows it (at the lower, sharp one the switched orbit's branch runs along the
anti-phase one to within 1e-4: not resolved, docs/orbits.md); and follows the in-phase
orbit (from rest) with its symmetry-breaking points. Writes
``data/branches/anti_phase_N2.h5`` (the anti-phase branch; the crossing and in-phase
branches beside it, ``.bp<k>.h5`` and ``.in_phase.h5``) and
``docs/figures/anti_phase_branches.png``; about 1.5 min on a 2-core machine.

    python3 scripts/anti_phase_branches.py [--out data/branches] [--figure PATH]
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

PAPER_START = [0.0, 0.0, 0.0, 0.0, 0.05, 0.05, 0.0, 0.0, 0.0]  # Fig. 14: disk 2 displaced
BOUNDS = (1.0, 5.0)


def both_ways(orbit: ssf.Orbit, max_points: int = 200) -> ssf.Branch:
    """The branch through ``orbit`` in eta, down and up, as one."""
    kw = dict(max_points=max_points, progress=False)
    down = ssf.continue_orbit(orbit, "eta", BOUNDS, direction=-1, **kw)
    up = ssf.continue_orbit(orbit, "eta", BOUNDS, direction=1, **kw)
    return ssf.join_branches(down, up)


def offset(branch: ssf.Branch) -> np.ndarray:
    """x2 - x1 at the section (the local minimum of x1): 0 for in-phase orbits."""
    return branch.points[:, 4] - branch.points[:, 0]


def plot(ax, branch: ssf.Branch, color: str, label: str) -> None:
    """The branch, solid where stable and dotted where not, with its labelled points."""
    y = offset(branch)
    for stable, style in ((True, "-"), (False, ":")):
        yy = np.where(branch.stable == stable, y, np.nan)
        ax.plot(branch.values, yy, style, color=color, lw=1.4,
                label=label if stable else None)  # fmt: skip
    for b in branch.bifurcations:
        if b.kind in ("branch-point", "symmetry-breaking", "fold", "period-doubling"):
            k = min(b.index, len(y) - 1)
            ax.plot(b.value, y[k], "o", ms=5, mfc="white", color=color)
            ax.annotate(b.label, (b.value, y[k]), textcoords="offset points", xytext=(4, 4),
                        fontsize=8, color=color)  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("data/branches"))
    ap.add_argument("--figure", type=Path, default=Path("docs/figures/anti_phase_branches.png"))
    args = ap.parse_args()
    t0 = time.time()
    two = ssf.System.preset("symmetric", drive="dc-motor", n_oscillators=2, eta=3.0)
    anti = both_ways(ssf.find_orbit(two, ssf.simulate(two, 3000, 2000, y0=PAPER_START)))
    crossings = []
    for bp in [b for b in anti.bifurcations if b.kind == "branch-point"][-1:]:
        start = ssf.switch_branch(anti, bp)
        if not start.converged:
            print(f"BP at {bp.value:.7f}: {start.message}")
            continue
        # the defaults walk away from the branch point with a small first step
        # (start.origin, walk_args.BRANCH_POINT_DS; the stored files, made on a Xeon, took 0.01)
        crossings.append(ssf.continue_orbit(start, "eta", BOUNDS, max_points=120,
                                            progress=False))  # fmt: skip
    with warnings.catch_warnings():  # from rest on purpose: the disks stay alike
        warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
        run = ssf.simulate(two, 3000, 2000)
    in_phase = both_ways(ssf.find_orbit(two, run))
    args.out.mkdir(parents=True, exist_ok=True)
    path = anti.to_hdf5(args.out / "anti_phase_N2.h5")
    in_phase.to_hdf5(args.out / "anti_phase_N2.in_phase.h5")
    named = [("anti-phase", anti), ("in-phase", in_phase)]
    named += [(f"crossing {k}", br) for k, br in enumerate(crossings, start=1)]
    for name, br in named:
        print(f"{name}: eta in [{br.values.min():.7f}, {br.values.max():.7f}], "
              f"{len(br.values)} points, ended {br.status}; "
              f"{[(b.label, round(b.value, 7)) for b in br.bifurcations]}")  # fmt: skip
    for k, br in enumerate(crossings, start=1):
        br.to_hdf5(args.out / f"anti_phase_N2.bp{k}.h5")
    print(f"{path} and beside it, {time.time() - t0:.0f} s")
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    plot(ax, anti, "C3", "anti-phase (the paper's start at η = 3)")
    for k, br in enumerate(crossings):
        plot(ax, br, f"C{1 + k}", f"crossing branch at η = {br.values[0]:.4f}")
    plot(ax, in_phase, "C0", "in phase (from rest)")
    ax.set(xlabel="η", ylabel="x₂ − x₁ at the minimum of x₁",
           title="two disks, symmetric set, one DC motor: period-1 orbits (dotted: unstable)")  # fmt: skip
    ax.legend(loc="upper right", fontsize=8)
    args.figure.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.figure, dpi=120)
    print(f"figure: {args.figure}")


if __name__ == "__main__":
    main()
