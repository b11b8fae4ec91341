"""The test suite's own setup (tests/conftest.py): what pytest-xdist's controller needs."""

import ast
import subprocess
import sys
from pathlib import Path

import conftest

PACKAGE = Path(__file__).resolve().parents[1] / "stickslip_fast"
TESTS = Path(__file__).resolve().parent

# In a fresh interpreter, as in xdist's controller: two threads (one per worker channel)
# rebuild two of the package's warnings at the same moment, after the conftest's hook
# has imported their modules in the main thread.
RACE = f"""
import sys, threading, warnings
sys.path.insert(0, {str(TESTS)!r})
from xdist.remote import serialize_warning_message
from xdist.workermanage import unserialize_warning_message

def data(module, name, *args):
    cls = type(name, (UserWarning,), {{"__module__": module}})
    msg = warnings.WarningMessage(cls(*args), cls, "f.py", 1)
    return serialize_warning_message(msg)

reports = [data("stickslip_fast.core.settings", "CoarseToleranceWarning", "atol"),
           data("stickslip_fast.model.system", "SynchronousStartWarning", "y0")]
if sys.argv[1] == "configured":
    import conftest
    conftest.import_warning_modules()
barrier, out = threading.Barrier(2), []

def rebuild(report):
    barrier.wait()
    try:
        out.append(unserialize_warning_message(report).category.__module__)
    except BaseException as exc:
        out.append(repr(exc))

threads = [threading.Thread(target=rebuild, args=(r,)) for r in reports]
[t.start() for t in threads]
[t.join() for t in threads]
print(sorted(out))
"""


def _warning_classes() -> dict[str, str]:
    """Every class of the package whose base is a warning, and the module defining it."""
    found = {}
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef) and any(
                getattr(base, "id", getattr(base, "attr", "")).endswith("Warning")
                for base in node.bases
            ):
                found[node.name] = module.removesuffix(".__init__")
    return found


def test_every_warning_class_of_the_package_is_imported_before_the_workers_start():
    classes = _warning_classes()
    assert {"CoarseToleranceWarning", "SynchronousStartWarning", "UnreadableCacheIndex"} <= set(
        classes
    )
    missing = {name: mod for name, mod in classes.items() if mod not in conftest.WARNING_MODULES}
    assert not missing, f"add their modules to tests/conftest.py's WARNING_MODULES: {missing}"


def test_two_workers_warnings_rebuilt_at_once_by_the_controller():
    # without the hook this failed every time on this VM (6 of 6): "cannot import name
    # 'warn_if_coarse_atol' from partially initialized module 'stickslip_fast.core.settings'"
    out = subprocess.run(
        [sys.executable, "-c", RACE, "configured"],
        capture_output=True, text=True, check=True, timeout=300,
    )  # fmt: skip
    assert out.stdout.strip() == repr(
        sorted(["stickslip_fast.core.settings", "stickslip_fast.model.system"])
    ), out.stdout + out.stderr
