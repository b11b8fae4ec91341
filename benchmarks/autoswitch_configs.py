"""``method="auto"`` on every diagram of ``data/``, with both stop rules, and on a census.

docs/performance.md ("Stiffness-aware switching") measured ``auto`` on the Fig. 6 and
Fig. 12 diagrams only; it names as unmeasured the literature set, two disks, converged
stopping and the census. This script measures them, side by side in one run:

1. **Diagrams.** Every sweep config of ``data/`` (Figs. 2, 4, 6, 9, 12, 14 and 16: three
   parameter sets, both drives, one and two disks, the configs' own starts and windows),
   on ``--values`` values spread over the config's range, with the fixed window and with
   ``stop="converged"``; ``rodas5p`` and ``auto`` at the same rtol (the default, 1e-9),
   alternating, best of ``--rounds``; the labels (status and period) compared with each
   other and with a ``rodas5p`` run at rtol / 100 (fixed window), and the periodic values'
   last points compared between the two methods.
2. **A census** (``data/census/fig06_census.toml``: constant belt; ``--census-values``
   values x ``--starts`` starts, converged stopping): ``rodas5p`` and ``auto``; the
   label (status and period) of every run compared, and the number of attractors per value.

Result: ``results/autoswitch_configs.json`` (``--out``), with the machine.

    python3 -m benchmarks.autoswitch_configs [--values 60] [--rounds 2] [--quick]
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from pathlib import Path

import numpy as np

from stickslip_fast.cli.config import load_config
from stickslip_fast.core.settings import Settings

from .autoswitch import _diagram_compare, _timed
from .common import ROOT, machine_info, ssf, write_result

RESULTS = Path(__file__).resolve().parent / "results"
CONFIGS = (
    "fig02_literature_constant", "fig04_symmetric_constant", "fig06_asymmetric_constant",
    "fig09_literature_dcmotor", "fig12_asymmetric_dcmotor", "fig14_symmetric_dcmotor_N2",
    "fig16_asymmetric_dcmotor_N2",
)  # fmt: skip
METHODS = ("rodas5p", "auto")
STOPS = ("fixed", "converged")


def _grid(values, n_values: int) -> np.ndarray:
    """``n_values`` values spread over the range of a config's ``values``."""
    vals = np.asarray(values, dtype=float)
    return np.linspace(vals.min(), vals.max(), n_values)


def _integration(cfg) -> dict:
    """A config's integration settings without the two this script sets itself."""
    return {k: v for k, v in cfg.integration.items() if k not in ("method", "stop")}


def _sweeper(cfg):
    integ = _integration(cfg)

    def sweep(method, values, stop, rtol_factor=1.0):
        kw = dict(integ)
        if rtol_factor != 1.0:
            base = Settings.resolve(**integ)
            kw.update(rtol=base.rtol * rtol_factor, atol=base.atol * rtol_factor)
        return ssf.sweep(cfg.system, cfg.sweep["param"], values, y0=cfg.y0, method=method,
                         stop=stop, progress=False, **kw)  # fmt: skip

    return sweep


