"""Labels at loose tolerances: how the period tolerance's cap decides them.

The period test calls the last points periodic when each lies within
``period_tol * (1 + max|point|)`` of the point ``p`` before it, and ``period_tol``
defaults to 1e4 rtol. At rtol 1e-4 that is 1 and at 1e-3 it is 10: every pair of points
then "repeats", and any run with enough crossings reads as period 1. This script runs the
classification corpus of ``tests/classification_corpus.py`` (random drive, N, eta and
start of the asymmetric, literature and symmetric sets) at loose rtol with the period
tolerance ``min(1e4 rtol, cap)`` for several caps, and sets each label against the
*settled* run of the same case at the default rtol (3x longer, judged on the last third):

- ``same``: the same status and period;
- ``false``: a label that claims more than the settled run: a period other than the
  settled one, rest where it moves, or motion where it rests;
- ``none found``: period 0 (``ok``, no period detected) where the settled run has one,
  or ``unsettled``: an honest "not found" or "not decided".

    python3 -m benchmarks.loose_labels [--rtol 1e-3 1e-4 1e-5 1e-6] [--caps inf 1e-3 1e-4]

Result: ``results/loose_labels_<date>.json``, with the machine.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).resolve().parent / "results"
#: (preset, cases, seed): the corpus of tests/test_classification.py.
CORPUS = (("asymmetric", 200, 2026), ("literature", 100, 2026), ("symmetric", 100, 2026))
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7)
CAPS = (math.inf, 1e-3, 1e-4)


def corpus():
    """The corpus module of the tests (imported from tests/, as the tests do)."""
    if str(ROOT / "tests") not in sys.path:
        sys.path.insert(0, str(ROOT / "tests"))
    import classification_corpus

    return classification_corpus


def verdict(label: tuple[str, int], settled: tuple[str, int]) -> str:
    """``same``, ``none found`` (period 0 where the settled run has one, or
    ``unsettled``: undecided) or ``false``."""
    if label == settled:
        return "same"
    if (label == ("ok", 0) and settled[0] == "ok") or label[0] == "unsettled":
        return "none found"
    return "false"


def main(argv=None) -> int:
    from .common import machine_info, write_result

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtol", type=float, nargs="*", default=list(RTOLS))
    ap.add_argument("--caps", type=float, nargs="*", default=list(CAPS))
    ap.add_argument(
        "--out", type=Path, default=RESULTS / f"loose_labels_{time.strftime('%Y-%m-%d')}.json"
    )
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")  # two disks from a synchronous start
    cc = corpus()
    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    t0 = time.perf_counter()
    rows = []
    for preset, n, seed in CORPUS:
        cases = cc.random_cases(n, seed, preset)
        settled = cc.run(cases, preset, **cc.SETTLED)
        for rtol in args.rtol:
            for cap in args.caps:
                ptol = min(1e4 * rtol, cap)
                labels = cc.run(cases, preset, t_end=cc.T_END, rtol=rtol, period_tol=ptol)
                v = [verdict(a, b) for a, b in zip(labels, settled, strict=True)]
                row = dict(preset=preset, rtol=rtol, cap=cap, period_tol=ptol, cases=n,
                           **{k: v.count(k) for k in ("same", "false", "none found")})  # fmt: skip
                rows.append(row)
                print(f"{preset:10s} rtol {rtol:g} period_tol {ptol:g}: same {row['same']}, "
                      f"false {row['false']}, none found {row['none found']}", flush=True)  # fmt: skip
    result = dict(machine=machine_info(), started=started, rows=rows,
                  wall=time.perf_counter() - t0)  # fmt: skip
    write_result(args.out, result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
