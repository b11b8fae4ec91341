"""Markdown for the peer sections (peers_trajectory, peers_diagram) and kernel_profile."""

from __future__ import annotations

import math


def _ms(x):
    return (
        "n/a" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x * 1e3:.3g}"
    )


def _x(x):
    return "n/a" if x is None else f"{x:.2f}x"


def _e(x):
    if x is None or isinstance(x, str):
        return str(x)
    return f"{x:.1e}"


def headline_rows(sec) -> list[str]:
    """Headline-table rows: engine speed-up against the fastest peer (issue 11 targets)."""
    L = []
    pt = sec.get("peers_trajectory")
    if pt and pt.get("status") != "error":
        for key, case in pt["cases"].items():
            for tgt, target in (("1e-06", 3.0), ("1e-08", 2.0)):
                tab = case["tables"].get(tgt)
                if not tab:
                    continue
                sp = tab.get("engine_speedup_vs_fastest")
                verdict = "n/a" if sp is None else ("**pass**" if sp >= target else "**miss**")
                L.append(
                    f"| engine speed-up vs the fastest peer ({tab.get('fastest_peer')}), "
                    f"Poincare error <= {float(tgt):g}, {key}, t 1500, 1 core | {_x(sp)} | "
                    f">= {target:g}x | {verdict} |"
                )
    pd = sec.get("peers_diagram")
    if pd and pd.get("status") != "error":
        sp = pd.get("engine_speedup_vs_fastest")
        verdict = "n/a" if sp is None else ("**pass**" if sp >= 10 else "**miss**")
        L.append(
            f"| engine ({pd.get('engine_best', 'engine rodas5p')}) speed-up vs the fastest peer "
            f"({pd.get('fastest_peer')}), Fig. 6 diagram "
            f"({pd['config']['n_values']} values), >= 99 % agreement, {pd['cores']} cores | "
            f"{_x(sp)} | >= 10x | {verdict} |"
        )
    return L


def _work(r) -> str:
    """Steps (engine) or RHS calls (numbalsoda) of the timed run, where recorded."""
    if "steps" in r:
        return f"{r['steps']} steps + {r['rejected']} rejected"
    if "rhs_evaluations" in r:
        return f"{r['rhs_evaluations']} RHS calls"
    return ""


def peers_trajectory(pt) -> list[str]:
    L = ["## Peers: per-trajectory work-precision (issue 11)", ""]
    s = pt["settings"]
    L.append(
        "Asymmetric preset, constant belt, from rest to t = 1500, Poincare points after "
        "t = 1000. Reference: SciPy Radau rtol 1e-12 / atol 1e-14 on the independent NumPy "
        "model (cached in results/reference_trajectories.json). Each solver at the first "
        f"rtol of the ladder (loose to tight, atol = {s['atol_factor']:g} rtol) whose points "
        "all lie within the target of the reference; then every solver timed at its rtol in "
        f"alternating rounds (best of {s['rounds']}, one core). 'points' = with Poincare "
        "points; 'integration' = the same solver without output grid or event function. "
        "Speed-up = peer time / engine time (> 1: the engine is faster)."
    )
    L.append("")
    for name, note in pt["solver_notes"].items():
        L.append(f"- **{name}**: {note}")
    for name, why in pt.get("unavailable", {}).items():
        L.append(f"- **{name}**: not run: {why}")
    L.append("")
    for key, case in pt["cases"].items():
        ref = case["reference"]
        L.append(f"### {key} ({ref['n_points']} reference points)")
        L.append("")
        for tgt, tab in case["tables"].items():
            L.append(f"Target: every point within {float(tgt):g}.")
            L.append("")
            L.append(
                "| solver | rtol | error | with points [ms] | integration only [ms] | "
                "engine speed-up (points) | engine speed-up (integration) | work |"
            )
            L.append("|---|---|---|---|---|---|---|---|")
            for name, r in tab["rows"].items():
                if r.get("rtol") is None:
                    L.append(f"| {name} | - | - | - | - | - | {r.get('note', '')} | |")
                    continue
                L.append(
                    f"| {name} | {r['rtol']:g} | {_e(r['error'])} | {_ms(r['time_points'])} | "
                    f"{_ms(r['time_integration'])} | {_x(r.get('engine_speedup_points'))} | "
                    f"{_x(r.get('engine_speedup_integration'))} | {_work(r)} |"
                )
            L.append("")
        L.append("<details><summary>ladder scans (single untimed-quality runs)</summary>")
        L.append("")
        for name, scan in case["scans"].items():
            L.append(f"- {name}: " + ", ".join(f"{x['rtol']:g} -> {_e(x['error'])}" for x in scan))
        L.append("")
        L.append("</details>")
        L.append("")
    return L