def diagram_rows(log, n_values: int, rounds: int, configs) -> dict:
    out = {}
    for name in configs:
        cfg = load_config(ROOT / "data" / f"{name}.toml")
        values = _grid(cfg.sweep["values"], n_values)
        sweep = _sweeper(cfg)
        for m in METHODS:  # compile outside the timing
            for stop in STOPS:
                sweep(m, values[:2], stop)
        tight = sweep("rodas5p", values, "fixed", rtol_factor=1e-2)
        for stop in STOPS:
            best, res = dict.fromkeys(METHODS, math.inf), {}
            for _ in range(rounds):
                for m in METHODS:
                    wall, res[m] = _timed(sweep, m, values, stop)
                    best[m] = min(best[m], wall)
            rec = dict(
                time=best, speedup_auto=best["rodas5p"] / best["auto"],
                steps={m: int(np.sum(res[m].n_steps)) for m in METHODS},
                auto_vs_rodas5p=_diagram_compare(res["auto"], res["rodas5p"]),
                rodas5p_vs_tight=_diagram_compare(res["rodas5p"], tight),
                auto_vs_tight=_diagram_compare(res["auto"], tight),
            )  # fmt: skip
            out[f"{name}/{stop}"] = rec
            log(f"  {name} {stop}: rodas5p {best['rodas5p']:.2f} s, auto {best['auto']:.2f} s "
                f"({rec['speedup_auto']:.2f}x); labels auto = rodas5p "
                f"{rec['auto_vs_rodas5p']['labels_equal']}/{values.size}, = tight: rodas5p "
                f"{rec['rodas5p_vs_tight']['labels_equal']}, auto "
                f"{rec['auto_vs_tight']['labels_equal']}; max point diff "
                f"{rec['auto_vs_rodas5p']['max_point_diff']:.1e}")  # fmt: skip
    return out


def census_row(log, n_values: int, n_starts: int, rounds: int) -> dict:
    cfg = load_config(ROOT / "data" / "census" / "fig06_census.toml")
    values = _grid(cfg.census["values"], n_values)
    integ = _integration(cfg)

    def run(method, vals=values):
        return ssf.census(cfg.system, cfg.census["param"], vals, n_starts=n_starts,
                          seed=cfg.census.get("seed", 0), stop="converged", method=method,
                          progress=False, **integ)  # fmt: skip

    for m in METHODS:
        run(m, values[:1])
    best, res = dict.fromkeys(METHODS, math.inf), {}
    for _ in range(rounds):
        for m in METHODS:
            wall, res[m] = _timed(run, m)
            best[m] = min(best[m], wall)
    a, b = res["auto"], res["rodas5p"]
    same = (np.asarray(a.status) == np.asarray(b.status)) & (a.period == b.period)
    n_att = {m: [len(x) for x in res[m].attractors] for m in METHODS}
    rec = dict(
        n_values=n_values, n_starts=n_starts, time=best,
        speedup_auto=best["rodas5p"] / best["auto"], runs=int(same.size),
        runs_same_label=int(same.sum()),
        values_same_attractor_count=int(sum(x == y for x, y in zip(*n_att.values()))),
        attractors_per_value=n_att,
    )  # fmt: skip
    log(f"  census: rodas5p {best['rodas5p']:.2f} s, auto {best['auto']:.2f} s "
        f"({rec['speedup_auto']:.2f}x); same label in {rec['runs_same_label']}/{same.size} "
        f"runs, same number of attractors at {rec['values_same_attractor_count']}/{n_values} "
        f"values")  # fmt: skip
    return rec


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--values", type=int, default=60, help="values per diagram")
    ap.add_argument("--rounds", type=int, default=2, help="timing rounds (alternating)")
    ap.add_argument("--census-values", type=int, default=12)
    ap.add_argument("--starts", type=int, default=16, help="starts per census value")
    ap.add_argument("--quick", action="store_true", help="small sizes, two configs (smoke test)")
    ap.add_argument("--out", type=Path, default=RESULTS / "autoswitch_configs.json")
    args = ap.parse_args(argv)
    if args.quick:
        args.values, args.rounds, args.census_values, args.starts = 6, 1, 2, 4
    configs = CONFIGS[2:4] if args.quick else CONFIGS

    def log(msg):
        print(msg, flush=True)

    # the sweeps' notes on values at rest are expected here: the labels are compared
    warnings.filterwarnings("ignore", message=".*gave no orbit", category=UserWarning)
    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    t0 = time.perf_counter()
    result = dict(machine=machine_info(), started=started, values=args.values,
                  rounds=args.rounds)  # fmt: skip
    log("diagrams")
    result["diagrams"] = diagram_rows(log, args.values, args.rounds, configs)
    log("census")
    result["census"] = census_row(log, args.census_values, args.starts, args.rounds)
    result["wall"] = time.perf_counter() - t0
    write_result(args.out, result, log)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
