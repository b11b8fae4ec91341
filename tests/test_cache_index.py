"""A Numba cache index that names a type whose module is gone is read as empty (base.cache_index).

Reproduced by hand (docs/developing.md, "Problem records from your own module"): a
record defined in a script, solved on the driver, then the script renamed; without
the fix the next ``simulate`` that compiled anything on the driver raised
``ModuleNotFoundError`` from the driver's cache index.
"""

import importlib
import sys

import pytest
from numba.core.caching import IndexDataCacheFile

import stickslip_fast  # noqa: F401  (installs the tolerant loader)
from stickslip_fast.base import cache_index


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
