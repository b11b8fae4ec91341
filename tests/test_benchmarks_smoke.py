"""Smoke test of the benchmark suite: `benchmarks/run.py --quick` runs and writes its files.

Checks structure, not timings. Quick mode skips the start-up benchmark's empty-cache
run (it compiled every kernel again: ~75 s of the suite); the full run keeps it.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("scipy")
pytest.importorskip("psutil")


def test_quick_benchmark_suite(tmp_path):
    out = tmp_path / "bench"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "run.py"), "--quick", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    results = json.loads((out / "results.json").read_text())
    assert results["mode"] == "quick"
    for key in ("cpu_model", "cores", "numba", "numpy", "scipy"):
        assert key in results["machine"]
    sec = results["sections"]
    assert set(sec) == {
        "work_precision",
        "sweep_throughput",
        "parallel_scaling",
        "n_scaling",
        "startup",
        "memory",
        "peers_trajectory",
        "peers_diagram",
        "kernel_profile",
        "converged_stopping",
        "tableaus",
        "first_run",
        "auto_tolerance_rules",
        "multirate_bound",
    }
    # issue 30's targets compile cold and time for minutes: full run only
    for name in ("first_run", "auto_tolerance_rules", "multirate_bound"):
        assert sec[name]["status"] == "skipped", name
    tb = sec["tableaus"]["cases"]["asymmetric_eta9.99"]["tables"]["1e-06"]
    assert set(tb) == {"rodas5p", "rodas4p", "rodas4p2"}
    # the 6-stage tableaus take more steps for the same accuracy (docs/model.md)
    assert tb["rodas4p"]["steps"] > tb["rodas5p"]["steps"]
    conv = sec["converged_stopping"]
    # converged stopping on Fig. 6 gives the fixed window's status and period
    # (docs/converged.md: 100 of 100 values on this diagram)
    assert conv["n_values"] == 60 and conv["agree_status_period"] == 60
    assert conv["steps_converged"] < conv["steps_fixed"]
    wp = sec["work_precision"]
    assert set(wp["trajectories"]) == {
        "asymmetric_eta2.0",
        "asymmetric_eta9.99",
        "literature_eta2.7",
    }
    for tr in wp["trajectories"].values():
        assert tr["reference"]["n_points"] >= 2
        assert "engine rodas5p" in tr["curves"]
        assert "scipy LSODA" in tr["curves"]
    assert set(wp["ratios"]) == set(wp["trajectories"])
    for name in ("fig6", "fig2"):
        rec = sec["sweep_throughput"][name]
        assert rec["trajectories_per_s"] > 0 and rec["poincare_points_per_s"] >= 0
    assert 0 < sec["parallel_scaling"]["efficiency"]
    assert sec["n_scaling"]["rows"][0]["N"] == 1
    assert sec["startup"]["cached_start_s"] > 0
    assert sec["memory"]["status"] in ("ok", "pending")
    # peers: the engine and SciPy LSODA always run; optional peers are either run or explained
    pt = sec["peers_trajectory"]["cases"]["asymmetric_eta9.99"]
    rows = pt["tables"]["1e-06"]["rows"]
    assert rows["engine rodas5p"]["time_points"] > 0
    assert rows["scipy LSODA"]["rtol"] is not None
    for name, r in rows.items():  # the chosen setting really meets the target (vs SciPy Radau)
        if r.get("rtol") is not None:
            assert r["error"] <= 1e-6, name
    pd = sec["peers_diagram"]
    assert pd["solvers"]["engine rodas5p"]["scans"]
    assert sum(pd["ref_status_counts"].values()) == pd["config"]["n_values"]
    # the replica Rodas5P driver (dense 4x4, same tableau) is itself accurate against the
    # independent SciPy Radau reference: rtol 1e-7 gives points within 1e-5
    pk = sec["kernel_profile"]
    row = pk["cases"]["asymmetric_eta9.99"][0]
    assert row["replica rodas5p"]["error"] <= 1e-5
    assert pk["ingredients_ns_plain_4x4"]["rhs"] > 0
    summary = (out / "summary.md").read_text()
    assert "## Headline" in summary
    assert "## Issue 30" not in summary  # no target section from skipped sections
    assert "## Peers: per-trajectory" in summary and "## Kernel profile" in summary
    assert (out / "work_precision.png").stat().st_size > 0
    assert (out / "n_scaling.png").stat().st_size > 0
