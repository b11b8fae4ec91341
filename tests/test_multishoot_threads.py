"""Independent integrations on threads: multiple shooting's segments
(MultiShooting.segment_flows) and a two-parameter curve's Jacobians (run_concurrently).

The segments are independent integrations, so the results must be the same bits on
one thread or several; Ctrl-C must stop every segment; and a checkpoint must never
record a segment that Ctrl-C cut short.
"""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.base import journal as jmod
from stickslip_fast.base import threads as bthreads
from stickslip_fast.base.interrupt import new_abort_flag
from stickslip_fast.bifurcation.multishoot import MultiShooting


@pytest.fixture(scope="module")
def orbit():
    s = ssf.System.preset("asymmetric", eta=2.0)
    o = ssf.find_orbit(s, ssf.simulate(s, 3000, 2000))
    assert o.converged and o.period == 1
    return o


def _threads(monkeypatch, n: int) -> list[str]:
    """Let segment_flows use ``n`` threads (whatever the cores), and record which
    threads integrate."""
    monkeypatch.setattr(bthreads, "numba_threads", lambda: n)
    names: list[str] = []
    real = MultiShooting.flow

    def flow(self, *args, **kw):
        names.append(threading.current_thread().name)
        return real(self, *args, **kw)

    monkeypatch.setattr(MultiShooting, "flow", flow)
    return names


def _evaluate(orbit, m: int):
    ms = MultiShooting(orbit.system, m, 1e-10, 1e-12, 1e-10, "eta")
    _, Y = ms.states_at(orbit.points[:1], orbit.T, ms.mesh[:-1] * orbit.T)
    return ms.evaluate(ms.pack(Y, orbit.T))


def _own_sigint(signum, frame):
    raise KeyboardInterrupt


@pytest.mark.parametrize("handler", ["python", "own"])
@pytest.mark.parametrize("threads", [2, 3])
def test_segments_on_threads_give_the_same_bits(orbit, monkeypatch, threads, handler):
    # with a SIGINT handler of the caller's own, each call from the main thread runs in a
    # worker thread (base/interrupt.py), which takes the caller's Numba thread count
    old = signal.signal(
        signal.SIGINT, _own_sigint if handler == "own" else signal.default_int_handler
    )
    try:
        _same_bits_on_threads(orbit, monkeypatch, threads)
    finally:
        signal.signal(signal.SIGINT, old)


def _same_bits_on_threads(orbit, monkeypatch, threads):
    names = _threads(monkeypatch, 1)
    one = _evaluate(orbit, 7)
    branch_one = ssf.continue_orbit(orbit, "eta", (2.0, 2.1), shooting="multiple", segments=5,
                                    max_points=5, progress=False)  # fmt: skip
    assert set(names) == {"MainThread"}
    names.clear()
    monkeypatch.setattr(bthreads, "numba_threads", lambda: threads)
    many = _evaluate(orbit, 7)
    branch_many = ssf.continue_orbit(orbit, "eta", (2.0, 2.1), shooting="multiple",
                                     segments=5, max_points=5, progress=False)  # fmt: skip
    # the pool's threads integrated the segments (the calling thread: the rest)
    assert len({n for n in names if n.startswith("stickslip-worker")}) >= 2
    assert one[0] == many[0] == "ok"
    for a, b in zip(one[1:3], many[1:3]):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(one[3], many[3]):
        np.testing.assert_array_equal(a, b)
    for name in ("values", "points", "multipliers", "T"):
        np.testing.assert_array_equal(getattr(branch_one, name), getattr(branch_many, name))


@pytest.mark.skipif(os.name != "posix", reason="SIGINT delivery")
def test_ctrl_c_stops_every_segment(orbit, monkeypatch):
    _threads(monkeypatch, 2)
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        # four segments of 50000 time units each: 60 s in all on two threads here, so a stop
        # that works is told from one that does not even on a loaded CI runner
        ms = MultiShooting(orbit.system, 4, 1e-10, 1e-12, 1e-10)
        Y = np.repeat(orbit.points[:1], 4, axis=0)
        ms.segment_flows(Y, 40.0)  # compiled and warm (and a check the path runs)
        timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
        start = time.perf_counter()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            ms.segment_flows(Y, 200000.0)
        elapsed = time.perf_counter() - start
        timer.join()
    finally:
        signal.signal(signal.SIGINT, old)
    assert elapsed < 5.0, elapsed  # measured 0.32 s
    assert signal.set_wakeup_fd(-1) == -1  # the watcher let go of the wakeup fd


