"""Labels at slow belt speeds: ``equilibrium_tol`` and ``dwell`` against the belt speed.

A disk that sticks rides with the belt, at the belt speed. The presets' belt speed is
v_b = v_b0 = 0.0112, and the fixed defaults ``equilibrium_tol`` = 1e-4 and ``dwell`` =
200 were set there. This script runs the classification corpus of
``tests/classification_corpus.py`` (random drive, N, eta and start of the asymmetric
set) with the belt speed (``vb`` and ``vb0``) replaced by a slower one, and labels
each case

- with the fixed defaults (1e-4, 200): ``fixed``;
- with the defaults that follow the belt speed
  (:func:`stickslip_fast.core.settings.default_equilibrium_tol`, ``default_dwell``):
  ``scaled``;

in two windows: the presets' ``t_end`` = 3000 (points after 2000) and one as long in
belt travel, 3000 x 0.0112 / v_b. Each label is set against the *settled* run of the
case: 9000 x 0.0112 / v_b time units, judged on the last third, with
``equilibrium_tol`` = 1e-3 v_b (ten times tighter than the scaled default) and the
scaled ``dwell``: ``same``, ``false`` or ``none found`` as in
:func:`classification_corpus.verdict`; ``false equilibrium`` counts the false labels
that call a moving case at rest (``equilibrium`` or ``stalled``), and ``no crossing in
window`` those that say ``no-crossings`` (moving, with no minimum of x1 in the window)
where the settled run has an orbit or is at rest: in the presets' window of 1000 time
units, shorter than a slow belt's period or than a slow creep to a stall, that can be
true of the window.

    python3 -m benchmarks.belt_speed [--vb 1e-3 3e-4 1e-4] [--cases 60]

Result: ``results/belt_speed_<date>.json``, with the machine.
"""

from __future__ import annotations

import time
from pathlib import Path

from .loose_labels import corpus_start, write_corpus_result

RESULTS = Path(__file__).resolve().parent / "results"
VB = (0.0112, 1e-3, 3e-4, 1e-4)
PRESET_VB = 0.0112
SEED = 2026
AT_REST = ("equilibrium", "stalled")


def _count(labels, settled, cc) -> dict:
    v = [cc.verdict(a, b) for a, b in zip(labels, settled, strict=True)]
    false_rest = sum(
        1 for a, b, w in zip(labels, settled, v, strict=True)
        if w == "false" and a[0] in AT_REST and b[0] not in AT_REST
    )  # fmt: skip
    no_crossing = sum(
        1 for a, b, w in zip(labels, settled, v, strict=True)
        if w == "false" and a[0] == "no-crossings"
    )  # fmt: skip
    return {**{k: v.count(k) for k in ("same", "false", "none found")},
            "false equilibrium": false_rest, "no crossing in window": no_crossing}  # fmt: skip


def main(argv=None) -> int:
    from stickslip_fast.core.settings import default_dwell

    args, cc, cases, started, t0 = corpus_start(__doc__, "belt_speed", "vb", VB, 60, argv, SEED)
    rows = []
    for vb in args.vb:
        stretch = PRESET_VB / vb
        t = time.perf_counter()
        settled = cc.run(cases, vb=vb, t_end=9000.0 * stretch, t_transient=6000.0 * stretch,
                         equilibrium_tol=1e-3 * vb, dwell=default_dwell(vb))  # fmt: skip
        settled_s = time.perf_counter() - t
        for window in ("presets'", "belt travel"):
            s = 1.0 if window == "presets'" else stretch
            for rule in ("fixed", "scaled"):
                fixed = dict(equilibrium_tol=1e-4, dwell=200.0) if rule == "fixed" else {}
                t = time.perf_counter()
                labels = cc.run(cases, vb=vb, t_end=3000.0 * s, t_transient=2000.0 * s,
                                **fixed)  # fmt: skip
                row = dict(vb=vb, window=window, t_end=3000.0 * s, rule=rule,
                           cases=len(cases), wall_s=time.perf_counter() - t,
                           settled_wall_s=settled_s, **_count(labels, settled, cc))  # fmt: skip
                rows.append(row)
                print(f"vb {vb:g}, t_end {3000.0 * s:g}, {rule}: same {row['same']}, false "
                      f"{row['false']} ({row['false equilibrium']} at rest, "
                      f"{row['no crossing in window']} no-crossings), none found "
                      f"{row['none found']} ({row['wall_s']:.1f} s)", flush=True)  # fmt: skip
    write_corpus_result(args.out, started, t0, rows, seed=SEED)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
