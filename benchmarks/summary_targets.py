"""Issue 30's targets beside the floors that bound them, from one ``results.json``.

Every number comes from the same run (``speed_targets.py``, and the ``n_scaling``
section for the cost per disk), so that each target reads as met, or as missed with the
measurement that says why, on one machine.
"""

from __future__ import annotations

import statistics

GOALS = {"1e-06": 3.0, "1e-08": 2.0}


def _ok(section) -> bool:
    return bool(section) and section.get("status") == "ok"


def _first_run_rows(fr: dict, verdict) -> list[str]:
    jobs, goal = fr["jobs_result"], fr["targets"]  # the goals first_run.run records
    L = []
    sim, floor, job = (jobs.get(k) for k in ("first_simulate", "driver_floor", "readme_main_job"))
    driver = None
    if floor:
        driver = statistics.median(r["driver_s"] for r in floor["cold"]["runs"])
        setup = statistics.median(r["setup_s"] for r in floor["cold"]["runs"])
    if sim:
        wall, cpu = sim["cold"]["median_wall_s"], sim["cold"]["median_cpu_s"]
        why = "—"
        if driver is not None:
            why = (f"the classified driver run `_run` alone compiles in {driver:.1f} s (its "
                   f"records' setup {setup:.1f} s more): a first `simulate` cannot compile "
                   "in less with this driver")  # fmt: skip
        L.append(
            f"| first `simulate`, empty cache (median of {len(sim['cold']['runs'])}; cached "
            f"{sim['cached']['wall_s']:.1f} s) | {wall:.1f} s ({cpu:.1f} s CPU) "
            f"| <= {goal['first_simulate_cold_s']:g} s "
            f"| {verdict(wall, goal['first_simulate_cold_s'], False)} | {why} |"
        )
    if job:
        wall, cpu = job["cold"]["median_wall_s"], job["cold"]["median_cpu_s"]
        cached = job["cached"]["wall_s"]
        why = "—"
        if driver is not None:  # the sweep kernel runs `_run` too: its compile is a floor
            why = (f"the cached job takes {cached:.1f} s; with `_run`'s compile above it "
                   f"cannot take less than {cached + driver:.1f} s")  # fmt: skip
        L.append(
            f"| README's main job (`stickslip-fast sweep` of Fig. 6), empty cache (cached "
            f"{cached:.1f} s) | {wall:.1f} s ({cpu:.1f} s CPU) "
            f"| <= {goal['readme_main_job_cold_s']:g} s "
            f"| {verdict(wall, goal['readme_main_job_cold_s'], False)} | {why} |"
        )
    return L


def _auto_floor_text(fair: dict, best: dict, goal: float) -> str:
    """What a free driver would give: each pick's attempts at the bare cost of one.

    Runs before the fair rule's floor was measured hold the best rule's alone.
    """
    best_floor = best.get("speedup_vs_peer_at_floor")
    if best_floor is None:
        return "—"
    head = "with a driver that cost nothing (its attempts at the bare cost of one)"
    fair_floor = fair.get("speedup_vs_peer_at_floor")
    if fair_floor is None:
        return f"{head} {best_floor:.2f}x; the driver adds {best['auto_over_floor']:.2f}x"
    text = (f"{head}: fair rule {fair_floor:.2f}x / best rule {best_floor:.2f}x; the driver "
            f"adds {fair['auto_over_floor']:.2f}x / {best['auto_over_floor']:.2f}x")  # fmt: skip
    if fair_floor < goal:
        text += f"; with the fair rule `auto`'s own steps cannot reach {goal:g}x"
    return text


def _auto_rows(au: dict, verdict) -> list[str]:
    L = []
    for eta, case in au["cases"].items():
        for tgt, table in case["tables"].items():
            goal = GOALS.get(tgt)
            fair_row = table.get("benchmark_rule", {}).get("auto", {})
            fair = fair_row.get("speedup_vs_peer")
            best = table.get("best_rule", {}).get("auto", {})
            ratio = best.get("speedup_vs_peer")
            if goal is None or ratio is None:
                continue
            why = _auto_floor_text(fair_row, best, goal)
            fair_txt = "n/a" if fair is None else f"{fair:.2f}x"
            L.append(
                f"| `auto` vs numbalsoda LSODA, eta = {eta}, points within {tgt}: fair rule / "
                f"each at its best rule | {fair_txt} / {ratio:.2f}x | >= {goal:g}x "
                f"| {verdict(fair, goal)} / {verdict(ratio, goal)} | {why} |"
            )
    return L


def _disk_rows(ns: dict | None, mr: dict | None, verdict) -> list[str]:
    if not ns or ns.get("worst_cost_per_N_rel_N8") is None:
        return []
    worst = ns["worst_cost_per_N_rel_N8"]
    nmax = ns["rows"][-1]["N"]
    why = "—"
    if _ok(mr) and mr["rows"]:
        last, first = mr["rows"][-1], mr["rows"][0]
        o = last["oracle"]
        why = (f"a partition with v_b known (the oracle) takes "
               f"{o['steps_per_disk_rel_first']:.2f}x the steps per disk at N = {last['N']} "
               f"as at N = {first['N']}, and one such pass costs "
               f"{1 / last['break_even_passes']:.2f}x the monolithic run "
               f"({1 / last['break_even_passes_at_floor']:.2f}x at the cheapest disk step)")  # fmt: skip
        rel = last.get("relaxation")
        if rel:
            why += (
                f"; waveform relaxation takes {rel['passes_mean']:.1f} passes per window: "
                f"{rel['projected_over_monolithic']:.2f}x the monolithic time "
                f"({rel['projected_over_monolithic_at_floor']:.2f}x at the floor)"
            )
    return [
        f"| cost per disk, desynchronised disks on a DC motor, N = 8 .. {nmax} (`n_scaling`) "
        f"| {worst:.2f}x | <= 1.5x | {verdict(worst, 1.5, False)} | {why} |"
    ]


def rows(sec: dict, verdict) -> list[str]:
    """The markdown section: a table of issue 30's targets, or nothing if none was run.

    ``verdict(value, target, higher_is_better=True)`` words a comparison with its target
    (``summary._verdict``, the headline table's).
    """
    fr, au, mr = (sec.get(k) for k in ("first_run", "auto_tolerance_rules", "multirate_bound"))
    if not any(_ok(s) for s in (fr, au, mr)):
        return []
    L = [
        "## Issue 30: the speed targets and their floors",
        "",
        "Each target beside what bounds it, measured in this run (`speed_targets.py`; "
        "docs/performance.md has the method of each).",
        "",
        "| target | this run | target | verdict | what bounds it (this run) |",
        "|---|---|---|---|---|",
    ]
    if _ok(fr):
        L += _first_run_rows(fr, verdict)
    if _ok(au):
        L += _auto_rows(au, verdict)
    L += _disk_rows(sec.get("n_scaling"), mr, verdict)
    return L + [""]
