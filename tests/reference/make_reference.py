"""Regenerate tests/reference/scipy_reference.npz from tests/reference/cases.json.

Each case is integrated twice with SciPy:
  * primary   : Radau, rtol=1e-10, atol=1e-12 (stored as <name>__t, <name>__y)
  * check     : Radau, rtol=1e-12, atol=1e-14 (only used for <name>__selfdiff)
  * (optional): LSODA, rtol=1e-11, atol=1e-13 with --lsoda (reported, not stored)

<name>__selfdiff is max |y_primary - y_check| over all Poincare points and state components
(<name>__selfdiff_t the same for the crossing times). Cases whose self-consistency is worse
than 1e-8 are not written (the script says so).

Usage:  python tests/reference/make_reference.py [--only NAME ...] [--lsoda]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from scipy_model import scipy_poincare  # noqa: E402

PRIMARY = {"method": "Radau", "rtol": 1e-10, "atol": 1e-12}
CHECK = {"method": "Radau", "rtol": 1e-12, "atol": 1e-14}
LSODA = {"method": "LSODA", "rtol": 1e-11, "atol": 1e-13}
MAX_SELFDIFF = 1e-8


def load_cases(path=HERE / "cases.json"):
    with open(path) as fh:
        return json.load(fh)


def run_case(case, setting):
    t0 = time.perf_counter()
    t, y = scipy_poincare(
        case["params"], case["t_end"], case["t_transient"], np.asarray(case["y0"]), **setting
    )
    return t, y, time.perf_counter() - t0


def diff(a_t, a_y, b_t, b_y):
    if a_t.shape != b_t.shape:
        return np.inf, np.inf
    if a_t.size == 0:
        return 0.0, 0.0
    return float(np.max(np.abs(a_y - b_y))), float(np.max(np.abs(a_t - b_t)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--lsoda", action="store_true", help="also compare with LSODA")
    ap.add_argument("--out", default=str(HERE / "scipy_reference.npz"))
    args = ap.parse_args(argv)

    cases = load_cases()
    if args.only:
        cases = [c for c in cases if c["name"] in args.only]
    arrays = {}
    rows = []
    for case in cases:
        name = case["name"]
        t1, y1, rt1 = run_case(case, PRIMARY)
        t2, y2, rt2 = run_case(case, CHECK)
        sd_y, sd_t = diff(t1, y1, t2, y2)
        row = [name, t1.size, rt1, rt2, sd_y, sd_t]
        if args.lsoda:
            t3, y3, rt3 = run_case(case, LSODA)
            row += [*diff(t1, y1, t3, y3), rt3]
        rows.append(row)
        if sd_y > MAX_SELFDIFF:
            print(f"DROPPED {name}: self-consistency {sd_y:.2e} > {MAX_SELFDIFF:.0e}", flush=True)
            continue
        arrays[f"{name}__t"] = t1
        arrays[f"{name}__y"] = y1
        arrays[f"{name}__selfdiff"] = np.float64(sd_y)
        arrays[f"{name}__selfdiff_t"] = np.float64(sd_t)
        print(f"done {name}", flush=True)

    hdr = f"{'case':26s} {'#pts':>5s} {'t_rtol1e-10[s]':>14s} {'t_rtol1e-12[s]':>14s}"
    hdr += f" {'selfdiff_y':>11s} {'selfdiff_t':>11s}"
    if args.lsoda:
        hdr += f" {'lsoda_dy':>10s} {'lsoda_dt':>10s} {'t_lsoda[s]':>10s}"
    print(hdr)
    for r in rows:
        line = f"{r[0]:26s} {r[1]:5d} {r[2]:14.1f} {r[3]:14.1f} {r[4]:11.2e} {r[5]:11.2e}"
        if args.lsoda:
            line += f" {r[6]:10.2e} {r[7]:10.2e} {r[8]:10.1f}"
        print(line)

    if args.only and Path(args.out).exists():
        with np.load(args.out) as old:
            merged = dict(old)
        merged.update(arrays)
        arrays = merged
    np.savez_compressed(args.out, **arrays)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
