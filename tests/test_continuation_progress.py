"""The progress bar over a continuation's points (bifurcation/progress.py)."""

from __future__ import annotations

import re

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.bifurcation import progress

ASYM = ssf.System.preset("asymmetric", eta=2.0)
DC = ssf.System.preset("asymmetric", drive="dc-motor", eta=2.0)


def _last_count(err: str) -> tuple[int, int]:
    """The last 'n/total' that a tqdm bar wrote."""
    counts = re.findall(r"(\d+)/(\d+) \[", err)
    assert counts, err
    n, total = counts[-1]
    return int(n), int(total)


@pytest.fixture(scope="module")
def sliding():
    return ssf.find_equilibrium(ASYM, "sliding")


def test_a_branch_shows_its_points_and_is_unchanged(sliding, capsys):
    kw = dict(ds=0.1, ds_max=0.5)
    quiet = ssf.continue_equilibrium(sliding, "eta", (1.0, 10.0), progress=False, **kw)
    assert capsys.readouterr().err == ""
    shown = ssf.continue_equilibrium(sliding, "eta", (1.0, 10.0), progress=True, **kw)
    err = capsys.readouterr().err
    assert "continue_equilibrium eta" in err
    # every point counted once (the start is the first), and the bar ends full
    assert _last_count(err) == (len(shown.values), len(shown.values))
    assert f"eta={shown.values[-1]:.10g}" in err
    # nothing computed depends on the bar
    assert shown.status == quiet.status
    assert np.array_equal(shown.values, quiet.values)
    assert np.array_equal(shown.points, quiet.points)
    assert np.array_equal(shown.multipliers, quiet.multipliers)


def test_by_default_only_on_a_terminal(sliding, capsys):
    ssf.continue_equilibrium(sliding, "eta", (1.0, 3.0), ds=0.1, ds_max=0.5)
    assert capsys.readouterr().err == ""  # pytest's captured stderr is not a terminal


def test_a_curve_shows_both_parameters(capsys):
    e = ssf.find_equilibrium(DC, "sliding")
    branch = ssf.continue_equilibrium(e, "beta", (0.0005, 0.05), ds=0.001, ds_max=0.005,
                                      max_points=400, progress=False)  # fmt: skip
    hopf = next(b for b in branch.bifurcations if b.kind == "hopf")
    curve = ssf.continue_bifurcation(branch, hopf, "eta", (1.9, 2.1), progress=True)
    err = capsys.readouterr().err
    assert "continue_bifurcation hopf" in err
    assert _last_count(err) == (len(curve.values), len(curve.values))
    beta, eta = curve.values[-1]
    assert f"beta={beta:.10g}, eta={eta:.10g}" in err


def test_bad_progress_names_it(sliding):
    with pytest.raises(ValueError, match="progress"):
        ssf.continue_equilibrium(sliding, "eta", (1.0, 3.0), progress="yes")


def test_a_walk_inside_a_walk_reports_nothing():
    seen = []
    with progress.points_bar(False, 10, "x", ["a"]):
        with progress.walk_reporter() as report:
            assert report is None  # no bar: no reporter
    with progress.points_bar(True, 10, "x", ["a"]):
        with progress.walk_reporter() as outer:
            assert outer is not None
            with progress.walk_reporter() as inner:
                assert inner is None
            outer(np.array([1.0, 2.0]))
            seen.append(1)
        with progress.walk_reporter() as again:  # the next walk reports again
            assert again is not None
    with progress.walk_reporter() as after:  # and no bar once it is closed
        assert after is None
    assert seen == [1]
