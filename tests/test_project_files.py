"""The files a citable package carries: README for newcomers, --version, CITATION.cff.

Cheap (no kernels run): the version checks use argparse only.
"""

import os
import re
import subprocess
import sys

import pytest

import stickslip_fast as ssf
from stickslip_fast.cli import main

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# the README's two commands, kept verbatim (CI and newcomers run them as written)
MAIN_JOB = (
    "python3 -m pip install . && stickslip-fast sweep data/fig06_asymmetric_constant.toml "
    "-o out/fig06.h5 && python3 scripts/plot_bifurcation.py out/fig06.h5 -o out/fig06.png --period"
)
TEST_JOB = 'python3 -m pip install ".[test]" && python3 -m pytest -q -n auto --dist loadfile'


def _read(name):
    with open(os.path.join(ROOT, name), encoding="utf-8") as f:
        return f.read()


def test_readme_is_short_and_has_the_two_commands():
    text = _read("README.md")
    assert len(text.splitlines()) <= 150
    assert MAIN_JOB in text
    assert TEST_JOB in text
    # CI runs the README's test command
    assert TEST_JOB.split(" && ")[1] in _read(".ci/run")
    # pictures it shows exist
    for path in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text):
        assert os.path.exists(os.path.join(ROOT, path)), path


def test_version_flag_prints_the_package_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"stickslip-fast {ssf.__version__}"


def test_version_flag_in_a_subprocess():
    proc = subprocess.run(
        [sys.executable, "-m", "stickslip_fast.cli", "--version"],
        capture_output=True, text=True, cwd=ROOT, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"stickslip-fast {ssf.__version__}"


def test_one_version_everywhere():
    # pyproject.toml is the source; __version__ reads it from the installed metadata
    pyproject = re.search(r'^version = "([^"]+)"', _read("pyproject.toml"), re.M).group(1)
    if ssf.__version__ != "0.0.0+unknown":  # not installed: nothing to compare
        assert ssf.__version__ == pyproject
    cff = re.search(r"^version: (\S+)", _read("CITATION.cff"), re.M).group(1)
    assert cff.strip("\"'") == pyproject
    assert "MIT License" in _read("LICENSE")
    assert "## [" + pyproject + "]" in _read("CHANGELOG.md")


def test_docstring_examples_of_the_public_names_run():
    # the rendered API reference shows these examples; they must stay true
    import doctest

    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    n_examples = 0
    for name in ssf.__all__:
        obj = getattr(ssf, name)
        if not (callable(obj) and getattr(obj, "__module__", "").startswith("stickslip_fast")):
            continue
        for test in finder.find(obj, name, globs={"np": __import__("numpy"), "ssf": ssf}):
            test.globs.update(vars(ssf))
            n_examples += len(test.examples)
            runner.run(test)
    assert runner.failures == 0, f"{runner.failures} docstring example(s) failed (see output)"
    assert n_examples >= 5


def test_the_period_map_config_loads():
    # the README's period-map picture is made from it (its notes say how)
    from stickslip_fast.cli.config import load_config

    cfg = load_config(os.path.join(ROOT, "data", "maps", "period_map_eta_k12.toml"))
    assert tuple(cfg.sweep["param"]) == ("eta", "k12")
    assert os.path.exists(os.path.join(ROOT, "docs", "figures", "period_map.png"))


_WITHOUT_EXTRAS = """
import importlib, importlib.abc, pkgutil, sys
# what only the extras install (pyproject.toml): test, dask, cuda
BLOCK = ("scipy", "xarray", "h5netcdf", "dask", "distributed", "hypothesis", "numba_cuda",
         "pytest")
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCK:
            raise ModuleNotFoundError(f"No module named {name!r} (an extra)")
sys.meta_path.insert(0, Block())
import stickslip_fast
for m in pkgutil.walk_packages(stickslip_fast.__path__, "stickslip_fast."):
    if not m.name.endswith("__main__"):
        try:
            importlib.import_module(m.name)
        except ImportError as e:
            print(m.name, "|", e)
"""


def test_the_package_imports_with_its_runtime_dependencies_alone():
    # a plain `pip install stickslip_fast` has no SciPy (a test extra). Until 2026-12-02 the
    # stick-phase curves imported scipy.optimize at module level, and `import
    # stickslip_fast` failed there; every module but the CUDA backend's (which names its
    # extra) must import without the extras
    out = subprocess.run([sys.executable, "-c", _WITHOUT_EXTRAS], capture_output=True,
                         text=True, timeout=300)  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    failed = [line.split(" | ") for line in out.stdout.strip().splitlines()]
    assert {m for m, _ in failed} <= {
        "stickslip_fast.backends.cuda", "stickslip_fast.backends.cuda_device",
        "stickslip_fast.backends.cuda_kernels",
    }, failed  # fmt: skip
    assert all('pip install "stickslip_fast[cuda]"' in msg for _, msg in failed), failed
