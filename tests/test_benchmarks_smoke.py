"""Smoke test of the benchmark suite: `benchmarks/run.py --quick` runs and writes its files.

Checks structure, not timings. Takes about a minute on 2 cores (most of it the
start-up benchmark compiling into an empty Numba cache).
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
    }
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
    summary = (out / "summary.md").read_text()
    assert "## Headline" in summary
    assert (out / "work_precision.png").stat().st_size > 0
    assert (out / "n_scaling.png").stat().st_size > 0
