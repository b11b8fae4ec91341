"""The fair benchmark with each solver at its best tolerance rule (benchmarks/atol_rules.py)."""

import math

import pytest

rules = pytest.importorskip("benchmarks.atol_rules")
reference = pytest.importorskip("benchmarks.reference")


def _rows(*pairs):
    return [dict(rtol=r, error=e, time=t) for r, e, t in pairs]


def test_pick_takes_the_cheapest_first_rung_over_the_rules():
    ladders = {
        "0.01": _rows((1e-6, 2e-6, 4.0), (3e-7, 9e-7, 5.0), (1e-7, 1e-9, 6.0)),
        "0.0001": _rows((1e-5, 5e-7, 4.5), (3e-6, 1e-7, 4.0)),  # later rungs are not looked at
    }
    got = rules.pick(ladders, 1e-6)
    assert (got["rule"], got["rtol"], got["time"]) == (1e-4, 1e-5, 4.5)
    got = rules.pick(ladders, 1e-8)
    assert (got["rule"], got["rtol"]) == (0.01, 1e-7)
    assert rules.pick(ladders, 1e-12) is None
    assert rules.pick({"0.01": _rows((1e-6, math.inf, 1.0))}, 1e-6) is None


def test_weighing_the_creep_makes_the_error_follow_rtol():
    # docs/performance.md, "Each solver at its best tolerance rule": with atol = 0.01 rtol
    # Rodas5P at eta = 9.99 is 1.7e-5 off at rtol 1e-6 and 3.7e-8 at 1e-7; with
    # atol = 1e-4 rtol 4.3e-8 and 3.6e-9 (the stored SciPy Radau reference)
    ref = reference.trajectory_reference(9.99, rules.T_END, rules.T_TRANSIENT, log=lambda *a: None)
    run = rules.runners(9.99)["rodas5p"]
    loose = rules.ladder(run, ref, 0.01, rungs=(1e-6, 1e-7), repeats=1)
    weighed = rules.ladder(run, ref, 1e-4, rungs=(1e-6, 1e-7), repeats=1)
    assert [r["error"] for r in loose] == pytest.approx([1.7e-5, 3.7e-8], rel=0.1)
    assert [r["error"] for r in weighed] == pytest.approx([4.3e-8, 3.6e-9], rel=0.1)
