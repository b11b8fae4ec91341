"""Default labels over random physical parameters, not only the presets.

The classification corpus (``tests/classification_corpus.py``) draws random drives,
disk counts, eta and starts of the three parameter sets. This script also draws the
system: one disk (or `--disks` identical ones on one belt), a preset's other fields, and

- m log-uniform in [0.5, 100], k12 uniform in (-0.9, 0.9), mu log-uniform in
  [0.01, 5], c uniform in [0, 0.05];
- the belt speed v_b = v_b0 log-uniform in [1e-3, 0.2]; a constant belt or the DC
  motor; eta uniform in [1, 10]; the start uniform in the census's default box.

Each case is labelled with the defaults (only ``t_end`` = 3000 and ``t_transient`` =
2000 given) and set against a *settled* run: 30 000 time units, judged on the last
third, atol 1e-13 and ``dwell`` = 5000 (so that an orbit's far-apart minima and a slow
stall are seen). Besides ``same``, ``false`` and ``none found`` of
:func:`classification_corpus.verdict`, a label is *wrong* if it claims a period
(``ok``, p > 0) other than the settled run's, or rest (``equilibrium``, ``stalled``)
where the settled run has an orbit; the ``false`` ones are also counted by (label,
settled) status.

    python3 -m benchmarks.param_labels [--seed 11 23] [--cases 500] [--disks 2]

Result: ``results/param_labels_<date>.json``, with the machine. About 30 s per 500
cases on one 2-core VM.
"""

from __future__ import annotations

import argparse
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

from .loose_labels import corpus, write_corpus_result

RESULTS = Path(__file__).resolve().parent / "results"
SEEDS = (11, 23)
PRESETS = ("asymmetric", "symmetric", "literature")
AT_REST = ("equilibrium", "stalled")


def draw_case(rng: np.random.Generator, disks: int = 1) -> tuple:
    """One random (system, eta, start) of ``disks`` identical disks."""
    import stickslip_fast as ssf
    from stickslip_fast.analysis.census import default_box

    base = ssf.System.preset(PRESETS[rng.integers(3)])
    fields = dict(
        m=float(np.exp(rng.uniform(np.log(0.5), np.log(100)))),
        k12=float(rng.uniform(-0.9, 0.9)),
        mu=float(np.exp(rng.uniform(np.log(0.01), np.log(5)))),
        c=float(rng.uniform(0, 0.05)),
        vb=float(np.exp(rng.uniform(np.log(1e-3), np.log(0.2)))),
    )
    fields["vb0"] = fields["vb"]
    system = base.replace(drive=("constant", "dc-motor")[rng.integers(2)], n_oscillators=disks,
                          **fields)  # fmt: skip
    eta = float(rng.uniform(1, 10))
    box = default_box(system.replace(eta=eta))
    return system, eta, box[:, 0] + rng.random(system.n_state) * (box[:, 1] - box[:, 0])


def label(system, eta: float, y0: np.ndarray, **given) -> tuple[str, int]:
    """(status, period) of one run through the sweep kernel, the defaults filled as
    ``sweep`` fills them."""
    from stickslip_fast.backends.local import compute_restart_chunk
    from stickslip_fast.base.status import STATUS_NAMES
    from stickslip_fast.core.settings import Settings, system_defaults

    atol, eq_tol, dwell = system_defaults(
        system, atol=given.pop("atol", None), dwell=given.pop("dwell", None)
    )
    s = Settings.resolve(atol=atol, equilibrium_tol=eq_tol, dwell=dwell, **given)
    res = compute_restart_chunk(system, ("eta",), np.array([[eta]]), y0[None, :], s)
    return STATUS_NAMES[int(res["status"][0])], int(res["period"][0])


def wrong(lab: tuple[str, int], settled: tuple[str, int]) -> bool:
    """A claimed period other than the settled one, or rest where it has an orbit."""
    claims_period = lab[0] == "ok" and lab[1] > 0 and lab != settled
    claims_rest = lab[0] in AT_REST and settled[0] == "ok" and settled[1] > 0
    return claims_period or claims_rest


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, nargs="*", default=list(SEEDS))
    ap.add_argument("--cases", type=int, default=500)
    ap.add_argument("--disks", type=int, default=1, help="disks per system (default 1)")
    ap.add_argument(
        "--out", type=Path, default=RESULTS / f"param_labels_{time.strftime('%Y-%m-%d')}.json"
    )
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    cc = corpus()
    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    t0 = time.perf_counter()
    rows = []
    for seed in args.seed:
        rng = np.random.default_rng(seed)
        verdicts, pairs, wrong_cases = Counter(), Counter(), []
        for i in range(args.cases):
            system, eta, y0 = draw_case(rng, args.disks)
            lab = label(system, eta, y0, t_end=3000.0, t_transient=2000.0)
            settled = label(system, eta, y0, t_end=30000.0, t_transient=20000.0, atol=1e-13,
                            dwell=5000.0)  # fmt: skip
            v = cc.verdict(lab, settled)
            verdicts[v] += 1
            if v == "false":
                pairs[f"{lab[0]}{'/p' if lab[1] else ''} vs {settled[0]}"
                      f"{'/p' if settled[1] else ''}"] += 1  # fmt: skip
            if wrong(lab, settled):
                wrong_cases.append(dict(case=i, system=repr(system), eta=eta, label=lab,
                                        settled=settled))  # fmt: skip
        row = dict(seed=seed, cases=args.cases, disks=args.disks, **verdicts, wrong=len(wrong_cases),
                   false_by_status=dict(pairs.most_common()), wrong_cases=wrong_cases)  # fmt: skip
        rows.append(row)
        print(f"seed {seed}: {dict(verdicts)}, wrong {len(wrong_cases)}; false by status: "
              f"{dict(pairs.most_common())}", flush=True)  # fmt: skip
    write_corpus_result(args.out, started, t0, rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
