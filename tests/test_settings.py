"""Typed settings, the sweep's layers and the compatibility of files written before them.

The references are the code before :class:`Settings` existed (commit 8f8aa13):
its ``resolve_settings`` dicts and the configuration hashes of files it wrote
are copied below as literals, and ``tests/data/sweep_before_settings.h5`` is a
sweep it left half done (2 of 4 values of a continuation, see
tests/data/README.md). Cost: about 5 s (a few 4-value sweeps of 300 time units).
"""

from __future__ import annotations

import ast
import dataclasses
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.analysis.sweep import sweep
from stickslip_fast.base.status import LABEL_RULES
from stickslip_fast.core import settings as settings_mod
from stickslip_fast.core.settings import Settings

DATA = Path(__file__).parent / "data"
PKG = Path(ssf.__file__).parent

# (arguments of the old resolve_settings, the dict it returned), printed by the old code;
# the default period_tol of rtol > 1e-8 changed since (capped at 1e-4: docs/model.md,
# "Period"), so the two entries with such an rtol and no period_tol say 1e-4
OLD_RESOLVED = [
    (
        dict(method="rodas5p", t_end=3000, t_transient=2000, rtol=None, atol=None, h=None,
             max_points=256, max_steps=None, equilibrium_tol=1e-4, period_tol=None),
        dict(method="rodas5p", t_end=3000.0, t_transient=2000.0, rtol=1e-09, atol=1e-11, h=0.0,
             max_points=256, max_steps=20000000, equilibrium_tol=0.0001, period_tol=1e-05),
    ),
    (
        dict(method="dopri5-fixed", t_end=100.0, t_transient=0, rtol=1e-6, atol=1e-8, h=0.01,
             max_points=3, max_steps=None, equilibrium_tol=1e-3, period_tol=1e-5),
        dict(method="dopri5-fixed", t_end=100.0, t_transient=0.0, rtol=1e-06, atol=1e-08,
             h=0.01, max_points=3, max_steps=10001, equilibrium_tol=0.001, period_tol=1e-05),
    ),
    (
        dict(method="rodas5p", t_end=50, t_transient=10.5, rtol=1e-7, atol=None, h=0.001,
             max_points=0, max_steps=10**6, equilibrium_tol=1e-4, period_tol=None),
        dict(method="rodas5p", t_end=50.0, t_transient=10.5, rtol=1e-07, atol=1e-11, h=0.001,
             max_points=0, max_steps=1000000, equilibrium_tol=0.0001, period_tol=1e-4),
    ),
    (
        dict(method="dopri5", t_end=1e4, t_transient=0.0, rtol=1e-3, atol=1e-3, h=None,
             max_points=1000, max_steps=5, equilibrium_tol=2e-4, period_tol=None),
        dict(method="dopri5", t_end=10000.0, t_transient=0.0, rtol=0.001, atol=0.001, h=0.0,
             max_points=1000, max_steps=5, equilibrium_tol=0.0002, period_tol=1e-4),
    ),
]  # fmt: skip

KW = dict(t_end=300.0, t_transient=200.0, max_points=8, progress=False)


# values without an orbit are expected here: silence sweep()'s summary warning
pytestmark = pytest.mark.filterwarnings("ignore:.*gave no orbit")


@pytest.mark.parametrize("args,old", OLD_RESOLVED)
def test_to_dict_is_the_old_settings_dict(args, old):
    new = Settings.resolve(**args).to_dict()
    assert new == old
    assert list(new) == list(old)  # same keys in the same order
    assert [type(v) for v in new.values()] == [type(v) for v in old.values()]  # 3000 -> 3000.0
    assert Settings.from_dict(new).to_dict() == new


def test_config_hash_of_new_files_is_the_old_one(tmp_path):
    # config_sha256 of the same two sweeps written by the old code
    sweep(ssf.System.preset("asymmetric"), "eta", [2.0, 3.0, 9.99], out=tmp_path / "a.h5",
          mode="continuation", chunk_size=2, **KW)  # fmt: skip
    two = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2)
    sweep(two, ("eta", "k12"), ([2.0, 3.0], [0.1, -0.5]), out=tmp_path / "b.h5",
          analyses=("sync",), **KW)  # fmt: skip
    for name, digest in (
        ("a.h5", "2ab94ef1f3e39de8e31f7d3c48d67512555a4b19e6fdf1201ab70aeadf7c99a0"),
        ("b.h5", "8dcb3bd9dd0680262e3b737f5b295ddd3de1a598c8c3a0e74c821eba2fe0cd8b"),
    ):
        with h5py.File(tmp_path / name, "r") as h5:
            assert h5.attrs["config_sha256"] == digest


