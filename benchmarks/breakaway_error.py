"""Where the Poincare points' error is made: the breakaway (issue 30, item 2).

The fair one-trajectory benchmark (:mod:`benchmarks.autoswitch`) runs every solver up a
ladder of tolerances and takes the first rung whose points all lie within the target of
the SciPy Radau reference. The error does not fall steadily along the ladder, for any
solver: Rodas5P at eta = 2.0 is 4.5e-8 off at rtol 1e-7 and 5.8e-7 at 3e-8; numbalsoda's
LSODA 1.8e-6 at 1e-6 and 3.2e-6 at 3e-7. This script finds where in the orbit the error
is made, for one run at each given rtol (asymmetric preset, constant belt, from rest,
t 1500, points after 1000, atol = 0.01 rtol, as in the benchmark):

1. **The points' error** against the Radau reference: max and median over the points.
2. **The error of each period**: from each Poincare point of the run, a tight run
   (Rodas5P, rtol 1e-12, atol 1e-14) to the next crossing, against the run's next point.
   This is the error the run makes in that one period, free of what came before.
3. **Within the worst period**: the run sampled every ``dt`` (its dense output), against
   a tight run from the period's first point; the sample step where that difference
   grows most is the *jump*. Then the same from starts just before the jump: the
   difference 0.1 time units after the jump, from a tight run started at the run's own
   state ``lead`` before it. Its state at the jump tells which event it is (disk 1's slip
   ``v_b - x1'`` and its rotation ``phi1'``).

4. **The ladders at two absolute tolerances** (``--ladder-atol``): each solver's point
   error and time (best of 5, one core, warm) along rtol 1e-6 ... 3e-9, with atol = 0.01
   rtol (the benchmark's rule) and with atol = 1e-4 rtol, which weighs the creep speeds
   of the stick band (of the order of eps) more: the engine's Rodas5P and ``auto``, and
   numbalsoda's LSODA when it imports.

Result: ``results/breakaway_error_<date>.json`` (``--out``), with the machine.

    python3 -m benchmarks.breakaway_error [--eta 2.0] [--rtol 3e-7 1e-7 3e-8]
"""

from __future__ import annotations

import argparse
import functools
import math
import time
from pathlib import Path

import numpy as np

from . import peers
from .common import best_time, machine_info, ssf, write_result
from .reference import trajectory_reference

RESULTS = Path(__file__).resolve().parent / "results"
T_END, T_TRANSIENT = 1500.0, 1000.0
TIGHT = dict(rtol=1e-12, atol=1e-14)
LEADS = (0.1, 0.03, 0.01, 0.003, 0.0)
LADDER = (1e-6, 3e-7, 1e-7, 3e-8, 1e-8, 3e-9)


def _run(system, rtol, method, t_transient=T_TRANSIENT, atol=None, **kw):
    atol = 0.01 * rtol if atol is None else atol
    return ssf.simulate(system, T_END, t_transient, rtol=rtol, atol=atol,
                        max_points=10_000, method=method, **kw)  # fmt: skip


def period_errors(system, points, times) -> np.ndarray:
    """The error each period adds: a tight run from each point to the next crossing."""
    out = np.empty(len(times) - 1)
    for k in range(len(times) - 1):
        span = times[k + 1] - times[k]
        q = ssf.simulate(system, 1.5 * span, 0.0, y0=points[k], max_points=100, **TIGHT)
        j = np.argmin(np.abs(q.t_poincare - span))
        out[k] = np.abs(q.poincare.reshape(-1, 4)[j] - points[k + 1]).max()
    return out


def _tight_difference(system, start, samples, dt) -> np.ndarray:
    """Max-abs difference of ``samples`` from a tight run that starts at ``start``."""
    n = len(samples)
    q = ssf.simulate(system, (n - 1) * dt + 1e-9, 0.0, y0=start, sample_dt=dt, **TIGHT)
    return np.abs(samples - q.y[:n]).max(axis=1)


def worst_period(system, rtol, method, times, k, dt) -> dict:
    """Where in period ``k`` the run's error is made (see the module docstring)."""
    a = _run(system, rtol, method, t_transient=times[k], sample_dt=dt)
    n = int((times[k + 1] - times[k]) / dt)
    d = _tight_difference(system, a.y[0], a.y[: n + 1], dt)
    i_jump = int(np.argmax(np.diff(d)))
    after = min(n, i_jump + int(round(0.1 / dt)))
    y = a.y[i_jump]
    leads = {}
    for lead in LEADS:
        i0 = max(0, i_jump - int(round(lead / dt)))
        leads[f"{lead:g}"] = float(_tight_difference(system, a.y[i0], a.y[i0 : after + 1], dt)[-1])
    return dict(
        period=k, t_start=float(times[k]), jump_offset=float(i_jump * dt),
        error_before_jump=float(d[max(0, i_jump - int(round(0.01 / dt)))]),
        error_after_jump=float(d[after]), error_period_end=float(d[n]),
        slip_at_jump=float(system.vb - y[1]), phi_dot_at_jump=float(y[3]),
        error_after_jump_from_lead=leads,
    )  # fmt: skip


