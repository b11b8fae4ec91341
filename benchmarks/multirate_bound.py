"""Many disks on one DC motor: what a partitioned (multirate) integrator could gain (issue 30).

With N desynchronised disks on one motor, the engine's single step size must resolve
every disk's stick-slip switches, so its step count grows with N while its cost per
disk and step stays flat (``n_scaling``). A multirate method lets every disk take its
own steps. The disks are coupled only through the belt speed v_b, so the natural one is
waveform relaxation: guess v_b(t) on a window, integrate every disk alone against it,
recompute v_b from the motor equation (linear in v_b), repeat until v_b stops changing.

This benchmark measures, in one run and on one thread, what decides whether such a
method can pay, with the engine's own Rodas5P driver and step-size controller:

``oracle``
    One pass with v_b(t) already known (interpolated from a tight monolithic
    reference run): every disk integrated alone over the whole run. Its steps per
    disk are what a partition can reach at best; ``monolithic / oracle`` is the most
    passes per window a waveform relaxation may take and still break even. The
    oracle's disk step here costs ~2x the monolithic run's per disk, so the break-even
    is also given at a *floor*: the oracle's attempts at the cheapest disk step
    measured (a one-disk constant-belt run's, or the monolithic run's per disk,
    whichever is less).
``relaxation``
    Jacobi waveform relaxation over windows of length ``--window``: the passes it
    needs per window until v_b changes by at most one tolerance (atol + rtol |v_b|)
    at every grid point (at most 30), the change after each pass, and its accuracy.
    Its cost is projected as its attempted disk steps (all passes) at the oracle's
    cost per attempt, and at the floor's. Its own wall time is also recorded; it holds
    this script's overheads (a spline per pass in Python, samples at every grid point,
    arrays allocated per pass).

Every run starts from the ``n_scaling`` start carried ``--settle`` time units
further by a tight monolithic run (past the motor's spin-up; from the near-synchronous
start the disks drift apart only slowly). The monolithic ``simulate`` runs at
``--rtol``, the oracle and the relaxation at ``--partition-rtol`` (default: the same;
tighter to match the monolithic run's accuracy); every run's samples of all disks are
compared with the reference run (rtol ``--ref-rtol``).

Per disk the integrated state is z = (x, x', phi, phi', t, r): the disk, the time
(so that the Rosenbrock method sees an autonomous system) and the motor's response to
this disk alone, T_b r' = -r + beta T_s(x' - v_b, phi') with r = 0 at the window start
T. The motor equation is linear in v_b, so it gives v_b exactly at every grid point::

    v_b(T + tau) = exp(-tau/T_b) (v_b(T) - v_b0) + v_b0 + mean_i r_i(tau)

r is the v_b response all N disks would give if they moved as this one: v_b takes the
mean of the r_i, so its error is no larger than the disks' errors in r, which their
controllers hold to the tolerance. (An earlier form integrated each disk's share of
v_b, beta / (N T_b) int exp((s - T) / T_b) T_s ds: there the errors of N disks added up
in v_b, and the change from pass to pass stalled at 25-39 tolerances for N = 512.)

v_b(t) reaches a disk as the C4 quintic spline through its values on a grid of
spacing ``--ds``. The error norm is the driver's default (RMS over the six
components; t has no error). With v_b constant, a disk reproduces a constant-belt
``simulate`` (tests/test_multirate_bound.py).

The disk's problem record is in ``benchmarks/multirate_disk.py``. The driver's Numba
cache index would record it, a type from outside the package, so the script compiles
into a cache folder of its own (it re-executes itself with ``NUMBA_CACHE_DIR`` set when
it is not).

Run::

    python3 -m benchmarks.multirate_bound          # N = 8, 32, 128, 512, t_end 10
    python3 -m benchmarks.multirate_bound --settle 20 --t-end 5 --partition-rtol 1e-9
    python3 -m benchmarks.multirate_bound --n 2 4 --t-end 2 --settle 5 --no-relaxation

Results: ``benchmarks/results/multirate_bound.json`` (or ``--out``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

import stickslip_fast as ssf
from benchmarks.common import best_time, desynchronised_start, machine_info
from benchmarks.multirate_disk import N_STATE, force_of_disks, integrate_disks, quintic
from stickslip_fast.model.params import P_BETA, P_EPS, P_ETAP, P_TB, P_VB0

RESULTS = Path(__file__).resolve().parent / "results"
# the driver's cache index would name the benchmark's problem record: keep it out of the
# package's own cache folders
CACHE = Path(tempfile.gettempdir()) / "stickslip_fast_multirate_bound"


# ----------------------------------------------------------------------- the runs
def desynchronised(n: int, settle: float, rtol: float):
    """``n_scaling``'s start (the asymmetric set on a DC motor, x_i and phi_i offset by up to
    1e-3, v_b = 0), then ``settle`` time units of a monolithic run at ``rtol``: past the
    motor's spin-up, the disks in their stick-slip motion."""
    system, y0 = desynchronised_start(n)
    if settle > 0.0:
        r = ssf.simulate(system, settle, 0.0, y0=y0, rtol=rtol, atol=1e-3 * rtol, max_points=10)
        if r.t_final != settle:
            raise RuntimeError(f"the settling run ended at t = {r.t_final}, not {settle}")
        y0 = r.final_state.copy()
    return system, y0


