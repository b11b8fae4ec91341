"""Bad input is refused, naming the field, before any work (issue 14, items 12 and 13).

Each test failed on the code before these checks (commit 8f8aa13): the input
was accepted, silently converted, or checked one value at a time. Cost: about
3 s (a few runs of 20 time units).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.cli.config import ConfigError, parse_config
from stickslip_fast.core import settings as settings_mod
from stickslip_fast.model.system import System

QUICK = dict(t_end=20.0, max_points=2, progress=False)


@pytest.fixture
def small_memory(monkeypatch):
    """Pretend the machine has 16 GiB, so memory checks do not depend on where tests run."""
    monkeypatch.setattr(settings_mod, "memory_limit", lambda: 16 * 2**30)


# ------------------------------------------------------------------ item 13
@pytest.mark.parametrize("rtol", [1.0, 0.011])
def test_rtol_is_bounded(rtol):
    with pytest.raises(ValueError, match=r"rtol must be <= 0\.01"):
        ssf.simulate(System(), 10.0, rtol=rtol)
    with pytest.raises(ValueError, match=r"rtol must be <= 0\.01"):
        ssf.sweep(System(), "eta", [2.0], rtol=rtol, **QUICK)


def test_rtol_at_the_bound_runs():
    assert ssf.simulate(System(), 10.0, rtol=1e-2, atol=1e-4).t_final == 10.0


@pytest.mark.parametrize(
    "kwargs,name",
    [
        (dict(t_end="300"), "t_end"),
        (dict(t_end=30.0, t_transient="10"), "t_transient"),
        (dict(t_end=30.0, atol="1e-9"), "atol"),
        (dict(t_end=30.0, sample_dt="0.1"), "sample_dt"),
        (dict(t_end=30.0, equilibrium_tol=True), "equilibrium_tol"),
    ],
)
def test_numbers_given_as_strings_or_booleans_are_refused(kwargs, name):
    with pytest.raises(ValueError, match=f"{name} must be a real number"):
        ssf.simulate(System(), **kwargs)


def test_max_steps_is_not_cut():
    with pytest.raises(ValueError, match=r"max_steps must be an integer.*2\.7"):
        ssf.simulate(System(), 10.0, max_steps=2.7)
    with pytest.raises(ValueError, match="max_steps"):
        ssf.sweep(System(), "eta", [2.0], max_steps=2.7, **QUICK)
    r = ssf.simulate(System(), 10.0, max_steps=2.0)  # an integral float is an integer
    assert r.status == "max-steps" and r.n_steps == 2


@pytest.mark.parametrize(
    "values,where",
    [
        ([2.0, "3.0"], r"\[sweep\]\.values\[1\] is '3\.0'"),
        ([True, 2], r"\[sweep\]\.values\[0\] is True"),
    ],
)
def test_toml_value_lists_hold_numbers_only(values, where):
    with pytest.raises(ConfigError, match=where):
        parse_config({"sweep": {"param": "eta", "values": values}})


def test_toml_2d_value_list_names_the_axis():
    data = {"sweep": {"param": ["eta", "k12"], "values": [[2.0, 3.0], [0.1, False]]}}
    with pytest.raises(ConfigError, match=r"\[sweep\]\.values\[1\]\[1\] is False"):
        parse_config(data)


@pytest.mark.parametrize("values", [["2.0", "3.0"], [True, 2.0], np.array([True, False])])
def test_strings_and_booleans_are_not_converted_to_values(values):
    with pytest.raises(ValueError, match="values for 'eta' must be numbers"):
        ssf.sweep(System(), "eta", values, **QUICK)


def test_max_points_zero_warns_in_a_sweep():
    # decided: allowed (a run's final state and status are still useful; simulate
    # documents it), but a sweep says clearly that no period can be detected
    with pytest.warns(UserWarning, match=r"max_points = 0: no Poincare points.*period 0"):
        res = ssf.sweep(System(), "eta", [2.0], t_end=20.0, max_points=0, progress=False)
    assert res.period.tolist() == [0]


@pytest.mark.parametrize(
    "values,mode,what",
    [
        ([2.0, 4.0, 3.0], "continuation", "is not monotonic"),
        ([2.0, 2.0, 3.0], "continuation", "has duplicates"),
        ([3.0, 2.0], "continuation-both", "is not increasing"),
        ([2.0, 3.0, 3.0], "continuation-both", "has duplicates"),
    ],
)
def test_continuation_warns_about_the_order_of_values(values, mode, what):
    with pytest.warns(UserWarning, match=f"values for 'eta' {what}; mode '{mode}'"):
        ssf.sweep(System(), "eta", values, mode=mode, **QUICK)


@pytest.mark.parametrize(
    "values,mode",
    [([3.0, 2.0], "continuation"), ([2.0, 3.0], "continuation-both"), ([3.0, 2.0], "restart")],
)
def test_ordered_or_restart_values_do_not_warn(values, mode):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        ssf.sweep(System(), "eta", values, mode=mode, **QUICK)
    assert not [w for w in seen if "values for" in str(w.message)]


def test_huge_chain_is_refused_with_a_memory_estimate(small_memory, tmp_path):
    big = System(n_oscillators=10**6)
    # 1000 points of 4e6 states: 29.8 GiB (the probe's MemoryError) plus work arrays
    with pytest.raises(ValueError, match=r"n_oscillators = 1000000.*about 3\d\.\d GiB"):
        ssf.simulate(big, 10.0)
    with pytest.raises(ValueError, match=r"in-memory results \(give out=.*n_oscillators = 1000000"):
        ssf.sweep(big, "eta", np.linspace(1, 10, 10), t_end=20.0, max_points=256)
    out = tmp_path / "never-written.h5"
    with pytest.raises(ValueError, match=r"one unit of 64 values.*GiB"):
        ssf.sweep(big, "eta", [2.0], t_end=20.0, max_points=256, out=out, chunk_size=64)
    assert not out.exists()  # refused before the file is created


def test_huge_sample_grid_is_refused(small_memory):
    with pytest.raises(ValueError, match=r"samples \(sample_dt = 1e-09\)"):
        ssf.simulate(System(), 300.0, sample_dt=1e-9)


@pytest.mark.parametrize("name,value", [("mu", -0.01), ("beta", -1e-3)])
def test_negative_friction_scales_are_refused(name, value):
    with pytest.raises(ValueError, match=f"System.{name} must be >= 0"):
        System(**{name: value})
    with pytest.raises(ValueError, match=f"swept param '{name}' is invalid"):
        ssf.sweep(System(), name, [0.01, value, 0.02], **QUICK)


def test_negative_damping_stays_allowed():
    # an energy source ("negative damping"): the runaway is classified, not an error
    assert System(c=-5.0).c == -5.0


# ------------------------------------------------------------------ item 12
def test_value_list_is_checked_vectorised(monkeypatch):
    calls = []
    original = System.replace

    def counting(self, **changes):
        calls.append(changes)
        return original(self, **changes)

    monkeypatch.setattr(System, "replace", counting)
    etas = np.linspace(1.0, 10.0, 100_000)
    with pytest.raises(ValueError, match="mode must be one of"):  # stops after the value check
        ssf.sweep(System(), "eta", etas, mode="sideways", **QUICK)
    assert len(calls) <= 2  # the extremes stand for every value (the rules are intervals)
    etas[50_000] = 10.5  # a bad value anywhere is still found and named
    with pytest.raises(ValueError, match=r"value 10\.5 of swept param 'eta' is invalid"):
        ssf.sweep(System(), "eta", etas, **QUICK)