def test_file_written_before_settings_resumes_bit_identically(tmp_path):
    old = tmp_path / "old.h5"
    shutil.copy(DATA / "sweep_before_settings.h5", old)
    with h5py.File(old, "r") as h5:
        assert h5["done"][...].tolist() == [1, 1, 0, 0]
    etas = [2.0, 3.0, 5.6, 9.99]
    args = dict(mode="continuation", chunk_size=2, t_end=300.0, t_transient=200.0, max_points=4,
                progress=False)  # fmt: skip
    resumed = sweep(ssf.System.preset("asymmetric"), "eta", etas, out=old, **args)
    fresh = sweep(ssf.System.preset("asymmetric"), "eta", etas, out=tmp_path / "new.h5", **args)
    for name in ("points", "final_state", "count", "period", "status", "n_steps"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(fresh, name), err_msg=name)
    with h5py.File(old, "r") as h5:
        assert h5["done"][...].tolist() == [1, 1, 1, 1]
        # written before label_rules existed (rules 1), with no value the rules since
        # decide otherwise: it resumed, and now records the current rules
        assert h5.attrs["label_rules"] == LABEL_RULES
    assert isinstance(resumed.settings, Settings) and resumed.settings.max_points == 4
    assert ssf.load_sweep(old).settings == resumed.settings


def test_settings_are_frozen_typed_and_named():
    s = Settings.resolve(t_end=10.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.rtol = 1e-3  # type: ignore[misc]
    assert s["rtol"] == s.rtol == ssf.DEFAULT_RTOL  # read access of the old dict stays
    with pytest.raises(ValueError, match="unknown setting.*'rtool'"):
        Settings.from_dict({**s.to_dict(), "rtool": 1e-6})
    with pytest.raises(TypeError, match="t_end"):
        Settings(method="rodas5p")  # t_end has no default


def test_resolve_keeps_records_apart_by_type_and_bits():
    a = Settings.resolve("rodas5p", 10.0, 0.0, 1e-8)
    # the same arguments, positional or by name: the same (immutable) record
    assert Settings.resolve(t_end=10.0, rtol=1e-8, method="rodas5p") is a
    # 0.0 and -0.0 compare equal but are different settings (a file's hash tells them apart)
    neg = Settings.resolve("rodas5p", 10.0, -0.0, 1e-8)
    assert neg is not a and str(neg.to_dict()["t_transient"]) == "-0.0"
    assert str(a.to_dict()["t_transient"]) == "0.0"
    # an int where a float was given: another record, equal in value
    b = Settings.resolve("rodas5p", 10, 0.0, 1e-8)
    assert b is not a and b == a
    assert Settings.resolve("rodas5p", 10.0, 0.0, 1e-8, stop="converged") is not a
    # bad input is refused every time, not remembered
    for _ in range(2):
        with pytest.raises(ValueError, match="rtol"):
            Settings.resolve("rodas5p", 10.0, 0.0, -1.0)
    # unhashable input is validated as before
    with pytest.raises(ValueError, match="rtol"):
        Settings.resolve("rodas5p", 10.0, 0.0, [1e-8])
    # the store is bounded
    for k in range(settings_mod._RESOLVED_MAX + 10):
        Settings.resolve(t_end=10.0 + k)
    assert len(settings_mod._RESOLVED) <= settings_mod._RESOLVED_MAX


def test_a_new_field_is_one_line_and_keeps_old_hashes():
    @dataclasses.dataclass(frozen=True, kw_only=True)
    class WithStop(Settings):
        stop: str = settings_mod._field("t_end", settings_mod._choice(("t_end", "k")), new=True)

    base = Settings.resolve(t_end=10.0).to_dict()
    assert WithStop.resolve(t_end=10.0).to_dict() == base  # at its default: not in the hash
    assert WithStop.resolve(t_end=10.0, stop="k").to_dict() == {**base, "stop": "k"}
    with pytest.raises(ValueError, match="stop must be one of"):
        WithStop.resolve(t_end=10.0, stop="never")


def test_results_carry_settings_objects(tmp_path):
    res = ssf.simulate(ssf.System(), 20.0, max_points=2)
    assert isinstance(res.settings, Settings) and res.settings.t_end == 20.0
    ssf.io.write_trajectory(tmp_path / "run.h5", res)
    assert ssf.io.read_trajectory(tmp_path / "run.h5")["result"].settings == res.settings


def test_in_memory_store_and_file_hold_the_same_arrays(tmp_path):
    etas = [2.0, 9.99]
    mem = sweep(ssf.System.preset("asymmetric"), "eta", etas, **KW)
    disk = sweep(ssf.System.preset("asymmetric"), "eta", etas, out=tmp_path / "s.h5", **KW)
    layout_names = set(mem._data)
    with h5py.File(tmp_path / "s.h5", "r") as h5:
        for name in layout_names:
            assert h5[name].dtype == mem._data[name].dtype, name
            np.testing.assert_array_equal(h5[name][...], mem._data[name])
    np.testing.assert_array_equal(disk.points, mem.points)


def test_no_module_imports_sweep_back():
    # the chunk functions live in backends/local.py: the backends never import sweep
    for name in ("backends/dask.py", "backends/local.py", "core/settings.py"):
        tree = ast.parse((PKG / name).read_text())
        mods = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        mods = {m.rsplit(".", 1)[-1] for m in mods if m}  # "..analysis.sweep" -> "sweep"
        assert "sweep" not in mods and "sweep_result" not in mods, name


def test_cli_choices_come_from_the_package():
    from stickslip_fast.cli import build_parser

    parser = build_parser()
    sim = parser._subparsers._group_actions[0].choices["simulate"]  # noqa: SLF001
    opts = {a.dest: a for a in sim._actions}
    assert tuple(opts["method"].choices) == ssf.METHODS
    assert tuple(opts["drive"].choices) == ssf.model.system.DRIVES
