"""Work-precision: wall time vs Poincare-point error for this engine, SciPy and numbalsoda.

Every solver integrates the same trajectory from y0 = 0 and records the
Poincare points (upward zero crossings of dx1, t >= t_transient). The error of
a run is the largest absolute difference over the full state of its points
and the reference points, matched one to one in time order (a run that finds
a different number of points near the reference times counts as failed).

SciPy gets the engine's own compiled RHS and analytic Jacobian
(``stickslip_fast.model.equations.rhs`` / ``dense_jacobian``) behind a thin Python
wrapper, so the comparison is between integrators, not RHS implementations.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .common import best_time, ssf

ATOL_FACTOR = 1e-2  # atol = 1e-2 rtol for every adaptive solver
TARGET_ERROR = 1e-6
REF_RTOL, REF_ATOL = 1e-12, 1e-14

TRAJECTORIES = {
    "full": [
        dict(key="asymmetric_eta2.0", preset="asymmetric", eta=2.0, t_end=400.0, t_transient=300.0),
        dict(
            key="asymmetric_eta9.99", preset="asymmetric", eta=9.99, t_end=450.0, t_transient=300.0
        ),
        dict(
            key="literature_eta2.7", preset="literature", eta=2.7, t_end=2000.0, t_transient=1000.0
        ),
    ],
    # the CI smoke test's: windows of 30, 80 and 150 time units after a transient of 100
    # (the same points for every solver): the section took 22 s against 33 s with a
    # transient of 300-1000 (one quick run each; ~7 s of it numbalsoda compiling at import)
    "quick": [
        dict(key="asymmetric_eta2.0", preset="asymmetric", eta=2.0, t_end=130.0, t_transient=100.0),
        dict(
            key="asymmetric_eta9.99", preset="asymmetric", eta=9.99, t_end=180.0, t_transient=100.0
        ),
        dict(key="literature_eta2.7", preset="literature", eta=2.7, t_end=250.0, t_transient=100.0),
    ],
}

SETTINGS = {
    "full": dict(
        rodas_rtols=[1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11],
        dopri_rtols=[1e-3, 1e-5, 1e-7, 1e-9],
        fixed_hs=[3e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6],
        fixed_max_steps=30_000_000,
        scipy_rtols={
            "LSODA": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
            "Radau": [1e-4, 1e-6, 1e-8, 1e-10],
            "BDF": [1e-4, 1e-6, 1e-8],
            "DOP853": [1e-5, 1e-8],
        },
        # the baseline users actually write: solve_ivp with a plain NumPy RHS and Jacobian
        scipy_numpy_rtols={"LSODA": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9]},
        scipy_cap=60.0,
        numbalsoda_rtols=[1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
        radau_check=True,
        radau_check_cap=240.0,
    ),
    "quick": dict(
        rodas_rtols=[1e-5, 1e-7, 1e-9],
        dopri_rtols=[1e-5],
        fixed_hs=[1e-4, 2e-5],
        fixed_max_steps=2_000_000,
        scipy_rtols={"LSODA": [1e-6, 1e-8], "Radau": [1e-6]},
        scipy_numpy_rtols={"LSODA": [1e-6]},
        scipy_cap=10.0,
        numbalsoda_rtols=[1e-6, 1e-8],
        radau_check=False,
        radau_check_cap=0.0,
    ),
}


# ----------------------------------------------------------------- error metric
def point_error(t_ref, p_ref, t, p):
    """Max abs state difference of matched points; (error, note).

    Points are matched in time order; if the counts differ, each reference point
    is matched to the nearest-in-time point of the run, within a quarter of the
    smallest reference spacing, else the run fails (error inf).
    """
    t = np.asarray(t)
    p = np.asarray(p)
    if len(t_ref) == 0:
        return math.nan, "no reference points"
    if len(t) == len(t_ref):
        return float(np.max(np.abs(p - p_ref))), ""
    if len(t) == 0:
        return math.inf, "no points"
    spacing = np.min(np.diff(t_ref)) if len(t_ref) > 1 else 1.0
    idx = np.abs(t[None, :] - t_ref[:, None]).argmin(axis=1)
    if np.any(np.abs(t[idx] - t_ref) > 0.25 * spacing):
        return math.inf, f"{len(t)} points vs {len(t_ref)} reference points, unmatched"
    return float(
        np.max(np.abs(p[idx] - p_ref))
    ), f"{len(t)} points vs {len(t_ref)}, matched by time"


# ------------------------------------------------------------------------ engine
def run_engine(system, tr, method, rtol=None, h=None, max_steps=None):
    kw = dict(method=method, max_points=10_000)
    if rtol is not None:
        kw.update(rtol=rtol, atol=ATOL_FACTOR * rtol)
    if h is not None:
        kw.update(h=h, max_steps=max_steps)

    def call():
        return ssf.simulate(system, tr["t_end"], tr["t_transient"], **kw)

    return best_time(call, max_repeats=3, budget=0.5)


# ------------------------------------------------------------------------- SciPy
class _Timeout(Exception):
    pass


def scipy_problem(system, rhs_kind="compiled"):
    """RHS and Jacobian for SciPy.

    ``"compiled"``: the engine's Numba functions behind a thin wrapper (compares
    integrators alone). ``"numpy"``: the independent plain NumPy model in
    tests/reference/scipy_model.py, i.e. what a SciPy user writes.
    """
    if rhs_kind == "numpy":
        import os
        import sys

        here = os.path.dirname(os.path.abspath(__file__))
        sys.path.insert(0, os.path.join(os.path.dirname(here), "tests", "reference"))
        import scipy_model

        params = system.to_dict()
        return (
            lambda t, y: scipy_model.rhs(t, y, params),
            lambda t, y: scipy_model.jac(t, y, params),
        )
    from stickslip_fast.base import jit
    from stickslip_fast.model.equations import dense_jacobian, rhs

    # the twin with Numba's wrapper, called directly (base.jit), where this version has it
    rhs = getattr(jit, "python_callable", lambda f: f)(rhs)
    p = system.to_array()
    n_osc = system.n_oscillators
    dc = system.is_dc_motor
    n = system.n_state

    def f(t, y):
        out = np.empty(n)
        rhs(y, p, n_osc, dc, out)
        return out

    def jac(t, y):
        return dense_jacobian(y, p, n_osc, dc)

    return f, jac


def run_scipy(system, tr, method, rtol, cap, rhs_kind="compiled"):
    """One solve_ivp run with event location; returns a record dict."""
    from scipy.integrate import solve_ivp

    f, jac = scipy_problem(system, rhs_kind)
    f(0.0, system.initial_state())  # compile / load from cache outside the timing
    jac(0.0, system.initial_state())
    state = dict(calls=0, t0=time.perf_counter())

    def f_capped(t, y):
        state["calls"] += 1
        if state["calls"] % 2000 == 0 and time.perf_counter() - state["t0"] > cap:
            raise _Timeout
        return f(t, y)

    def event(t, y):
        return y[1]

    event.direction = 1
    kw = {} if method == "DOP853" else dict(jac=jac)
    y0 = system.initial_state()
    state["t0"] = time.perf_counter()
    try:
        sol = solve_ivp(
            f_capped, (0.0, tr["t_end"]), y0, method=method, rtol=rtol,
            atol=ATOL_FACTOR * rtol, events=event, **kw,
        )  # fmt: skip
    except _Timeout:
        return dict(status="timeout", time=time.perf_counter() - state["t0"], nfev=state["calls"])
    wall = time.perf_counter() - state["t0"]
    te = sol.t_events[0]
    keep = te >= tr["t_transient"]
    return dict(
        status="ok" if sol.status == 0 else f"failed: {sol.message}",
        time=wall,
        nfev=int(sol.nfev),
        njev=int(getattr(sol, "njev", 0)),
        t_points=te[keep],
        points=sol.y_events[0][keep],
    )


# -------------------------------------------------------------------- numbalsoda
def numbalsoda_available():
    try:
        import numbalsoda  # noqa: F401
    except Exception as exc:  # noqa: BLE001
        return False, f"import numbalsoda failed: {exc!r}"
    return True, ""


def run_numbalsoda(system, tr, rtol, dt_eval=0.01):
    """numbalsoda's compiled LSODA (its FD Jacobian) with the njit RHS and the njit Hermite
    crossing finder of :mod:`benchmarks.peers` (output grid only after the transient)."""
    from . import peers

    p = peers.params(system.to_dict())

    def call():
        return peers.numbalsoda_run(
            p, tr["t_end"], tr["t_transient"], rtol, ATOL_FACTOR * rtol, dt=dt_eval
        )

    call()  # compile outside the timing
    wall, (ok, tp, pts) = best_time(call, max_repeats=3, budget=1.0)
    return dict(status="ok" if ok else "failed", time=wall, t_points=tp, points=pts)


# ----------------------------------------------------------------- curve analysis
def pareto(points):
    """(time, error) pairs of successful runs on the lower-left front, by time."""
    good = sorted((p["time"], p["error"]) for p in points if np.isfinite(p.get("error", np.nan)))
    front = []
    for t, e in good:
        if not front or e < front[-1][1]:
            front.append((t, e))
    return front


def time_at_error(points, target=TARGET_ERROR):
    """Wall time to reach error <= target: log-log interpolation on the Pareto front
    when the target is bracketed, else the cheapest run below it. (time, how)."""
    front = pareto(points)
    for j, (t, e) in enumerate(front):
        if e <= target:
            if j == 0:
                return t, "cheapest run already below target (upper bound)"
            t0, e0 = front[j - 1]
            w = (math.log(target) - math.log(e0)) / (math.log(e) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t) - math.log(t0))), "interpolated"
    return None, "target not reached"


# --------------------------------------------------------------------------- main
def reference(system, tr, settings, log):
    """Engine at its tightest tolerance, checked against SciPy Radau rtol=1e-12."""
    wall, ref = run_engine(system, tr, "rodas5p", rtol=REF_RTOL)  # atol = 1e-2 rtol = REF_ATOL
    out = dict(
        method="rodas5p",
        rtol=REF_RTOL,
        atol=REF_ATOL,
        n_points=len(ref.t_poincare),
        period=ref.period,
        status=ref.status,
        t_points=ref.t_poincare.tolist(),
        time=wall,
    )
    if settings["radau_check"]:
        log(f"  reference check: SciPy Radau rtol={REF_RTOL:g} ...")
        from scipy.integrate import solve_ivp

        f, jac = scipy_problem(system)

        def event(t, y):
            return y[1]

        event.direction = 1
        t0 = time.perf_counter()
        sol = solve_ivp(
            f, (0.0, tr["t_end"]), system.initial_state(), method="Radau", rtol=REF_RTOL,
            atol=REF_ATOL, jac=jac, events=event,
        )  # fmt: skip
        te = sol.t_events[0]
        keep = te >= tr["t_transient"]
        err, note = point_error(ref.t_poincare, ref.poincare, te[keep], sol.y_events[0][keep])
        out["radau_check"] = dict(
            rtol=REF_RTOL,
            atol=REF_ATOL,
            time=time.perf_counter() - t0,
            nfev=int(sol.nfev),
            max_abs_diff=err,
            note=note,
        )
        log(
            f"    Radau vs engine reference: max |diff| = {err:.2e} ({out['radau_check']['time']:.1f} s)"
        )
    else:
        out["radau_check"] = "skipped in quick mode"
    return ref, out


def run(mode, log):
    settings = SETTINGS[mode]
    nbl_ok, nbl_why = numbalsoda_available()
    results = dict(
        target_error=TARGET_ERROR,
        atol_factor=ATOL_FACTOR,
        settings={k: v for k, v in settings.items()},
        numbalsoda=dict(available=nbl_ok, note=nbl_why),
        trajectories={},
    )
    for tr in TRAJECTORIES[mode]:
        system = ssf.System.preset(tr["preset"], eta=tr["eta"])
        log(f"work-precision: {tr['key']} (t_end={tr['t_end']}, t_transient={tr['t_transient']})")
        ref, ref_info = reference(system, tr, settings, log)
        curves = {}

        def add(curve, rec, res=None, ref=ref, curves=curves):
            if res is not None:
                rec.update(status=res.status, n_steps=res.n_steps, n_rejected=res.n_rejected)
                if res.status == "ok":
                    rec["error"], rec["note"] = point_error(
                        ref.t_poincare, ref.poincare, res.t_poincare, res.poincare
                    )
                else:
                    rec["error"], rec["note"] = math.inf, f"status {res.status}"
            elif rec.get("status") == "ok":
                rec["error"], rec["note"] = point_error(
                    ref.t_poincare, ref.poincare, rec.pop("t_points"), rec.pop("points")
                )
            else:
                rec.pop("t_points", None)
                rec.pop("points", None)
                rec.setdefault("error", math.inf)
            curves.setdefault(curve, []).append(rec)

        for rtol in settings["rodas_rtols"]:
            wall, res = run_engine(system, tr, "rodas5p", rtol=rtol)
            add("engine rodas5p", dict(rtol=rtol, time=wall), res)
        for rtol in settings["dopri_rtols"]:
            wall, res = run_engine(system, tr, "dopri5", rtol=rtol)
            add("engine dopri5", dict(rtol=rtol, time=wall), res)
        # per-step cost of dopri5-fixed, to extrapolate the runs over the step cap
        cal_h = settings["fixed_hs"][-1]
        cal_steps = min(200_000, math.ceil(tr["t_end"] / cal_h))
        wall, res = run_engine(system, tr, "dopri5-fixed", h=cal_h, max_steps=cal_steps)
        per_step = [wall / max(res.n_steps, 1)]
        for h in settings["fixed_hs"]:
            need = math.ceil(tr["t_end"] / h)
            if need > settings["fixed_max_steps"]:
                est = need * (np.median(per_step) if per_step else math.nan)
                curves.setdefault("engine dopri5-fixed", []).append(
                    dict(
                        h=h,
                        status="skipped",
                        error=math.inf,
                        time=None,
                        note=f"needs {need:.2e} steps > cap {settings['fixed_max_steps']:.0e}; "
                        f"estimated {est:.0f} s",
                        estimated_time=est,
                    )
                )
                continue
            wall, res = run_engine(system, tr, "dopri5-fixed", h=h, max_steps=need + 1)
            per_step.append(wall / max(res.n_steps, 1))
            add("engine dopri5-fixed", dict(h=h, time=wall), res)
        runs = [(m, r, "compiled", f"scipy {m}") for m, r in settings["scipy_rtols"].items()]
        runs += [
            (m, r, "numpy", f"scipy {m} (NumPy RHS)")
            for m, r in settings.get("scipy_numpy_rtols", {}).items()
        ]
        for method, rtols, rhs_kind, curve in runs:
            gave_up = None
            for rtol in rtols:
                if gave_up:
                    curves.setdefault(curve, []).append(
                        dict(rtol=rtol, status="skipped", error=math.inf, time=None, note=gave_up)
                    )
                    continue
                rec = run_scipy(system, tr, method, rtol, settings["scipy_cap"], rhs_kind)
                rec["rtol"] = rtol
                if rec["status"] == "timeout":
                    rec["note"] = f"timeout after {settings['scipy_cap']:.0f} s"
                    gave_up = f"skipped: rtol={rtol:g} already timed out"
                    rec["time"] = None
                elif method == "DOP853" and rec["time"] > 0.25 * settings["scipy_cap"]:
                    gave_up = (
                        f"skipped: rtol={rtol:g} took {rec['time']:.0f} s; explicit DOP853 is "
                        "stability-bound, its cost hardly depends on rtol"
                    )
                add(curve, rec)
                log(
                    f"  {curve} rtol={rtol:g}: {rec['status']} {rec.get('time')} s, err {rec.get('error')}"
                )
        if nbl_ok:
            for rtol in settings["numbalsoda_rtols"]:
                rec = run_numbalsoda(system, tr, rtol)
                rec["rtol"] = rtol
                add("numbalsoda LSODA", rec)
        at = {}
        for name, pts in curves.items():
            t, how = time_at_error(pts)
            at[name] = dict(time=t, how=how)
        results["trajectories"][tr["key"]] = dict(
            trajectory=tr, reference=ref_info, curves=curves, time_at_target=at
        )
        log("  time at error 1e-6: " + ", ".join(f"{k}: {v['time']}" for k, v in at.items()))
    results["ratios"] = ratios(results)
    return results


COMPETITORS = {
    "scipy LSODA": 100.0,
    "scipy LSODA (NumPy RHS)": 100.0,
    "numbalsoda LSODA": 2.0,
    "engine dopri5-fixed": 100.0,
}


def ratios(results):
    """Speed of rodas5p relative to each competitor at error = TARGET_ERROR."""
    out = {}
    for key, tr in results["trajectories"].items():
        at = tr["time_at_target"]
        ours = at.get("engine rodas5p", {}).get("time")
        row = {}
        for name in [*COMPETITORS, "scipy Radau", "scipy BDF", "scipy DOP853", "engine dopri5"]:
            theirs = at.get(name, {}).get("time")
            if ours and theirs:
                row[name] = dict(ratio=theirs / ours, how=at[name]["how"])
            else:
                why = at.get(name, {}).get("how", "not run")
                row[name] = dict(ratio=None, how=why)
                # the fixed-step method may only have estimated (skipped) runs
                if name == "engine dopri5-fixed" and ours:
                    ests = [
                        p["estimated_time"]
                        for p in tr["curves"].get(name, [])
                        if p.get("estimated_time") and np.isfinite(p["estimated_time"])
                    ]
                    if ests:
                        row[name]["ratio_lower_bound"] = min(ests) / ours
                        row[name]["how"] = (
                            "no completed run reached the target; lower bound from the cheapest "
                            "skipped run's extrapolated time"
                        )
        out[key] = row
    return out


def plot(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    trs = results["trajectories"]
    fig, axes = plt.subplots(1, len(trs), figsize=(5.2 * len(trs), 4.4), squeeze=False)
    styles = {
        "engine rodas5p": ("C0", "o", "-"),
        "engine dopri5": ("C1", "s", "-"),
        "engine dopri5-fixed": ("C2", "^", "-"),
        "scipy LSODA": ("C3", "v", "--"),
        "scipy LSODA (NumPy RHS)": ("C3", "v", "-."),
        "scipy Radau": ("C4", "D", "--"),
        "scipy BDF": ("C5", "P", "--"),
        "scipy DOP853": ("C6", "X", "--"),
        "numbalsoda LSODA": ("C7", "*", ":"),
    }
    for ax, tr in zip(axes[0], trs.values()):
        for name, pts in tr["curves"].items():
            xy = [(p["time"], p["error"]) for p in pts if p.get("time") and np.isfinite(p["error"])]
            if not xy:
                continue
            xy.sort()
            c, m, ls = styles.get(name, ("k", ".", "-"))
            x, y = zip(*xy)
            ax.loglog(x, np.maximum(y, 1e-16), ls, color=c, marker=m, label=name, ms=5)
        ax.axhline(results["target_error"], color="grey", lw=0.8, ls=":")
        t = tr["trajectory"]
        ax.set_title(f"{t['preset']} eta={t['eta']} (t_end={t['t_end']:g})", fontsize=10)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel("max |Poincare point error|")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
