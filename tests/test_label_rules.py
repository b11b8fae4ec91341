"""Result files record the rules that labelled them, and never mix two sets of rules.

A file begun under older labelling rules (``label_rules``, absent: 1) resumes only if
none of its finished values has a status that the rules changed since could decide
otherwise (docs/file-format.md). The premise that makes this safe: rules 2 (a window
that ends undecided looks past its end) act exactly where rules 1 said "unsettled" or
"no-crossings" (``tests/test_converged.py`` holds ``poincare.undecided`` to
``classify``), so every other value ends where, and as, it did; rules 3 (a period
refused for an oscillation dying out) only ever turn the period of an "ok" value into 0
(``poincare.orbit_period`` returns ``detect_period``'s period or 0, and the status is
decided before it), and so do rules 4 (the same for two modes dying out at once,
``poincare.envelope_decays``).
"""

import hashlib

import h5py
import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.base.status import (
    LABEL_RULES,
    ST_NO_CROSSINGS,
    ST_OK,
    ST_UNSETTLED,
    STATUS_NAMES,
    stale_labels,
)
from stickslip_fast.cli.report import _report
from stickslip_fast.io import ConfigMismatchError

ASYM = ssf.System.preset("asymmetric")
ETAS = np.array([5.2, 6.6, 9.99])
KW = dict(t_end=300.0, t_transient=200.0, max_points=8, progress=False)

# sweeps with equilibria warn that they gave no orbit; not what these tests are about
pytestmark = pytest.mark.filterwarnings("ignore:.*gave no orbit")


def _as_if_older(path, status=None, undone=(2,), rules=1):
    """Make ``path`` look like a file of older rules (1: no attribute) interrupted before
    the values ``undone``."""
    with h5py.File(path, "r+") as h5:
        if rules == 1:
            del h5.attrs["label_rules"]
        else:
            h5.attrs["label_rules"] = rules
        for i in undone:
            h5["done"][i] = 0
        if status is not None:
            h5["status"][0] = status


def _digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_only_the_labels_a_later_rule_acts_on_are_stale():
    codes = np.arange(-1, len(STATUS_NAMES))
    none = np.zeros_like(codes)
    some = np.ones_like(codes)
    # rules 1 -> 2: the look past the end; 2 -> 3: a period refused for a decay to rest
    assert codes[stale_labels(1, codes, none)].tolist() == [ST_NO_CROSSINGS, ST_UNSETTLED]
    assert codes[stale_labels(1, codes, some)].tolist() == [ST_OK, ST_NO_CROSSINGS, ST_UNSETTLED]
    assert not stale_labels(2, codes, none).any()
    assert codes[stale_labels(2, codes, some)].tolist() == [ST_OK]
    assert codes[stale_labels(2, codes)].tolist() == [ST_OK]  # periods unknown: any "ok"
    # 3 -> 4: a period refused for two modes dying out at once
    assert not stale_labels(3, codes, none).any()
    assert codes[stale_labels(3, codes, some)].tolist() == [ST_OK]
    assert not stale_labels(LABEL_RULES, codes, some).any()
    assert LABEL_RULES == 4


def test_a_new_file_records_its_rules_and_an_older_one_without_stale_labels_resumes(tmp_path):
    fresh = ssf.sweep(ASYM, "eta", ETAS, out=tmp_path / "fresh.h5", **KW)
    assert list(fresh.status) == ["equilibrium", "ok", "ok"]  # the premise: nothing stale
    with h5py.File(tmp_path / "fresh.h5", "r") as h5:
        assert h5.attrs["label_rules"] == LABEL_RULES
    old = tmp_path / "old.h5"
    ssf.sweep(ASYM, "eta", ETAS, out=old, **KW)
    _as_if_older(old)  # its finished orbit's period is what the current rules read
    resumed = ssf.sweep(ASYM, "eta", ETAS, out=old, **KW)
    for name in ("points", "final_state", "status_code", "period", "n_steps"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(fresh, name), err_msg=name)
    with h5py.File(old, "r") as h5:
        assert h5.attrs["label_rules"] == LABEL_RULES
        assert h5["done"][...].tolist() == [1, 1, 1]
    assert f"label rules {LABEL_RULES}," in _report(old)  # what stickslip-fast info shows


@pytest.mark.parametrize("status", [ST_UNSETTLED, ST_NO_CROSSINGS])
def test_an_older_file_with_values_the_rules_now_decide_otherwise_is_refused(tmp_path, status):
    old = tmp_path / "old.h5"
    first = ssf.sweep(ASYM, "eta", ETAS, out=old, **KW).status_code[0]
    _as_if_older(old, status=status)
    before = _digest(old)
    name = STATUS_NAMES[status]
    with pytest.raises(
        ConfigMismatchError,
        match=rf"label_rules 1.*1 of its 2 finished values are labelled '{name}'",
    ):
        ssf.sweep(ASYM, "eta", ETAS, out=old, **KW)
    assert _digest(old) == before  # untouched
    # a value of that status that is not finished (done = 0) is computed anew: no refusal
    with h5py.File(old, "r+") as h5:
        h5["done"][0] = 0
    ssf.sweep(ASYM, "eta", ETAS, out=old, **KW)
    with h5py.File(old, "r") as h5:
        assert h5.attrs["label_rules"] == LABEL_RULES
        assert h5["status"][0] == first


