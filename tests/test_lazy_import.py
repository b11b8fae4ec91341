"""``import stickslip_fast`` loads what a first ``simulate`` needs; the rest on first use.

The package's ``__getattr__`` (PEP 562) imports the orbit, census, basin and Lyapunov
names when they are first used, so a process that only simulates starts sooner
(docs/performance.md, "Against the code the issue was filed on, and the cached start").
"""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import stickslip_fast as ssf

INIT = Path(ssf.__file__)

PROBE = """
import sys
import stickslip_fast as ssf
before = sorted(m for m in sys.modules if m.startswith("stickslip_fast"))
ssf.simulate  # imported at once
orbit = ssf.find_orbit  # imported now
after = sorted(m for m in sys.modules if m.startswith("stickslip_fast"))
print(repr((before, after, orbit.__module__)))
"""


def test_a_plain_import_leaves_the_bifurcation_layer_unloaded_until_used():
    out = subprocess.run(
        [sys.executable, "-c", PROBE], capture_output=True, text=True, check=True, timeout=120
    )
    before, after, module = ast.literal_eval(out.stdout.strip().splitlines()[-1])
    assert "stickslip_fast.analysis.simulate" in before
    assert not [m for m in before if m.startswith("stickslip_fast.bifurcation")]
    assert "stickslip_fast.analysis.basins" not in before
    assert "stickslip_fast.bifurcation.orbits" in after and module.endswith("bifurcation.orbits")


def test_every_public_name_resolves_and_is_listed():
    for name in ssf.__all__:
        assert getattr(ssf, name) is not None, name
        assert name in dir(ssf), name
    from stickslip_fast.analysis.census import census
    from stickslip_fast.bifurcation.orbits import find_orbit

    assert ssf.census is census and ssf.find_orbit is find_orbit


def test_an_unknown_name_is_an_attribute_error_naming_it():
    with pytest.raises(AttributeError, match="'no_such_name'"):
        ssf.no_such_name  # noqa: B018
    assert not hasattr(ssf, "sweep_kernels")


def test_the_lazy_table_and_the_type_checking_imports_name_the_same_things():
    tree = ast.parse(INIT.read_text())
    block = next(
        node
        for node in tree.body
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING"
    )
    typed = {
        ("." * imp.level + (imp.module or ""), alias.name)
        for imp in block.body
        for alias in imp.names
    }
    lazy = {(module, name) for name, module in ssf._LAZY.items()}
    assert typed == lazy
    eager = set(ssf.__all__) - set(ssf._LAZY) - {"__version__"}
    assert eager <= set(vars(ssf))  # the rest is imported with the package


def test_a_layer_reached_as_an_attribute_holds_the_modules_it_held_before():
    # submodules not yet imported of layers that a plain import binds (analysis, base,
    # core), asked for first, then a layer not yet imported (bifurcation, cli): the
    # documented dotted names work after ``import stickslip_fast`` alone, as with the
    # eager import (the first three failed while only unbound layers imported modules)
    code = (
        "import stickslip_fast as ssf; "
        "print(ssf.analysis.census.load_census.__module__, ssf.base.journal.__name__, "
        "ssf.core.variational.propagate_tangents.__module__, hasattr(ssf.core, 'nothing'), "
        "ssf.bifurcation.orbits.return_map.__module__, ssf.cli.__name__)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.split() == [
        "stickslip_fast.analysis.census",
        "stickslip_fast.base.journal",
        "stickslip_fast.core.variational",
        "False",
        "stickslip_fast.bifurcation.returnmap",
        "stickslip_fast.cli",
    ]


THREADS = """
import threading
import stickslip_fast as ssf
names = ["census", "find_orbit", "basins", "largest_lyapunov", "sync_stability", "sweep"]
barrier, out = threading.Barrier(len(names)), {}

def first_use(name):
    barrier.wait()
    try:
        out[name] = getattr(ssf, name).__module__
    except BaseException as exc:
        out[name] = repr(exc)

threads = [threading.Thread(target=first_use, args=(n,)) for n in names]
[t.start() for t in threads]
[t.join() for t in threads]
print(repr(out))
"""


def test_public_names_first_used_by_several_threads_at_once():
    # each first use imports its module in the thread that asks: six at once must each
    # get their function, not an ImportError from a module another thread is importing
    out = subprocess.run(
        [sys.executable, "-c", THREADS], capture_output=True, text=True, check=True, timeout=120
    )
    modules = ast.literal_eval(out.stdout.strip().splitlines()[-1])
    assert modules == {
        "census": "stickslip_fast.analysis.census",
        "find_orbit": "stickslip_fast.bifurcation.orbits",
        "basins": "stickslip_fast.analysis.basins",
        "largest_lyapunov": "stickslip_fast.analysis.lyapunov",
        "sync_stability": "stickslip_fast.bifurcation.synchrony",
        "sweep": "stickslip_fast.analysis.sweep",
    }, out.stderr
