"""What each Lyapunov exponent costs: ``lyapunov_spectrum`` with k = 1 .. 4 on one orbit.

The period-1 orbit of the asymmetric set at eta = 2.0 (Fig. 6), started on the orbit
(``find_orbit``), warm kernels, each k run ``--repeats`` times in turn over the same
window (``--periods`` periods, no transient). k = 1 and 2 are the directions that do
not stick; k = 3 and 4 add the two that the stick phase locks, whose exponents are of
order -1000 and force steps on their time scale. For each k: the best wall time, the
steps, the exponents, the mean divergence and how far the exponents' sum is from it
(Liouville's formula: with k = 4 it must vanish).

    python -m benchmarks.lyapunov_spectrum --repeats 3 --out benchmarks/results/lyapunov_spectrum.json
"""

from __future__ import annotations

import argparse
import json
import time

import stickslip_fast as ssf

from .common import machine_info


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--periods", type=float, default=4.0)
    ap.add_argument("--out", help="JSON file for the results")
    args = ap.parse_args()

    system = ssf.System.preset("asymmetric", eta=2.0)
    orbit = ssf.find_orbit(system, ssf.simulate(system, 3000, stop="converged"))
    t_end = args.periods * orbit.T
    ssf.lyapunov_spectrum(system, 1.0, 0.0, y0=orbit.points[0], k=1)  # compile
    rows = []
    for k in (1, 2, 3, 4):
        best, spec = float("inf"), None
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            spec = ssf.lyapunov_spectrum(system, t_end, 0.0, y0=orbit.points[0], k=k)
            best = min(best, time.perf_counter() - t0)
        row = dict(
            k=k, seconds=best, steps=spec.n_steps, exponents=spec.exponents.tolist(),
            divergence=spec.divergence, sum_minus_divergence=float(spec.exponents.sum()
                                                                   - spec.divergence),
            resolved=spec.resolved.tolist(),
        )  # fmt: skip
        rows.append(row)
        print(f"k={k}: {best:.3f} s, {spec.n_steps} steps, exponents {spec.exponents}, "
              f"divergence {spec.divergence:.6g}", flush=True)  # fmt: skip
    result = dict(machine=machine_info(), t_end=t_end, period=orbit.T,
                  multipliers=[abs(m) for m in orbit.multipliers], runs=rows)  # fmt: skip
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(result, fh, indent=1)


if __name__ == "__main__":
    main()