def peers_diagram(pd) -> list[str]:
    c = pd["config"]
    L = ["## Peers: Fig. 6 diagram work-precision (issue 11)", ""]
    L.append(
        f"{c['n_values']} values of eta in [1, 10], t_end {c['t_end']:g}, t_transient "
        f"{c['t_transient']:g}, asymmetric preset, constant belt, from rest. Reference: "
        f"{pd['reference']['method']} (engine rtol 1e-11 agrees on "
        f"{(pd['reference'].get('engine_check') or {}).get('n_agree', '?')}/"
        f"{(pd['reference'].get('engine_check') or {}).get('n_compared', '?')} values). A value "
        "agrees when status (rest / no-crossings / ok) and period match and, if periodic, the "
        f"last 64 points lie within {pd['rule']['point_tol']:g}; a setting passes at >= 99 %. "
        f"Reference statuses: {pd['ref_status_counts']}. Each solver's ladder is scanned loose "
        "to tight and stops at the first pass. Engine, numbalsoda (prange) and diffrax (vmap) "
        f"use all {pd['cores']} cores and are re-timed side by side (best of 2); SciPy and "
        f"CVODE run every {c['subset_every']}th value serially, their time is extrapolated "
        f"to {c['n_values']} values and divided by {pd['cores']} cores (ideal parallelism, "
        "in their favour)."
    )
    L.append("")
    for name, why in pd.get("unavailable", {}).items():
        L.append(f"- **{name}**: not run: {why}")
    L.append("")
    L.append("| solver | rtol | agree | time [s] | engine speed-up | scan (rtol: agree, s) |")
    L.append("|---|---|---|---|---|---|")
    for name, rec in pd["solvers"].items():
        ch = rec.get("chosen")
        scan = "; ".join(
            f"{x['rtol']:g}: {x['n_agree']}/{x['n_compared']}, {x['wall_s']:.1f}"
            for x in rec["scans"]
        )
        if ch is None:
            L.append(f"| {name} | not reached | - | - | - | {scan} |")
            continue
        t = rec.get("time_s")
        extra = " (extrapolated)" if "wall_s_extrapolated" in ch else ""
        L.append(
            f"| {name} | {ch['rtol']:g} | {ch['n_agree']}/{ch['n_compared']} | "
            f"{'n/a' if t is None else f'{t:.3g}'}{extra} | {_x(rec.get('engine_speedup'))} | {scan} |"
        )
    L.append("")
    L.append(
        "![diagram work-precision](diagram_work_precision.png) (each solver's ladder: share of "
        "the values agreeing with the reference against the time for all values; open markers: "
        "extrapolated from the values run; the chosen rung at its re-timed time)"
    )
    L.append("")
    return L


def kernel_profile(pk) -> list[str]:
    L = ["## Kernel profile: where a Rodas5P step's time goes (issue 11, part 2)", ""]
    pl = pk["ingredients_ns_plain_4x4"]
    en = pk["ingredients_ns_engine"]
    L.append("ns per call, `@njit` loops, one core:")
    L.append("")
    L.append("| ingredient | engine's function | plain 4-state / dense 4x4 |")
    L.append("|---|---|---|")
    for k, label in (
        ("rhs", "RHS"),
        ("jacobian", "Jacobian"),
        ("factor", "factor W = I/(h gamma) - J"),
        ("solve", "one solve with W"),
        ("error_norm", "error norm"),
        ("error_norm+controller", "error norm + PI controller (2 pow)"),
        ("rosenbrock_step", "one whole `rosenbrock_step` call (factor, 7 RHS, 8 solves)"),
    ):
        L.append(f"| {label} | {_n(en.get(k))} | {_n(pl.get(k))} |")
    ss = pk["rodas5p_attempt_sum_ns"]
    L.append(
        f"| **sum for one Rodas5P attempt** (8 RHS, 1 Jacobian, 1 factor, 8 solves, norm) | "
        f"{_n(ss.get('engine'))} | {_n(ss.get('plain'))} |"
    )
    if "note" in en:
        L.append("")
        L.append(f"Engine pieces: {en['note']}")
    L.append("")
    L.append(
        "Whole runs (t 1500, points after 1000), best of 3: the engine (`ssf.simulate`) "
        "against replica drivers in benchmarks/profile_kernel.py (same tableau and PI "
        "controller, dense 4x4, Hermite crossings). 'att' = accepted + rejected attempts; "
        "error against the SciPy Radau reference."
    )
    L.append("")
    for key, rows in pk["cases"].items():
        L.append(f"### {key}")
        L.append("")
        names = [k for k in rows[0] if k != "rtol"]
        L.append("| rtol | " + " | ".join(names) + " |")
        L.append("|---|" + "---|" * len(names))
        for row in rows:
            cells = []
            for n in names:
                r = row[n]
                jac = f", {r['jacobians']} J" if "jacobians" in r and "J every" in n else ""
                cells.append(
                    f"{r['time_ms']:.1f} ms, {r['steps']}+{r['rejected']} att "
                    f"({r['rejected_fraction']:.0%} rej{jac}), {r['ns_per_attempt']:.0f} ns/att, "
                    f"err {_e(r['error'])}"
                )
            L.append(f"| {row['rtol']:g} | " + " | ".join(cells) + " |")
        L.append("")
        L.append(
            "Stick-slip transitions (replica rodas5p; stick = |dx1 - v_b| < "
            f"{pk['stick_v']:g}, 'near' = within {pk['near']:g} time units of a switch):"
        )
        L.append("")
        L.append(
            "| rtol | switches | attempts near / all | rejections near / all | "
            "time near / simulated | accepted steps sticking |"
        )
        L.append("|---|---|---|---|---|---|")
        for row in rows:
            tr = row.get("replica rodas5p", {}).get("transitions")
            if not tr:
                continue
            L.append(
                f"| {row['rtol']:g} | {tr['n_switches']} | {tr['attempts_near']}/{tr['attempts']} "
                f"({tr['attempts_near'] / max(tr['attempts'], 1):.0%}) | {tr['rejected_near']}/"
                f"{tr['rejected']} ({tr['rejected_near'] / max(tr['rejected'], 1):.0%}) | "
                f"{tr['time_near']:.0f}/{tr['sim_time']:.0f} | "
                f"{tr['stick_fraction_of_accepted']:.0%} |"
            )
        L.append("")
    return L


