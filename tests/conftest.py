import os
import sys
import threading

# Tests import the package from the source tree even when it is not installed.
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

#: The modules that define the package's warning classes (tests/test_conftest.py keeps
#: this list complete).
WARNING_MODULES = (
    "stickslip_fast.base.cache_index",  # UnreadableCacheIndex
    "stickslip_fast.core.settings",  # CoarseToleranceWarning
    "stickslip_fast.model.system",  # SynchronousStartWarning
)


def import_warning_modules() -> None:
    """Import the package and the modules of its warning classes, in this (main) thread."""
    import importlib

    for name in ("stickslip_fast", *WARNING_MODULES):
        importlib.import_module(name)


def rebuild_warnings_one_at_a_time() -> None:
    """Make pytest-xdist's controller rebuild the workers' warnings one at a time."""
    try:
        from xdist import workermanage
    except ImportError:  # no pytest-xdist: one process, nothing to race
        return
    rebuild = getattr(workermanage, "unserialize_warning_message", None)
    if rebuild is None or getattr(rebuild, "one_at_a_time", False):
        return
    lock = threading.Lock()

    def one_at_a_time(data):
        with lock:
            return rebuild(data)

    one_at_a_time.one_at_a_time = True
    workermanage.unserialize_warning_message = one_at_a_time


def pytest_configure(config):
    # pytest-xdist's controller rebuilds each warning a worker reports by importing the
    # module of its class, in the thread that reads that worker's channel. Two such
    # first imports at once, one per worker, race in Python's import locks and fail
    # ("cannot import name ... from partially initialized module"); the controller then
    # drops the worker in the middle of its file and ends with an internal error
    # ("KeyError: <WorkerController gw0>", exit 3: a CI run of 2026-12-03). Imported
    # here first, the modules are only looked up there; and the rebuilds take turns, for
    # warning classes of other packages that nothing here imported.
    if not hasattr(config, "workerinput"):  # the controller, or a run without workers
        import_warning_modules()
        rebuild_warnings_one_at_a_time()
