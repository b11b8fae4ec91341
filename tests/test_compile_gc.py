"""No full garbage collections while Numba compiles (base/compile_gc.py)."""

from __future__ import annotations

import gc
import os
import subprocess
import sys

import numpy as np
import pytest
from numba import njit
from numba.core import event

import stickslip_fast  # noqa: F401 - installs the listener
from stickslip_fast.base import compile_gc


class _Probe(event.Listener):
    """Records the collector's state at the start of every compile (registered after
    the package's listener, so it sees what that one set)."""

    def __init__(self):
        self.seen = []

    def on_start(self, ev):
        self.seen.append((gc.isenabled(), gc.get_threshold()))

    def on_end(self, ev):
        pass


@pytest.fixture
def probe():
    p = _Probe()
    event.register(compile_gc.EVENT, p)
    yield p
    event.unregister(compile_gc.EVENT, p)


@pytest.fixture
def thresholds():
    saved = gc.get_threshold()
    yield saved
    gc.set_threshold(*saved)
    gc.enable()


def _fresh_pair():
    # new functions each call (no cache): the caller compiles its callee within its own compile
    @njit(cache=False)
    def inner(x):
        return 2.0 * x + 1.0

    @njit(cache=False)
    def outer(a):
        s = 0.0
        for v in a:
            s += inner(v)
        return s

    return outer


def test_the_package_installs_the_listener_once():
    assert compile_gc.installed()
    assert compile_gc.install()  # a second call registers nothing more
    listeners = [
        x for x in event._registered[compile_gc.EVENT] if isinstance(x, compile_gc.CompileGCPause)
    ]
    assert len(listeners) == 1


def test_a_compile_holds_off_full_collections_and_restores_the_thresholds(probe, thresholds):
    gc.set_threshold(700, 10, 10)
    outer = _fresh_pair()
    assert outer(np.arange(4.0)) == 2.0 * 6.0 + 4.0
    # two compiles (outer, then inner within it), both with the compile's thresholds
    assert len(probe.seen) == 2
    assert all(
        seen == (True, (compile_gc.YOUNG_THRESHOLD, 10, compile_gc.NEVER)) for seen in probe.seen
    )
    assert gc.get_threshold() == (700, 10, 10) and gc.isenabled()
    # a larger young threshold of the user's own is kept during the compile
    gc.set_threshold(50_000, 5, 7)
    probe.seen.clear()
    _fresh_pair()(np.arange(3.0))
    assert {seen[1] for seen in probe.seen} == {(50_000, 5, compile_gc.NEVER)}
    assert gc.get_threshold() == (50_000, 5, 7)


def test_a_failed_compile_restores_the_thresholds(probe, thresholds):
    gc.set_threshold(700, 10, 10)

    @njit(cache=False)
    def bad(x):
        return x + "a string"

    with pytest.raises(Exception, match="(?i)typing"):
        bad(1.0)
    assert probe.seen and probe.seen[0][1][2] == compile_gc.NEVER
    assert gc.get_threshold() == (700, 10, 10)


def test_a_collector_that_is_off_is_left_alone(probe, thresholds):
    gc.set_threshold(700, 10, 10)
    gc.disable()
    _fresh_pair()(np.arange(2.0))
    assert probe.seen and all(seen == (False, (700, 10, 10)) for seen in probe.seen)
    assert not gc.isenabled() and gc.get_threshold() == (700, 10, 10)


def test_restore_mid_compile_and_the_variable_that_turns_it_off():
    pause = compile_gc.CompileGCPause()
    saved = gc.get_threshold()
    try:
        pause.on_start(None)
        assert gc.get_threshold()[2] == compile_gc.NEVER
        pause.restore()
        assert gc.get_threshold() == saved
    finally:
        gc.set_threshold(*saved)
    code = "import stickslip_fast; from stickslip_fast.base import compile_gc; print(compile_gc.installed())"
    env = dict(os.environ, **{compile_gc.ENV_VAR: "0"})
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "False"
