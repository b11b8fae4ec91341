"""The breakaway study of docs/performance.md ("Where the points' error is made").

Its claims, on one of its runs (Rodas5P at eta = 2.0, rtol 1e-7, against the stored
SciPy Radau reference): on the period-1 orbit every period adds the same error; in a
period the error jumps at disk 1's breakaway, where the slip is of the order of eps;
and the last 0.03 time units before the jump make it.
"""

import numpy as np
import pytest

breakaway = pytest.importorskip("benchmarks.breakaway_error")


def test_the_error_of_a_period_is_made_just_before_the_breakaway():
    row = breakaway.study(2.0, 1e-7, "rodas5p", 1e-4, log=lambda *a: None)
    assert row["points"] == 52  # the reference's count: every point matched
    assert row["point_error_max"] < 1e-6
    # the steps repeat from period to period on the orbit, and so does their error
    assert row["period_error_max"] == pytest.approx(row["period_error_median"], rel=1e-2)
    w = row["worst"]
    assert 6.48 < w["jump_offset"] < 6.50  # into the period of about 9.64
    assert abs(w["slip_at_jump"]) < 3e-5  # within a few eps = 1e-5 of the belt speed
    assert w["error_after_jump"] > 20 * w["error_before_jump"]
    leads = w["error_after_jump_from_lead"]
    assert leads["0.03"] == pytest.approx(leads["0.1"], rel=0.05)
    assert leads["0"] < 0.05 * leads["0.1"]
    assert np.isfinite(list(leads.values())).all()