def _disk_error(states_a, states_b, n):
    """Largest difference of the disks' components (x, x', phi, phi') between two (k, n_state)."""
    return float(np.max(np.abs(states_a[:, : 4 * n] - states_b[:, : 4 * n])))


def _samples_as_full(samples, n):
    """(N, k, 6) per-disk samples -> (k, 4N) full-state layout."""
    return np.ascontiguousarray(
        samples[:, :, :4].transpose(1, 0, 2).reshape(samples.shape[1], 4 * n)
    )


def _start(y0, n, t0):
    z = np.zeros((n, N_STATE))
    z[:, :4] = y0[: 4 * n].reshape(n, 4)
    z[:, 4] = t0
    return z


def oracle(system, y0, ref, t_end, ds, rtol, atol):
    """One pass with the reference's v_b(t): a callable giving (status, steps (N, 2), samples)."""
    n = system.n_oscillators
    p = system.to_array()
    if abs(ref.t[1] - ref.t[0] - ds) > 1e-12 * ds or ref.t[0] != 0.0:
        raise ValueError("the reference's samples are not the grid 0, ds, 2 ds, ...")
    coef = quintic(ref.t, ref.y[:, 4 * n])
    n_grid = ref.t.size

    def run(sampled=False):
        z = _start(y0, n, 0.0)
        # timed without samples (the monolithic run is timed without them too)
        samples = np.empty((n, n_grid if sampled else 1, N_STATE))
        steps = np.zeros((n, 2), dtype=np.int64)
        st = integrate_disks(p, z, 0.0, ds, coef, 0.0, t_end, ds, samples, rtol, atol, steps)
        return st, steps, samples

    return run


def relaxation(system, y0, t_end, window, ds, rtol, atol, max_passes=30):
    """Jacobi waveform relaxation over windows: a callable giving the run's record.

    Each pass integrates every disk over the window against the v_b(t) of the last
    pass (the first guess: the tangent at the window start), then recomputes v_b on
    the grid from the motor equation and the disks' motor responses. The window is
    done when v_b moved by at most atol + rtol |v_b| at every grid point.
    """
    n = system.n_oscillators
    p = system.to_array()
    tb, vb0, beta, eps, etap = p[P_TB], p[P_VB0], p[P_BETA], p[P_EPS], p[P_ETAP]
    n_win = int(round(t_end / window))
    per_win = int(round(window / ds))
    tau = np.arange(per_win + 1) * ds
    decay = np.exp(-tau / tb)
    r_scale = beta  # r: the v_b response all disks would give if they moved alike

    def run():
        z = _start(y0, n, 0.0)
        vb_now = float(y0[4 * n])
        one = z[:, None, :].copy()
        dvb_now = (
            vb0 - vb_now + beta / n * force_of_disks(one, np.array([vb_now]), eps, etap)[0]
        ) / tb
        steps = np.zeros((n, 2), dtype=np.int64)
        passes, stalls, worst, history = [], 0, 0, []
        out_samples = np.empty((n, n_win * per_win + 1, N_STATE))
        vb_all = np.empty(n_win * per_win + 1)
        for w in range(n_win):
            t_win = w * window
            z[:, 4] = t_win  # each disk's clock, and its motor response from the window start
            z[:, 5] = 0.0
            vb = vb_now + dvb_now * tau
            tol = atol + rtol * abs(vb_now)
            history.append([])
            for k in range(1, max_passes + 1):  # noqa: B007 - k is the passes taken
                zw = z.copy()
                samples = np.empty((n, tau.size, N_STATE))
                st = integrate_disks(p, zw, t_win, ds, quintic(t_win + tau, vb), r_scale,
                                     window, ds, samples, rtol, atol, steps)  # fmt: skip
                worst = max(worst, st)
                vb_new = decay * (vb_now - vb0) + vb0 + samples[:, :, 5].mean(axis=0)
                change = float(np.max(np.abs(vb_new - vb)))
                history[-1].append(change / tol)
                vb_seen, vb = vb, vb_new
                if change <= tol:
                    break
            else:
                stalls += 1
            passes.append(k)
            z = zw
            lo = w * per_win
            out_samples[:, lo : lo + per_win + 1] = samples
            vb_all[lo : lo + per_win + 1] = vb
            vb_now = float(vb[-1])
            force = force_of_disks(samples[:, -1:], vb_seen[-1:], eps, etap)[0]
            dvb_now = (vb0 - vb_now + beta / n * force) / tb
        return dict(passes=passes, stalls=stalls, status=worst, steps=steps,
                    samples=out_samples, vb=vb_all, history=history)  # fmt: skip

    return run