def test_a_segment_cut_short_is_not_recorded(tmp_path):
    # a worker thread's kernel returns when the flag is set (only the calling thread
    # raises KeyboardInterrupt): the journal must not keep that result as the answer
    def kernel(x, abort):
        return x + 1.0

    with jmod.journal(tmp_path / "j.ckpt", "test", {"a": 1}) as j:
        abort = new_abort_flag()
        assert j.call(kernel, (1.0,), abort) == 2.0
        abort[0] = 1
        with pytest.raises(KeyboardInterrupt):
            j.call(kernel, (5.0,), abort)
        assert (j.hits, j.misses) == (0, 1)
    with jmod.journal(tmp_path / "j.ckpt", "test", {"a": 1}) as j:
        assert j.recorded == 1


def test_run_concurrently_keeps_order_errors_and_nesting(monkeypatch):
    monkeypatch.setattr(bthreads, "numba_threads", lambda: 3)
    seen = []
    took_one = {"main": threading.Event(), "worker": threading.Event()}

    def call(k):
        name = threading.current_thread().name
        seen.append(name)
        # the calls take no time, so whichever thread starts first could take all eight:
        # each waits (at most 30 s) until the other kind of thread has taken one too
        mine, other = (
            ("worker", "main") if name.startswith("stickslip-worker") else ("main", "worker")
        )
        took_one[mine].set()
        took_one[other].wait(30.0)
        # nested work in a worker runs in that worker, one call after the other
        inner = bthreads.run_concurrently([lambda: k, lambda: -k])
        return k * k, inner

    out = bthreads.run_concurrently([lambda k=k: call(k) for k in range(8)])
    assert out == [(k * k, [k, -k]) for k in range(8)]
    assert "MainThread" in seen and any(n.startswith("stickslip-worker") for n in seen)

    def fail():
        raise RuntimeError("segment 3 failed")

    with pytest.raises(RuntimeError, match="segment 3 failed"):
        bthreads.run_concurrently([lambda: 1, fail, lambda: 2])


@pytest.fixture(scope="module")
def fold_point():
    # the upper fold of Fig. 6's period-1 branch at k12 = -0.8 (tests/test_checkpoint.py)
    s = ssf.System.preset("asymmetric", eta=3.30, k12=-0.8)
    o = ssf.find_orbit(s, np.array([0.07332092304307371, 0.0, 0.12221581726865255,
                                    -0.00674109106906407]), 1)  # fmt: skip
    branch = ssf.continue_orbit(o, "eta", (3.30, 3.35), ds=2e-3, ds_max=5e-3, max_points=100,
                                stick_events=False, progress=False)  # fmt: skip
    return branch, next(b for b in branch.bifurcations if b.kind == "fold")


def test_a_fold_curve_is_the_same_on_one_thread_or_three(fold_point, monkeypatch):
    # each step's four return maps (two sensitivities at x, then x +- h v) run side by side
    branch, fold = fold_point
    pools = []
    real = bthreads.shared_pool

    def spy(workers):
        pools.append(workers)
        return real(workers)

    monkeypatch.setattr(bthreads, "shared_pool", spy)
    curves = {}
    for n in (1, 3):
        monkeypatch.setattr(bthreads, "numba_threads", lambda n=n: n)
        curves[n] = ssf.continue_bifurcation(branch, fold, "k12", (-0.95, -0.79), direction=-1,
                                             max_points=4, stick_events=False)  # fmt: skip
        assert bool(pools) is (n > 1)  # on threads only when there are
    assert len(curves[1].values) == 4
    np.testing.assert_array_equal(curves[1].values, curves[3].values)
    np.testing.assert_array_equal(curves[1].points, curves[3].points)
    np.testing.assert_array_equal(curves[1].multipliers, curves[3].multipliers)
