"""The fold curves of Fig. 6's period-1 orbit in the (eta, v_b) plane (issue 28).

The paper's belt speed v_b = 0.0112 lies just below the top of the period-1 region of
the (eta, v_b) census (docs/census.md: period-1 cells up to v_b = 0.01125). This script
locates the two folds of the period-1 branch in eta at k12 = -0.8, v_b = 0.0112 (as
``scripts/fold_curves_eta_k12.py`` does) and follows each in v_b with
:func:`stickslip_fast.continue_bifurcation`, up (towards where the region closes) and
down (to v_b = 0.0025), writing ``data/curves/p1_fold_{upper,lower}_{up,down}_eta_vb.h5``.
``scripts/plot_census_plane.py --curve`` lays them over the census maps of the plane.

``dc-motor`` does the same for Fig. 12's period-1 orbit (the asymmetric set on the DC
motor) in (eta, v_b0), the motor's no-load belt speed: its stable interval in eta ends
in a fold at the top (3.721570072) and in a grazing of the section at the bottom
(1.458266356, not a codim-1 point that ``continue_bifurcation`` follows), so only the
upper fold is followed (``p1_fold_upper_{up,down}_eta_vb0_dcmotor.h5``). ``dc-motor-N2``
follows the fold of two disks' period-1 orbit with the disks apart
(``p1_fold_apart_{up,down}_eta_vb0_dcmotor_N2.h5``). In phase, two disks are one disk:
the motor's equation sees their mean friction (beta / N times the sum), so their orbit,
fold (3.7215700716) and fold curve are ``dc-motor``'s.

    python3 scripts/fold_curves_eta_vb.py [upper|lower|dc-motor|dc-motor-N2 ...] [--points 400]
        [--out data/curves] [--directions up,down]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fold_curves_eta_k12  # noqa: E402

import stickslip_fast as ssf  # noqa: E402

#: the v_b interval of the census plane (data/maps/census_plane_eta_vb.toml)
VB_BOUNDS = (0.0025, 0.04)
#: the curve's corrector tolerance and the test function's difference step (the closing
#: settings of the (eta, k12) curves: a fold curve near its extremum needs h = 1e-9)
CURVE_KW = dict(tol=1e-9, h=1e-9)


def dc_motor_fold() -> tuple[ssf.Branch, ssf.Bifurcation]:
    """(branch, fold): Fig. 12's period-1 branch from eta = 2.0 up to its fold at 3.7216
    (data/continuation/fig12_p1.toml, upwards only)."""
    s = ssf.System.preset("asymmetric", drive="dc-motor", eta=2.0)
    orbit = ssf.find_orbit(s, ssf.simulate(s, 3000.0, stop="converged"), 1)
    branch = ssf.continue_orbit(orbit, "eta", (2.0, 4.0), ds=0.02, ds_max=0.05, max_points=200,
                                stick_events=False)  # fmt: skip
    return branch, next(b for b in branch.bifurcations if b.kind == "fold")


#: a start of two disks on the DC motor at eta = 3 that settles on a period-1 orbit with
#: the disks apart (x1 = 0.0809, x2 = 0.1414 at the section; multipliers 0.892, 0.223)
N2_START = [0.05, 0.0, 0.0, 0.0, -0.05, 0.0, 0.0, 0.0, 0.0112]


def dc_motor_n2_fold() -> tuple[ssf.Branch, ssf.Bifurcation]:
    """(branch, fold): the period-1 orbit of two disks on the DC motor with the disks apart,
    from eta = 3.0 up to its fold at 3.9768865. (With the disks in phase the orbit is one
    disk's, the motor seeing their mean friction: its fold is Fig. 12's, 3.7215701.)"""
    s = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2, eta=3.0)
    run = ssf.simulate(s, 20000.0, y0=N2_START, stop="converged")
    orbit = ssf.find_orbit(s, run, 1)
    branch = ssf.continue_orbit(orbit, "eta", (3.0, 4.2), ds=0.02, ds_max=0.05, max_points=120,
                                stick_events=False)  # fmt: skip
    return branch, next(b for b in branch.bifurcations if b.kind == "fold")


def fold_curve_vb(which: str, direction: int, points: int,
                  checkpoint: Path | None = None) -> ssf.Curve:  # fmt: skip
    """The fold ``which`` ("upper", "lower"; "dc-motor": Fig. 12's upper fold in v_b0;
    "dc-motor-N2": two disks apart on the motor) followed in v_b up (+1) or down (-1),
    recording its integrations in ``checkpoint`` (a killed run resumes from it)."""
    if which == "dc-motor-N2":
        (branch, fold), param2 = dc_motor_n2_fold(), "vb0"
    elif which == "dc-motor":
        (branch, fold), param2 = dc_motor_fold(), "vb0"
    else:
        (branch, fold), param2 = fold_curves_eta_k12.locate_fold(which), "vb"
    return ssf.continue_bifurcation(branch, fold, param2, VB_BOUNDS, direction=direction,
                                    ds=5e-3, ds_max=0.05, max_points=points,
                                    checkpoint=checkpoint, **CURVE_KW)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("which", nargs="*", default=["upper", "lower"],
                   choices=["upper", "lower", "dc-motor", "dc-motor-N2"])  # fmt: skip
    p.add_argument("--points", type=int, default=400, help="points per curve (default 400)")
    p.add_argument("--out", default="data/curves", help="folder of the curve files")
    p.add_argument("--directions", default="up,down", help="up, down or both (default)")
    args = p.parse_args(argv)
    wanted = args.directions.split(",")
    for which in args.which:
        for direction, name in ((1, "up"), (-1, "down")):
            if name not in wanted:
                continue
            t0 = time.perf_counter()
            stem = {
                "dc-motor": "upper_{}_eta_vb0_dcmotor",
                "dc-motor-N2": "apart_{}_eta_vb0_dcmotor_N2",
            }.get(which, which + "_{}_eta_vb")
            path = Path(args.out) / f"p1_fold_{stem.format(name)}.h5"
            path.parent.mkdir(parents=True, exist_ok=True)
            # a killed run goes on from its checkpoint when run again (docs/orbits.md)
            curve = fold_curve_vb(which, direction, args.points, path.with_suffix(".ckpt"))
            curve.to_hdf5(path)
            path.with_suffix(".ckpt").unlink(missing_ok=True)
            kinds = [(c.kind, [round(float(v), 10) for v in c.values]) for c in curve.codim2]
            print(f"{which} {name}: {len(curve.values)} points to {curve.values[-1].tolist()} "
                  f"({curve.status}, {time.perf_counter() - t0:.0f} s) codim2 {kinds} -> {path}",
                  flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
