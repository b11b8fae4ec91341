"""Labels at loose tolerances: the period tolerance's cap, and atol against eps.

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

Then the same corpus at the default (capped) period tolerance with atol from 1e-11 (the
default) to 1e-5, the friction law's eps of the three sets, at rtol 1e-6 and 1e-3: how
small atol must be against eps (:data:`stickslip_fast.core.settings.ATOL_EPS_RATIO`).
Last, converged stopping (the census's default) at rtol 1e-6 and 1e-4, uncapped and
capped.

    python3 -m benchmarks.loose_labels [--rtol ...] [--caps inf 1e-3 1e-4] [--atols ...]

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
ATOLS = (1e-11, 1e-8, 1e-7, 1e-6, 1e-5)
ATOL_RTOLS = (1e-6, 1e-3)
CONVERGED_RTOLS = (1e-6, 1e-4)


def corpus():
    """The corpus module of the tests (imported from tests/, as the tests do)."""
    if str(ROOT / "tests") not in sys.path:
        sys.path.insert(0, str(ROOT / "tests"))
    import classification_corpus

    return classification_corpus


def corpus_start(doc: str, stem: str, axis: str, values, cases: int, argv, seed: int) -> tuple:
    """The start of a benchmark on the corpus: its command line (``--<axis>`` values,
    ``--cases``, ``--out``: ``results/<stem>_<date>.json``), the corpus module, ``cases``
    asymmetric cases of ``seed``, the start time (UTC) and the clock. Warnings are
    silenced from here on (two disks from a synchronous start, a coarse tolerance on
    purpose)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument(f"--{axis}", type=float, nargs="*", default=list(values))
    ap.add_argument("--cases", type=int, default=cases)
    ap.add_argument(
        "--out", type=Path, default=RESULTS / f"{stem}_{time.strftime('%Y-%m-%d')}.json"
    )
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    cc = corpus()
    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    return args, cc, cc.random_cases(args.cases, seed), started, time.perf_counter()


def write_corpus_result(out: Path, started: str, t0: float, rows: list, **extra) -> None:
    """Write a corpus benchmark's rows with the machine, its start and its wall time."""
    from .common import machine_info, write_result

    write_result(out, dict(machine=machine_info(), started=started, rows=rows,
                           wall=time.perf_counter() - t0, **extra))  # fmt: skip


def main(argv=None) -> int:
    from .common import machine_info, write_result

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtol", type=float, nargs="*", default=list(RTOLS))
    ap.add_argument("--caps", type=float, nargs="*", default=list(CAPS))
    ap.add_argument("--atols", type=float, nargs="*", default=list(ATOLS))
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
        grid = [
            dict(rtol=r, cap=c, period_tol=min(1e4 * r, c)) for r in args.rtol for c in args.caps
        ]
        grid += [dict(rtol=r, atol=a) for r in ATOL_RTOLS for a in args.atols]
        grid += [dict(rtol=r, stop="converged", **({"period_tol": 1e4 * r} if raw else {}))
                 for r in CONVERGED_RTOLS for raw in (True, False)]  # fmt: skip
        for point in grid:
            kw = {k: v for k, v in point.items() if k != "cap"}
            labels = cc.run(cases, preset, t_end=cc.T_END, **kw)
            v = [cc.verdict(a, b) for a, b in zip(labels, settled, strict=True)]
            row = dict(preset=preset, cases=n, **point,
                       **{k: v.count(k) for k in ("same", "false", "none found")})  # fmt: skip
            rows.append(row)
            print(f"{preset:10s} {kw}: same {row['same']}, false {row['false']}, "
                  f"none found {row['none found']}", flush=True)  # fmt: skip
    result = dict(machine=machine_info(), started=started, rows=rows,
                  wall=time.perf_counter() - t0)  # fmt: skip
    write_result(args.out, result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