def one_disk_attempt_ns(rtol, atol, rounds):
    """The engine's cheapest disk step: ns per attempted step of a one-disk constant-belt run."""
    system = ssf.System.preset("asymmetric", n_oscillators=1)

    def run():
        return ssf.simulate(system, 300.0, 0.0, rtol=rtol, atol=atol, max_points=10)

    run()
    wall, r = best_time(run, max(rounds, 3), math.inf)
    return wall / (r.n_steps + r.n_rejected) * 1e9


def measure(n, args, log, attempt_ns):
    system, y0 = desynchronised(n, args.settle, args.ref_rtol)
    t_end, ds, rtol = args.t_end, args.ds, args.rtol
    atol = 1e-3 * rtol
    row = dict(N=n, t_end=t_end, rtol=rtol, atol=atol, ds=ds, settle=args.settle)
    ref = ssf.simulate(system, t_end, 0.0, y0=y0, rtol=args.ref_rtol, atol=1e-3 * args.ref_rtol,
                       sample_dt=ds, max_points=10)  # fmt: skip
    row["reference_steps"] = int(ref.n_steps)

    def mono(sample_dt=None):
        return ssf.simulate(system, t_end, 0.0, y0=y0, rtol=rtol, atol=atol, sample_dt=sample_dt,
                            max_points=10)  # fmt: skip

    mono()
    wall, res = best_time(mono, args.rounds, math.inf)
    m = row["monolithic"] = dict(
        wall=wall, steps=int(res.n_steps), rejected=int(res.n_rejected),
        error=_disk_error(mono(ds).y, ref.y, n),
        ns_per_disk_attempt=wall / ((res.n_steps + res.n_rejected) * n) * 1e9,
    )  # fmt: skip
    # the partitioned runs may take a tighter rtol, for the monolithic run's accuracy
    prtol = args.partition_rtol or rtol
    row["partition_rtol"] = prtol
    run = oracle(system, y0, ref, t_end, ds, prtol, 1e-3 * prtol)
    run()
    wall, (st, steps, _) = best_time(run, args.rounds, math.inf)
    attempts = int(steps.sum())
    o = row["oracle"] = dict(
        wall=wall, status=int(st), steps_per_disk=float(steps[:, 0].mean()),
        rejected_per_disk=float(steps[:, 1].mean()),
        error=_disk_error(_samples_as_full(run(True)[2], n), ref.y, n),
        ns_per_disk_attempt=wall / attempts * 1e9,
    )  # fmt: skip
    # the cheapest disk step measured: a one-disk run's, or the monolithic run's per disk
    o["floor_ns_per_disk_attempt"] = min(attempt_ns, m["ns_per_disk_attempt"])
    o["floor_wall"] = attempts * o["floor_ns_per_disk_attempt"] * 1e-9
    row["steps_per_disk_over_monolithic_steps"] = o["steps_per_disk"] / m["steps"]
    row["break_even_passes"] = m["wall"] / o["wall"]
    row["break_even_passes_at_floor"] = m["wall"] / o["floor_wall"]
    log(f"N={n}: monolithic {m['wall']:.3f} s ({m['steps']} steps, error {m['error']:.1e}); "
        f"oracle {o['wall']:.3f} s ({o['steps_per_disk']:.0f} steps per disk, "
        f"error {o['error']:.1e}); break-even {row['break_even_passes']:.2f} passes "
        f"({row['break_even_passes_at_floor']:.2f} at the floor)")  # fmt: skip
    if args.relaxation:
        wr = relaxation(system, y0, t_end, args.window, ds, prtol, 1e-3 * prtol)
        wall, rec = best_time(wr, 1, math.inf)
        err = _disk_error(_samples_as_full(rec["samples"], n), ref.y, n)
        vb_err = float(np.max(np.abs(rec["vb"] - ref.y[:, 4 * n])))
        passes = np.asarray(rec["passes"])
        r = row["relaxation"] = dict(
            window=args.window, wall=wall, status=int(rec["status"]),
            passes_mean=float(passes.mean()), passes_max=int(passes.max()),
            passes=passes.tolist(), windows_not_converged=int(rec["stalls"]),
            change_over_tol=rec["history"],
            steps_per_disk=float(rec["steps"][:, 0].mean()), error=err, vb_error=vb_err,
            wall_with_overheads=wall,
        )  # fmt: skip
        # its wall time here holds this script's overheads (a spline per pass in Python,
        # samples at every grid point, arrays allocated per pass): priced instead as its
        # attempted disk steps (every pass) at the oracle's cost per attempt, and the floor's
        wr_attempts = int(rec["steps"].sum())
        r["attempts_per_disk"] = wr_attempts / n
        r["projected_over_monolithic"] = wr_attempts * o["ns_per_disk_attempt"] * 1e-9 / m["wall"]
        r["projected_over_monolithic_at_floor"] = (
            wr_attempts * o["floor_ns_per_disk_attempt"] * 1e-9 / m["wall"]
        )
        log(f"  relaxation: {r['passes_mean']:.2f} passes per window (max {r['passes_max']}, "
            f"{r['windows_not_converged']} not converged), error {r['error']:.1e}; projected "
            f"{r['projected_over_monolithic']:.2f}x the monolithic time "
            f"({r['projected_over_monolithic_at_floor']:.2f}x at the floor)")  # fmt: skip
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[8, 32, 128, 512])
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--settle", type=float, default=50.0, help="time run before the start")
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument(
        "--partition-rtol", type=float, default=None,
        help="rtol of the oracle and the relaxation (default: --rtol)",
    )  # fmt: skip
    ap.add_argument("--ref-rtol", type=float, default=1e-11)
    ap.add_argument("--ds", type=float, default=0.0005, help="grid spacing of v_b and the samples")
    ap.add_argument("--window", type=float, default=1.0, help="relaxation window length")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--no-relaxation", dest="relaxation", action="store_false")
    ap.add_argument("--out", type=Path, default=RESULTS / "multirate_bound.json")
    args = ap.parse_args(argv)
    if "NUMBA_CACHE_DIR" not in os.environ:
        # the driver's cache index would record PrescribedBelt, a type from outside the package:
        # compile into a cache of this benchmark's own (and run in one thread)
        os.environ["NUMBA_CACHE_DIR"] = str(CACHE)
        os.execv(sys.executable, [sys.executable, "-m", "benchmarks.multirate_bound", *(
            sys.argv[1:] if argv is None else argv)])  # fmt: skip
    numba.set_num_threads(1)
    rows = []
    t0 = time.perf_counter()
    attempt_ns = one_disk_attempt_ns(args.rtol, 1e-3 * args.rtol, args.rounds)
    print(f"one disk, constant belt: {attempt_ns:.0f} ns per attempted step")
    for n in args.n:
        rows.append(measure(n, args, print, attempt_ns))
    base = rows[0]
    for r in rows:
        for key in ("monolithic", "oracle"):
            r[key]["cost_per_disk_rel_first"] = (r[key]["wall"] / r["N"]) / (
                base[key]["wall"] / base["N"]
            )
        r["oracle"]["steps_per_disk_rel_first"] = (
            r["oracle"]["steps_per_disk"] / base["oracle"]["steps_per_disk"]
        )
        r["monolithic"]["steps_rel_first"] = r["monolithic"]["steps"] / base["monolithic"]["steps"]
    out = dict(
        benchmark="multirate_bound", machine=machine_info(),
        command=" ".join(
            ["python3 -m benchmarks.multirate_bound", *(sys.argv[1:] if argv is None else argv)]
        ),
        settings=vars(args) | {"out": str(args.out)}, wall_s=time.perf_counter() - t0,
        one_disk_ns_per_attempt=attempt_ns, rows=rows,
    )  # fmt: skip
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=1, default=float))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
