"""Markdown summary of a results.json dictionary."""

from __future__ import annotations

from . import summary_peers, summary_targets


def _f(x, fmt="{:.3g}"):
    if x is None or isinstance(x, str):
        return "n/a" if x is None else x
    return fmt.format(x)


def _verdict(value, target, higher_is_better=True):
    if value is None:
        return "n/a"
    ok = value >= target if higher_is_better else value <= target
    if ok:
        return "**pass**"
    short = target / value if higher_is_better else value / target
    return f"**miss** ({short:.2g}x short)"


def write_summary(r):
    m = r["machine"]
    sec = {k: v for k, v in r["sections"].items() if v.get("status") != "error"}
    L = [
        f"# stickslip_fast benchmark summary ({r['mode']} run)",
        "",
        f"Machine: {m['cpu_model']}, {m['cores']} cores, {m.get('memory_total_gb', '?')} GB; "
        f"Python {m['python']}, numpy {m['numpy']}, numba {m['numba']}, scipy {m['scipy']}, "
        + ", ".join(
            f"{d} {m.get(d) or 'not installed'}"
            for d in ("numbalsoda", "scikit-sundae", "diffrax", "jax")
        )
        + f", commit {m.get('git_commit', '?')}. Load average at start "
        f"{', '.join(f'{x:.2f}' for x in m['loadavg_at_start'])}, at end "
        f"{', '.join(f'{x:.2f}' for x in m.get('loadavg_at_end', []))} (shared machine). "
        f"Sweep implementation: `{r['sweep_impl']}`. Total wall time {r['total_wall_s']:.0f} s.",
        "",
    ]
    prev = m.get("previous_run_machine")
    if r.get("merged_runs") and isinstance(prev, dict):
        merged = ", ".join(s for run in r["merged_runs"] for s in run)
        L += [
            f"Sections re-run later and merged into this file: {merged} (the machine line "
            f"above is the latest merge's). The full run: commit {prev.get('git_commit', '?')}, "
            "load average at start "
            f"{', '.join(f'{x:.2f}' for x in prev.get('loadavg_at_start', []))}.",
            "",
        ]
    L += [
        "## Headline",
        "",
        "| measure | value | target | verdict |",
        "|---|---|---|---|",
    ]
    L += summary_peers.headline_rows(sec)
    wp = sec.get("work_precision")
    if wp:
        for key, row in wp["ratios"].items():
            for name, target in (
                ("scipy LSODA", 100.0),
                ("scipy LSODA (NumPy RHS)", 100.0),
                ("numbalsoda LSODA", 2.0),
                ("engine dopri5-fixed", 100.0),
            ):
                c = row.get(name, {})
                ratio = c.get("ratio")
                lb = c.get("ratio_lower_bound")
                if ratio is not None:
                    val, verdict = f"{ratio:.3g}x", _verdict(ratio, target)
                elif lb is not None:
                    val = f">= {lb:.3g}x (extrapolated)"
                    verdict = _verdict(lb, target) + " (bound)"
                else:
                    val, verdict = c.get("how", "n/a"), "n/a"
                L.append(
                    f"| rodas5p speed-up vs {name} at error {wp['target_error']:g}, {key} "
                    f"| {val} | >= {target:g}x | {verdict} |"
                )
    ps = sec.get("parallel_scaling")
    if ps:
        L.append(
            f"| parallel efficiency T1/(p Tp), p={ps['threads']}, {ps['n_values']}-value Fig. 6 "
            f"sweep | {ps['efficiency']:.1%} | >= 90% | {_verdict(ps['efficiency'], 0.9)} |"
        )
    ns = sec.get("n_scaling")
    if ns:
        nmax = ns["rows"][-1]["N"]
        for label, key in (
            ("cost/N per unit time, identical disks", "worst_cost_per_N_rel_N8_identical"),
            ("cost/N per unit time, desynchronized disks", "worst_cost_per_N_rel_N8"),
            ("cost/N per step, desynchronized disks", "worst_cost_per_step_per_N_rel_N8"),
        ):
            w = ns.get(key)
            if w is None:
                continue
            L.append(
                f"| {label}, relative to N=8, worst of N=8..{nmax} (DC motor) "
                f"| {w:.2f}x | <= 1.5x | {_verdict(w, 1.5, higher_is_better=False)} |"
            )
    su = sec.get("startup")
    if su:
        L.append(
            f"| cached start (fresh process: import + first simulate) | {su['cached_start_s']:.2f} s "
            f"| <= 3 s | {_verdict(su['cached_start_s'], 3.0, higher_is_better=False)} |"
        )
    me = sec.get("memory")
    if me:
        if me["status"] == "ok":
            L.append(
                f"| peak RSS ratio, {me['rows'][1]['n_values']} vs {me['rows'][0]['n_values']} "
                f"values to HDF5 | {me['rss_ratio']:.2f} | ~1 (flat) | "
                f"{_verdict(me['rss_ratio'], 1.2, higher_is_better=False)} |"
            )
        else:
            L.append(f"| peak RSS of file-backed sweeps | {me['status']} | flat | pending |")
    cs = sec.get("converged_stopping")
    if cs:
        L.append(
            f"| converged stopping, Fig. 6 {cs['n_values']} values: fixed / converged "
            f"| {cs['best_fixed']:.1f} s / {cs['best_converged']:.1f} s = {cs['speedup']:.1f}x "
            f"({cs['agree_status_period']}/{cs['n_values']} same status and period) | >= 5x "
            f"| {_verdict(cs['speedup'], 5.0)} |"
        )
        c = cs.get("census")
        if c:
            L.append(
                f"| census, 64 starts x 200 values (projected from {c['values']} x "
                f"{c['n_starts']}: {c['ms_per_start']:.1f} ms per start) / fixed "
                f"{c['fixed_sweep_values']}-value sweep | {c['projected_200x64_s']:.0f} s / "
                f"{c['fixed_sweep_s']:.1f} s = {c['ratio_to_fixed_sweep']:.2f}x | <= 1x "
                f"| {_verdict(c['ratio_to_fixed_sweep'], 1.0, higher_is_better=False)} |"
            )
            g = c.get("ratio_to_fixed_sweep_generic_kernel")
            if g is not None:
                L.append(
                    f"| census as above / the same fixed sweep on the generic kernel "
                    f"(bit-identical results) | {c['projected_200x64_s']:.0f} s / "
                    f"{c['fixed_sweep_generic_kernel_s']:.1f} s = {g:.2f}x | <= 1x "
                    f"| {_verdict(g, 1.0, higher_is_better=False)} |"
                )
    L.append("")
    L += summary_targets.rows(sec, _verdict)
    L += summary_peers.readme_rows(r)

    if wp:
        L += ["## Work-precision", "", "![work-precision](work_precision.png)", ""]
        L.append(
            "Error = max abs difference over the full state of the Poincare points (t >= "
            "t_transient) against the engine's rodas5p at rtol=1e-12, atol=1e-14; atol = "
            f"{wp['atol_factor']:g} rtol for all adaptive runs. 'scipy X' and numbalsoda call "
            "the engine's compiled RHS (SciPy also its analytic Jacobian): that compares the "
            "integrators alone. 'scipy LSODA (NumPy RHS)' is what a SciPy user writes: the "
            "independent plain NumPy model and Jacobian of tests/reference/scipy_model.py."
        )
        L.append("")
        for key, tr in wp["trajectories"].items():
            t = tr["trajectory"]
            ref = tr["reference"]
            chk = ref.get("radau_check")
            chk_s = (
                f"Radau rtol=1e-12 check: max |diff| {chk['max_abs_diff']:.2e} "
                f"({chk['time']:.1f} s)"
                if isinstance(chk, dict)
                else str(chk)
            )
            L.append(
                f"### {key}: t_end {t['t_end']:g}, t_transient {t['t_transient']:g}, "
                f"{ref['n_points']} reference points (period {ref['period']}); {chk_s}"
            )
            L.append("")
            L.append("| solver | time at error 1e-6 [s] | how | rodas5p speed-up |")
            L.append("|---|---|---|---|")
            rat = wp["ratios"][key]
            for name, at in tr["time_at_target"].items():
                rr = rat.get(name, {}).get("ratio")
                L.append(f"| {name} | {_f(at['time'])} | {at['how']} | {_f(rr)} |")
            L.append("")
            L.append("<details><summary>all runs</summary>")
            L.append("")
            L.append("| solver | setting | time [s] | error | steps | rejected | note |")
            L.append("|---|---|---|---|---|---|---|")
            for name, pts in tr["curves"].items():
                for p in pts:
                    setting = f"h={p['h']:g}" if "h" in p else f"rtol={p['rtol']:g}"
                    steps = p.get("n_steps", p.get("nfev"))
                    if "nfev" in p and "n_steps" not in p:
                        steps = f"nfev {p['nfev']}"
                    L.append(
                        f"| {name} | {setting} | {_f(p.get('time'))} | {_f(p.get('error'), '{:.2e}')} "
                        f"| {_f(steps, '{}')} | {_f(p.get('n_rejected'), '{}')} | "
                        f"{p.get('note', '') or p.get('status', '')} |"
                    )
            L.append("")
            L.append("</details>")
            L.append("")
        if not wp["numbalsoda"]["available"]:
            L.append(f"numbalsoda: not available ({wp['numbalsoda']['note']}).")
            L.append("")

    st = sec.get("sweep_throughput")
    if st:
        L += [
            "## Sweep throughput (all cores)",
            "",
            "| sweep | values | t_end / t_transient | wall [s] | traj/s | points/s | steps/s | "
            "statuses | wall for 1000 values [s] |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for name in ("fig6", "fig2"):
            s = st.get(name)
            if not s:
                continue
            w1000 = s.get("extrapolated_wall_for_paper_n", s["wall"])
            L.append(
                f"| {name} ({s['preset']}, eta in [1, 10]) | {s['n_values']} | "
                f"{s['t_end']:g} / {s['t_transient']:g} | {s['wall']:.1f} | "
                f"{s['trajectories_per_s']:.1f} | {s['poincare_points_per_s']:.0f} | "
                f"{s['steps_per_s']:.3g} | {s['status_counts']} | "
                f"{w1000:.0f}{' (extrapolated)' if 'note' in s else ''} |"
            )
        L.append("")
    if ps:
        L += [
            "## Parallel scaling",
            "",
            f"Best of alternating runs: T1 = {ps['t1']:.2f} s (all: "
            f"{', '.join(f'{w:.2f}' for w in ps.get('all_walls_1', []))}), T{ps['threads']} = "
            f"{ps['tp']:.2f} s (all: {', '.join(f'{w:.2f}' for w in ps.get('all_walls_p', []))}), "
            "efficiency "
            f"{ps['efficiency']:.1%}; CPU utilisation {ps['cpu_utilisation_1']:.0%} (1 thread), "
            f"{ps['cpu_utilisation_p']:.0%} ({ps['threads']} threads); the static contiguous "
            f"split of the values allows at most {ps['static_split_balance_bound']:.1%} "
            "(step counts per half); interleaving the values over the threads in chunks of "
            f"{ps.get('chunk_assumed', '?')} values with a barrier after each (what ssf.sweep "
            f"does by default) allows at most {_f(ps.get('chunked_dynamic_bound'), '{:.1%}')}. "
            "CPU time T1/Tp "
            f"{ps['cpu_work_ratio']:.2f} (1 = no parallel overhead). Control (identical "
            f"compute-bound tasks, same threads): efficiency {ps['control_before']['efficiency']:.1%} "
            f"before, {ps['control_after']['efficiency']:.1%} after -- what the shared machine "
            "allowed at the time. Load average "
            f"{', '.join(f'{x:.2f}' for x in ps['loadavg'])}.",
            "",
        ]
    if ns:
        L += [
            "## Scaling in N (DC motor, 1 thread)",
            "",
            "![N scaling](n_scaling.png)",
            "",
            "| disks | N | t_end | wall [s] | steps | rejected | us/step | cost/N rel. N=8 | "
            "steps rel. N=8 | cost/step/N rel. N=8 | status |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for scen, key in (("desynchronized", "rows"), ("identical", "rows_identical")):
            for row in ns.get(key, []):
                L.append(
                    f"| {scen} | {row['N']} | {row['t_end']:g} | {row['wall']:.2f} | "
                    f"{row['n_steps']} | {row['n_rejected']} | {row['time_per_step_us']:.2f} | "
                    f"{row['cost_per_N_rel_N8']:.2f} | {row['steps_rel_N8']:.2f} | "
                    f"{row['cost_per_step_per_N_rel_N8']:.2f} | {row['status']} |"
                )
        L += [
            "",
            "Identical disks stay identical, so every N has the same events: that row "
            "isolates the engine's cost per disk (bordered O(N) solves). Desynchronized disks "
            "have ~N times as many stick-slip transitions per unit time, all sharing one step "
            "size, so the step count grows with N while the cost per step stays linear.",
            "",
        ]
    if su:
        rows = [("empty cache", su["cold"]), ("cached", su["cached"])]
        L += [
            "## Start-up",
            "",
            f"Call: {su['call']}.",
            "",
            "| process | total wall [s] | import [s] | first simulate [s] | first sweep [s] |",
            "|---|---|---|---|---|",
        ]
        for name, proc in rows:
            if proc is None:
                L.append(f"| {name} | not run (quick mode) | | | |")
                continue
            L.append(
                f"| {name} | {proc['process_wall_s']:.2f} | {proc['import_s']:.2f} | "
                f"{proc['first_simulate_s']:.2f} | {_f(proc.get('first_sweep_s'), '{:.2f}')} |"
            )
        L.append("")
    if me:
        L += ["## Memory", ""]
        if me["status"] == "ok":
            for row in me["rows"]:
                L.append(
                    f"- {row['n_values']} values: peak RSS {row['peak_rss_mb']:.0f} MB, "
                    f"{row['wall']:.1f} s, file {row['file_mb']:.1f} MB"
                )
        else:
            L.append(f"{me['status']}: {me.get('note', me.get('stderr', ''))}")
        L.append("")
    if "peers_trajectory" in sec:
        L += summary_peers.peers_trajectory(sec["peers_trajectory"])
    if "peers_diagram" in sec:
        L += summary_peers.peers_diagram(sec["peers_diagram"])
    if "kernel_profile" in sec:
        L += summary_peers.kernel_profile(sec["kernel_profile"])
    if "tableaus" in sec and sec["tableaus"].get("status") != "error":
        L += summary_peers.tableaus(sec["tableaus"])
    for name, v in r["sections"].items():
        if v.get("status") == "error":
            L += [f"## {name}: FAILED", "", "```", v["traceback"], "```", ""]
    return "\n".join(L)
