"""The package's cache and problem records defined outside it (base.cache_index).

Both hazards were reproduced by hand first (docs/developing.md, "Problem records from
your own module"): a record defined in a script and solved on the driver; the script
renamed, and the next ``simulate`` that compiled anything on the driver raised
``ModuleNotFoundError`` from the driver's cache index; the script's f edited, and the
driver cached with the old f was loaded again (exp(-2) where exp(-4) was due).
"""

import importlib
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from numba.core.caching import IndexDataCacheFile

import stickslip_fast  # noqa: F401  (installs the tolerant loader)
from stickslip_fast.base import cache_index

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def vanished_key(tmp_path, monkeypatch):
    """A cache key holding a class whose module existed when it was saved and is gone now."""
    mod_dir = tmp_path / "src"
    mod_dir.mkdir()
    (mod_dir / "ssf_vanishing_records.py").write_text("class Record:\n    pass\n")
    monkeypatch.syspath_prepend(str(mod_dir))
    importlib.invalidate_caches()
    mod = importlib.import_module("ssf_vanishing_records")
    key = ("sig", mod.Record)
    yield key, mod_dir
    sys.modules.pop("ssf_vanishing_records", None)


def _saved_index(folder, key):
    folder.mkdir(exist_ok=True)
    f = IndexDataCacheFile(str(folder), "fn-1.py311", ("stamp", 1))
    f.save(key, b"compiled")
    return f


def _forget(mod_dir):
    sys.modules.pop("ssf_vanishing_records", None)
    (mod_dir / "ssf_vanishing_records.py").unlink()
    importlib.invalidate_caches()


def test_installed_at_import():
    assert cache_index.installed()


def test_package_index_naming_a_gone_module_is_a_miss_and_is_rebuilt(
    tmp_path, monkeypatch, vanished_key
):
    key, mod_dir = vanished_key
    folder = tmp_path / "pkgcache"
    _saved_index(folder, key)
    _forget(mod_dir)
    monkeypatch.setattr(
        cache_index, "_package_cache_dirs", lambda: frozenset({str(folder.resolve())})
    )
    fresh = IndexDataCacheFile(str(folder), "fn-1.py311", ("stamp", 1))
    with pytest.warns(cache_index.UnreadableCacheIndex, match="ssf_vanishing_records"):
        assert fresh._load_index() == {}
    # the next save writes a readable index holding only the new entry
    with pytest.warns(cache_index.UnreadableCacheIndex):
        fresh.save(("sig", "float64"), b"again")
    assert fresh.load(("sig", "float64")) == b"again"
    assert list(fresh._load_index()) == [("sig", "float64")]


def test_other_packages_indexes_keep_numbas_behaviour(tmp_path, vanished_key):
    key, mod_dir = vanished_key
    folder = tmp_path / "othercache"
    _saved_index(folder, key)
    _forget(mod_dir)
    fresh = IndexDataCacheFile(str(folder), "fn-1.py311", ("stamp", 1))
    with pytest.raises(ModuleNotFoundError, match="ssf_vanishing_records"):
        fresh._load_index()


def test_the_package_cache_folders_are_numbas():
    from stickslip_fast.base.cache_guard import cache_dirs

    dirs = cache_index._package_cache_dirs()
    assert len(dirs) == len(cache_dirs()) >= 9  # the root and its eight layers
    assert all(cache_index._of_package(str(d)) for d in cache_dirs())
    assert not cache_index._of_package(str(cache_dirs()[0]) + "_elsewhere")


# ------------------------------------------------------- a user's record, end to end
USER_MODULE = """
from collections import namedtuple

from numba import types
from numba.extending import overload

from stickslip_fast.base.jit import OVERLOAD
from stickslip_fast.core import problems
from stickslip_fast.model.linalg import dense_w_factor, dense_w_solve

RATE = {rate}
Decay = namedtuple("Decay", ["k"])


def _mine(t):
    return isinstance(t, types.BaseNamedTuple) and t.instance_class is Decay


@overload(problems.problem_f, **OVERLOAD)
def _f(prob, y, out):
    if _mine(prob):
        def impl(prob, y, out):
            out[0] = -RATE * prob.k * y[0]
        return impl


@overload(problems.problem_jac, **OVERLOAD)
def _jac(prob, y, lin):
    if _mine(prob):
        def impl(prob, y, lin):
            lin.jac[0, 0] = -RATE * prob.k
        return impl


@overload(problems.problem_factor, **OVERLOAD)
def _factor(prob, lin, sigma):
    if _mine(prob):
        return lambda prob, lin, sigma: dense_w_factor(sigma, lin.jac, lin.lu, lin.piv)


@overload(problems.problem_solve, **OVERLOAD)
def _solve(prob, lin, b):
    if _mine(prob):
        return lambda prob, lin, b: dense_w_solve(lin.lu, lin.piv, b)
"""

SOLVE = """
import numpy as np
from stickslip_fast.core.testproblems import solve_test_problem
import ssf_user_decay as m
y = solve_test_problem(True, m.Decay(2.0), np.ones(1), 1.0, 1e-10, 1e-12, 0.0, 100000)[0]
print(repr(float(y[0])))
"""

KAPS = """
import math, numpy as np
from stickslip_fast.core.testproblems import Kaps, solve_test_problem
y = solve_test_problem(True, Kaps(1e-3), np.ones(2), 1.0, 1e-10, 1e-12, 0.0, 100000)[0]
print(repr(float(abs(y[0] - math.exp(-2.0)) + abs(y[1] - math.exp(-1.0)))))
"""


def _run(code, src, cache):
    env = dict(
        os.environ, NUMBA_CACHE_DIR=str(cache), PYTHONPATH=os.pathsep.join([str(src), str(ROOT)])
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return float(proc.stdout.strip().splitlines()[-1]), proc.stderr


def test_a_users_record_edited_or_gone_never_gives_stale_or_failed_compiles(tmp_path):
    src, cache = tmp_path / "src", tmp_path / "cache"
    src.mkdir()
    module = src / "ssf_user_decay.py"
    module.write_text(USER_MODULE.format(rate=1.0))
    # y' = -k y from 1 over t = 1: the driver compiled for the record, cached
    assert abs(_run(SOLVE, src, cache)[0] - math.exp(-2.0)) < 1e-8
    # the record's f edited: the cached driver with the old f must not be loaded
    module.write_text(USER_MODULE.format(rate=2.0))
    st = module.stat()
    os.utime(module, (st.st_atime, st.st_mtime + 5.0))
    assert abs(_run(SOLVE, src, cache)[0] - math.exp(-4.0)) < 1e-8
    # the module gone: a new compile on the driver warns and rebuilds its index
    module.rename(src / "ssf_user_decay_old.py")
    err, stderr = _run(KAPS, src, cache)
    assert err < 1e-8  # Kaps' exact solution (exp(-2t), exp(-t)) at t = 1
    assert "UnreadableCacheIndex" in stderr and "ssf_user_decay" in stderr