def study(eta: float, rtol: float, method: str, dt: float, log) -> dict:
    system = ssf.System.preset("asymmetric", eta=eta)
    ref = trajectory_reference(eta, T_END, T_TRANSIENT, log=lambda *a: None)
    r = _run(system, rtol, method)
    pts, ts = r.poincare.reshape(-1, 4), r.t_poincare
    row = dict(eta=eta, rtol=rtol, method=method, points=len(ts), steps=int(r.n_steps))
    if len(ts) != len(ref["t"]):
        log(f"  eta {eta} {method} rtol {rtol:g}: {len(ts)} points, reference {len(ref['t'])}")
        return row
    dev = np.abs(pts - np.asarray(ref["points"])).max(axis=1)
    per = period_errors(system, pts, ts)
    k = int(np.argmax(per))
    row.update(point_error_max=float(dev.max()), point_error_median=float(np.median(dev)),
               period_error_max=float(per.max()), period_error_median=float(np.median(per)),
               worst=worst_period(system, rtol, method, ts, k, dt))  # fmt: skip
    w = row["worst"]
    log(
        f"  eta {eta} {method} rtol {rtol:g}: points max {dev.max():.1e} median "
        f"{np.median(dev):.1e}; period error median {np.median(per):.1e}, max {per.max():.1e} "
        f"(period {k}); in it the error jumps at +{w['jump_offset']:.4f} (slip "
        f"{w['slip_at_jump']:.1e}, phi1' {w['phi_dot_at_jump']:.1e}) from "
        f"{w['error_before_jump']:.1e} to {w['error_after_jump']:.1e}; made from "
        + ", ".join(f"-{lead}: {v:.1e}" for lead, v in w["error_after_jump_from_lead"].items())
    )
    return row


def ladders(eta: float, atol_factor: float, log) -> dict:
    """Point error and time of each solver along :data:`LADDER` at atol = factor * rtol."""
    system = ssf.System.preset("asymmetric", eta=eta)
    ref = np.asarray(trajectory_reference(eta, T_END, T_TRANSIENT, log=lambda *a: None)["points"])
    p = peers.params(system.to_dict())
    runners = {
        m: (lambda rtol, m=m: _run(system, rtol, m, atol=atol_factor * rtol).poincare)
        for m in ("rodas5p", "auto")
    }
    if peers.numbalsoda_available()[0]:
        runners["numbalsoda LSODA"] = lambda rtol: peers.numbalsoda_run(
            p, T_END, T_TRANSIENT, rtol, atol_factor * rtol
        )[2]
    out = {}
    for name, run in runners.items():
        rows = []
        for rtol in LADDER:
            pts = np.asarray(run(rtol)).reshape(-1, 4)
            err = float(np.abs(pts - ref).max()) if pts.shape == ref.shape else np.inf
            best, _ = best_time(functools.partial(run, rtol), max_repeats=5, budget=math.inf)
            rows.append(dict(rtol=rtol, error=err, time=best))
        out[name] = rows
        log(
            f"  eta {eta} atol {atol_factor:g} rtol, {name}: "
            + "  ".join(f"{r['rtol']:g}: {r['error']:.1e} {r['time'] * 1e3:.1f} ms" for r in rows)
        )
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eta", type=float, nargs="*", default=[2.0, 9.99])
    ap.add_argument("--rtol", type=float, nargs="*", default=[3e-7, 1e-7, 3e-8, 1e-8])
    ap.add_argument("--method", nargs="*", default=["rodas5p", "auto"])
    ap.add_argument("--dt", type=float, default=1e-4, help="sample step within a period")
    ap.add_argument(
        "--ladder-atol",
        type=float,
        nargs="*",
        default=[0.01, 1e-4],
        help="atol / rtol of the ladders (none: skip them)",
    )
    ap.add_argument(
        "--out", type=Path, default=RESULTS / f"breakaway_error_{time.strftime('%Y-%m-%d')}.json"
    )
    args = ap.parse_args(argv)

    def log(msg):
        print(msg, flush=True)

    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    t0 = time.perf_counter()
    rows = [study(eta, rtol, m, args.dt, log)
            for eta in args.eta for m in args.method for rtol in args.rtol]  # fmt: skip
    ladder = {f"{f:g}": {f"{eta:g}": ladders(eta, f, log) for eta in args.eta}
              for f in args.ladder_atol}  # fmt: skip
    result = dict(machine=machine_info(), started=started, rows=rows, dt=args.dt,
                  ladders=ladder, wall=time.perf_counter() - t0)  # fmt: skip
    write_result(args.out, result, log)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
