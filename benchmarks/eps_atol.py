"""The default atol against a sharper friction law (a smaller eps).

A sticking disk creeps at slip speeds of the order of the friction law's eps, and the
error control weighs a speed against ``atol + rtol |speed|``. The presets all have
eps = 1e-5, where the default atol 1e-11 is 1e-6 eps. This script runs the
classification corpus of ``tests/classification_corpus.py`` (200 random drive, N, eta
and start of the asymmetric set) with eps replaced by 1e-3 ... 1e-10, at the default
rtol and ``t_end`` 3000, for several atol:

- 1e-11, the fixed default before :func:`stickslip_fast.core.settings.default_atol`;
- 1e-3, 1e-4 and 1e-6 eps (the last is ``default_atol(eps)`` for eps <= 1e-5),

and sets each label against the *settled* run of the same case (3x longer, judged on
the last third) at atol = 1e-7 eps: ``same``, ``false`` or ``none found`` as in
:func:`classification_corpus.verdict`. A settled run that itself failed
(``step-underflow``, ``max-steps``, ``nonfinite``) is counted apart, as ``settled
failed``, whatever the label.

    python3 -m benchmarks.eps_atol [--eps 1e-5 1e-8 ...] [--cases 200]

Result: ``results/eps_atol_<date>.json``, with the machine. About 1 min per eps on one
2-core VM.
"""

from __future__ import annotations

import time
from pathlib import Path

from .loose_labels import corpus_start, write_corpus_result

RESULTS = Path(__file__).resolve().parent / "results"
EPS = (1e-3, 1e-4, 1e-5, 1e-7, 1e-8, 1e-9, 1e-10)
#: atol per eps of the labelled runs; None: the old fixed default 1e-11.
ATOL_PER_EPS = (None, 1e-3, 1e-4, 1e-6)
SETTLED_ATOL_PER_EPS = 1e-7
FAILED = ("step-underflow", "max-steps", "nonfinite")
SEED = 2026


def main(argv=None) -> int:
    args, cc, cases, started, t0 = corpus_start(__doc__, "eps_atol", "eps", EPS, 200, argv, SEED)
    rows = []
    for eps in args.eps:
        t = time.perf_counter()
        settled = cc.run(cases, eps=eps, atol=SETTLED_ATOL_PER_EPS * eps, max_steps=10**8,
                         **cc.SETTLED)  # fmt: skip
        settled_s = time.perf_counter() - t
        for per_eps in ATOL_PER_EPS:
            atol = 1e-11 if per_eps is None else per_eps * eps
            t = time.perf_counter()
            labels = cc.run(cases, eps=eps, atol=atol, t_end=cc.T_END)
            wall = time.perf_counter() - t
            v = [
                "settled failed" if b[0] in FAILED else cc.verdict(a, b)
                for a, b in zip(labels, settled, strict=True)
            ]
            row = dict(eps=eps, atol=atol, atol_per_eps=atol / eps, cases=len(cases),
                       wall_s=wall, settled_wall_s=settled_s,
                       **{k: v.count(k) for k in ("same", "false", "none found",
                                                  "settled failed")})  # fmt: skip
            rows.append(row)
            print(f"eps {eps:g} atol {atol:g} ({atol / eps:g} eps): same {row['same']}, "
                  f"false {row['false']}, none found {row['none found']}, settled failed "
                  f"{row['settled failed']} ({wall:.1f} s)", flush=True)  # fmt: skip
    write_corpus_result(args.out, started, t0, rows, seed=SEED)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