def tableaus(tb) -> list[str]:
    """The engine's Rosenbrock tableaus at matched accuracy (issue 11, part 2)."""
    L = ["## Rosenbrock tableaus at matched accuracy (issue 11, part 2)", ""]
    L.append(
        "Each method at the first rtol of the ladder whose Poincare points are all within the "
        "target of the SciPy Radau reference; best of the alternating rounds, one core. "
        "'att' = accepted + rejected step attempts."
    )
    L.append("")
    for key, case in tb["cases"].items():
        for tgt, rows in case["tables"].items():
            L.append(f"### {key}, Poincare error <= {tgt}")
            L.append("")
            L.append("| method | rtol | ms | steps | rejected | ns/att | speed-up vs rodas5p |")
            L.append("|---|---|---|---|---|---|---|")
            for m, r in rows.items():
                if r.get("rtol") is None:
                    L.append(f"| {m} | {r.get('note', 'n/a')} | | | | | |")
                    continue
                L.append(
                    f"| {m} | {r['rtol']:g} | {_ms(r['time'])} | {r['steps']} | "
                    f"{r['rejected']} | {r['ns_per_attempt']:.0f} | "
                    f"{_x(r.get('speedup_vs_rodas5p'))} |"
                )
            L.append("")
    return L


def _n(x):
    return "n/a" if x is None else f"{x:.0f}"


def readme_rows(r) -> list[str]:
    """A performance table for the top-level README: only the peer sections of this run."""
    sec = r["sections"]
    pt = sec.get("peers_trajectory")
    pd = sec.get("peers_diagram")
    if not pt or pt.get("status") == "error":
        return []
    m = r["machine"]
    L = [
        "## Rows for the top-level README",
        "",
        f"Measured by `benchmarks/run.py` (sections peers_trajectory and peers_diagram of one "
        f"run) on {m['cpu_model']}, {m['cores']} cores shared with other jobs (load average "
        f"{', '.join(f'{x:.1f}' for x in m['loadavg_at_start'])} at start). Times at the "
        "cheapest rtol (atol = 0.01 rtol) that meets the accuracy; speed-up = peer time / "
        "engine time (below 1: the engine is slower).",
        "",
        "| case | accuracy | engine (rodas5p) | fastest peer | engine speed-up |",
        "|---|---|---|---|---|",
    ]
    for key, case in pt["cases"].items():
        for tgt, tab in case["tables"].items():
            e = tab["rows"].get("engine rodas5p", {})
            fp = tab.get("fastest_peer")
            f = tab["rows"].get(fp, {}) if fp else {}
            if not e.get("rtol") or not f.get("rtol"):
                continue
            L.append(
                f"| {key}, t 1500, 1 core | points within {float(tgt):g} | "
                f"{e['time_points'] * 1e3:.1f} ms (rtol {e['rtol']:g}) | {fp}: "
                f"{f['time_points'] * 1e3:.1f} ms (rtol {f['rtol']:g}) | "
                f"{tab['engine_speedup_vs_fastest']:.2f}x |"
            )
    if pd and pd.get("status") != "error" and pd.get("fastest_peer"):
        f = pd["solvers"][pd["fastest_peer"]]
        for name, e in pd["solvers"].items():
            if not name.startswith("engine") or not e.get("time_s"):
                continue
            L.append(
                f"| Fig. 6 diagram, {pd['config']['n_values']} values, {pd['cores']} cores | "
                f">= 99 % same status/period, points within 1e-6 | {name}: {e['time_s']:.1f} s "
                f"(rtol {e['chosen']['rtol']:g}) | {pd['fastest_peer']}: {f['time_s']:.1f} s "
                f"(rtol {f['chosen']['rtol']:g}) | {f['time_s'] / e['time_s']:.2f}x |"
            )
    L.append("")
    return L
