"""Labels of the 900 Hopf-adjacent values of docs/converged.md, with both stop rules.

Usage: ``PYTHONPATH=CHECKOUT python3 grid900.py OUT.json`` (30 x 30 grid, eta in
[1, 1.4], k12 in [-0.05, 0.05], asymmetric set, t_end 3000, 64 points; the fixed
window records after t_transient 2000). Prints the (status, period) counts.
"""

import collections
import json
import sys
import warnings

import numpy as np

import stickslip_fast as ssf

ASYM = ssf.System.preset("asymmetric")
ETA = np.linspace(1.0, 1.4, 30)
K12 = np.linspace(-0.05, 0.05, 30)


def main(out_path: str) -> None:
    print(ssf.__file__, file=sys.stderr)
    out = {}
    warnings.simplefilter("ignore")  # the sweeps' "no orbit" warnings
    for stop in ("fixed", "converged"):
        t_transient = 2000.0 if stop == "fixed" else 0.0
        res = ssf.sweep(
            ASYM, ("eta", "k12"), (ETA, K12), t_end=3000.0, t_transient=t_transient,
            max_points=64, stop=stop, progress=False,
        )  # fmt: skip
        status = np.asarray(res.status).ravel().tolist()
        period = np.asarray(res.period).ravel().tolist()
        out[stop] = {"status": status, "period": period}
        counts = collections.Counter(zip(status, period, strict=True)).most_common()
        print(stop, counts, file=sys.stderr)
    with open(out_path, "w") as fh:
        json.dump(out, fh)


if __name__ == "__main__":
    main(sys.argv[1])