def test_an_older_file_whose_periods_the_rules_now_read_otherwise_is_refused(tmp_path):
    # rules 3 refuse a period where the points still head for rest (poincare.orbit_period):
    # the decaying oscillation of tests/test_decaying_oscillation.py, which rules 2 stored
    # as period 1 (its points are the same: only the reading of them changed)
    from test_decaying_oscillation import DECAYING, NEAR_REST

    kw = dict(t_end=300.0, t_transient=0.0, y0=NEAR_REST, max_points=32, progress=False)
    etas = [DECAYING.eta, 5.9, 6.0]
    old = tmp_path / "old.h5"
    fresh = ssf.sweep(DECAYING, "eta", etas, out=old, **kw)
    assert (fresh.status[0], fresh.period[0]) == ("ok", 0)
    with h5py.File(old, "r+") as h5:
        h5["period"][0] = 1
    _as_if_older(old, rules=2)
    before = _digest(old)
    with pytest.raises(
        ConfigMismatchError,
        match=r"label_rules 2.*1 of its 2 finished values are labelled 'ok' with another period",
    ):
        ssf.sweep(DECAYING, "eta", etas, out=old, **kw)
    assert _digest(old) == before
    # with the period the current rules read, the same file resumes
    with h5py.File(old, "r+") as h5:
        h5["period"][0] = 0
    resumed = ssf.sweep(DECAYING, "eta", etas, out=old, **kw)
    np.testing.assert_array_equal(resumed.period, fresh.period)
    with h5py.File(old, "r") as h5:
        assert h5.attrs["label_rules"] == LABEL_RULES


def test_a_rules_3_file_with_a_two_mode_decay_read_as_an_orbit_is_refused(tmp_path):
    # rules 4 refuse the period of two modes dying out at once (poincare.envelope_decays):
    # the random system of tests/test_decaying_oscillation.py, which rules 3 read as period 1
    from test_decaying_oscillation import TWO_MODES, TWO_MODES_START

    kw = dict(t_end=3000.0, y0=TWO_MODES_START, progress=False)
    old = tmp_path / "old.h5"
    fresh = ssf.sweep(TWO_MODES, "eta", [TWO_MODES.eta], out=old, **kw)
    assert (fresh.status[0], fresh.period[0]) == ("ok", 0)
    with h5py.File(old, "r+") as h5:
        h5["period"][0] = 1  # what rules 3 stored: the same points, read otherwise
    _as_if_older(old, rules=3, undone=())
    before = _digest(old)
    with pytest.raises(ConfigMismatchError, match=r"label_rules 3.*1 of its 1 finished values"):
        ssf.sweep(TWO_MODES, "eta", [TWO_MODES.eta], out=old, **kw)
    assert _digest(old) == before


def test_the_periods_of_a_map_are_judged_with_each_cell_s_own_system(tmp_path):
    # the decaying oscillation's cell (eta, mu) of a 2-D map: judged with the base mu's rest
    # position (4 times as far out) the points would not head for rest, and the period 1
    # of rules 2 would stand
    from test_decaying_oscillation import DECAYING, NEAR_REST

    kw = dict(t_end=300.0, t_transient=0.0, y0=NEAR_REST, max_points=32, progress=False)
    axes = ([DECAYING.eta], [DECAYING.mu, 0.05])
    base = DECAYING.replace(mu=0.05)
    old = tmp_path / "map.h5"
    fresh = ssf.sweep(base, ("eta", "mu"), axes, out=old, **kw)
    assert fresh.period[0, 0] == 0
    with h5py.File(old, "r+") as h5:
        h5["period"][0, 0] = 1
        h5.attrs["label_rules"] = 2
        h5["done"][0, 1] = 0
    with pytest.raises(ConfigMismatchError, match=r"1 of its 1 finished values .*another period"):
        ssf.sweep(base, ("eta", "mu"), axes, out=old, **kw)


def test_a_census_file_follows_the_same_rule(tmp_path):
    kw = dict(n_starts=3, seed=7, t_end=300.0, t_transient=150.0, max_points=32, progress=False)
    path = tmp_path / "census.h5"
    ssf.census(ASYM, "eta", [2.0, 7.0], out=path, **kw)
    with h5py.File(path, "r+") as h5:
        assert h5.attrs["label_rules"] == LABEL_RULES
        del h5.attrs["label_rules"]
        h5["done"][1, 2] = 0
        h5["status"][0, 1] = ST_UNSETTLED
        h5["period"][1, 0] = h5["period"][1, 0] + 1  # an orbit read otherwise now
        assert h5["status"][1, 0] == ST_OK
    with pytest.raises(
        ConfigMismatchError,
        match=r"2 of its 5 finished values .*'ok' with another period or 'unsettled'",
    ):
        ssf.census(ASYM, "eta", [2.0, 7.0], out=path, **kw)


def test_a_file_of_newer_rules_is_refused_and_left_as_it_was(tmp_path):
    path = tmp_path / "newer.h5"
    ssf.sweep(ASYM, "eta", ETAS, out=path, **KW)
    with h5py.File(path, "r+") as h5:
        h5.attrs["label_rules"] = LABEL_RULES + 1
        h5["done"][2] = 0
    before = _digest(path)
    with pytest.raises(ConfigMismatchError, match=rf"newer version.*label_rules {LABEL_RULES + 1}"):
        ssf.sweep(ASYM, "eta", ETAS, out=path, **KW)
    assert _digest(path) == before
