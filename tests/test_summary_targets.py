"""The table of issue 30's targets in the benchmark summary (benchmarks/summary_targets.py).

Built from a hand-made ``results.json`` section dictionary, so every verdict and every
number of the table is known: a target met, a target missed, and the floor beside it.
"""

from __future__ import annotations

import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import summary_targets  # noqa: E402
from benchmarks.summary import _verdict  # noqa: E402


def _cold(*walls, **extra):
    runs = [dict(wall_s=w, cpu_s=w - 1.0, **extra) for w in walls]
    return dict(runs=runs, median_wall_s=statistics.median(walls),
                median_cpu_s=statistics.median(w - 1.0 for w in walls))  # fmt: skip


def _sections():
    first_run = dict(
        status="ok",
        targets=dict(first_simulate_cold_s=10.0, readme_main_job_cold_s=25.0),
        jobs_result=dict(
            first_simulate=dict(cold=_cold(28.0, 30.0), cached=dict(wall_s=1.2)),
            driver_floor=dict(
                cold=dict(
                    runs=[dict(driver_s=12.0, setup_s=3.0), dict(driver_s=14.0, setup_s=2.0)]
                ),
                cached=dict(wall_s=1.0),
            ),
            readme_main_job=dict(cold=_cold(20.0, 24.0), cached=dict(wall_s=9.0)),
        ),
    )
    auto_row = dict(speedup_vs_peer=2.6, speedup_vs_peer_at_floor=3.18, auto_over_floor=1.22)
    fair_row = dict(speedup_vs_peer=2.19, speedup_vs_peer_at_floor=2.74, auto_over_floor=1.25)
    auto = dict(
        status="ok",
        cases={"2": dict(tables={
            "1e-06": dict(benchmark_rule=dict(auto=fair_row), best_rule=dict(auto=auto_row)),
            "1e-08": dict(benchmark_rule=dict(auto=dict(speedup_vs_peer=3.34)),
                          best_rule=dict(auto=dict(speedup_vs_peer=2.26))),
        }),
        # a run made before the fair rule's floor was measured: the best rule's alone
        "9.99": dict(tables={
            "1e-06": dict(benchmark_rule=dict(auto=dict(speedup_vs_peer=3.1)),
                          best_rule=dict(auto=dict(auto_row, speedup_vs_peer_at_floor=4.4))),
        })},
    )  # fmt: skip
    oracle = dict(steps_per_disk_rel_first=1.1)
    multirate = dict(
        status="ok",
        rows=[
            dict(N=8, oracle=dict(steps_per_disk_rel_first=1.0), break_even_passes=1.0,
                 break_even_passes_at_floor=1.0),
            dict(N=512, oracle=oracle, break_even_passes=0.5, break_even_passes_at_floor=0.8,
                 relaxation=dict(passes_mean=3.0, projected_over_monolithic=4.0,
                                 projected_over_monolithic_at_floor=2.0)),
        ],
    )  # fmt: skip
    n_scaling = dict(worst_cost_per_N_rel_N8=2.73, rows=[dict(N=1), dict(N=512)])
    return dict(first_run=first_run, auto_tolerance_rules=auto, multirate_bound=multirate,
                n_scaling=n_scaling)  # fmt: skip


def _row(lines, start):
    (row,) = [line for line in lines if line.startswith(start)]
    return [cell.strip() for cell in row.strip("|").split("|")]


def test_each_target_with_its_verdict_and_floor():
    lines = summary_targets.rows(_sections(), _verdict)
    assert lines[0] == "## Issue 30: the speed targets and their floors"
    first = _row(lines, "| first `simulate`")
    assert first[1:4] == ["29.0 s (28.0 s CPU)", "<= 10 s", "**miss** (2.9x short)"]
    assert "`_run` alone compiles in 13.0 s (its records' setup 2.5 s more)" in first[4]
    job = _row(lines, "| README's main job")
    assert job[1:4] == ["22.0 s (21.0 s CPU)", "<= 25 s", "**pass**"]
    assert (
        job[4]
        == "the cached job takes 9.0 s; with `_run`'s compile above it cannot take less than 22.0 s"
    )
    a6 = _row(lines, "| `auto` vs numbalsoda LSODA, eta = 2, points within 1e-06")
    assert a6[1:4] == ["2.19x / 2.60x", ">= 3x", "**miss** (1.4x short) / **miss** (1.2x short)"]
    assert a6[4] == (
        "with a driver that cost nothing (its attempts at the bare cost of one): fair rule "
        "2.74x / best rule 3.18x; the driver adds 1.25x / 1.22x; with the fair rule `auto`'s "
        "own steps cannot reach 3x"
    )
    old_run = _row(lines, "| `auto` vs numbalsoda LSODA, eta = 9.99, points within 1e-06")
    assert old_run[1:4] == ["3.10x / 2.60x", ">= 3x", "**pass** / **miss** (1.2x short)"]
    assert old_run[4] == (
        "with a driver that cost nothing (its attempts at the bare cost of one) 4.40x; "
        "the driver adds 1.22x"
    )
    a8 = _row(lines, "| `auto` vs numbalsoda LSODA, eta = 2, points within 1e-08")
    assert a8[1:4] == ["3.34x / 2.26x", ">= 2x", "**pass** / **pass**"]
    assert a8[4] == "—"  # no floor measured for that pick
    disk = _row(lines, "| cost per disk")
    assert disk[1:4] == ["2.73x", "<= 1.5x", "**miss** (1.8x short)"]
    assert "1.10x the steps per disk at N = 512 as at N = 8" in disk[4]
    assert (
        "one such pass costs 2.00x the monolithic run (1.25x at the cheapest disk step)" in disk[4]
    )
    assert "3.0 passes per window: 4.00x the monolithic time (2.00x at the floor)" in disk[4]


def test_no_section_when_the_targets_were_skipped():
    skipped = dict(status="skipped", why="full run only")
    sec = dict(first_run=skipped, auto_tolerance_rules=skipped, multirate_bound=skipped,
               n_scaling=dict(worst_cost_per_N_rel_N8=2.0, rows=[dict(N=512)]))  # fmt: skip
    assert summary_targets.rows(sec, _verdict) == []
