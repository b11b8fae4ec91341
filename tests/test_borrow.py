"""jit.borrow: records without reference counts for the driver's step loop.

The driver borrows its records once per run, so that the inlined calls of the step
loop copy no reference counts (docs/developing.md, "Borrowed records"). A borrowed
record must be the same record: the same values, shapes and strides, and writes
through it must reach the caller's arrays, including writes that an IR-inlined
overload makes (Numba's dead-code elimination removed those until it was told
that ``borrow`` aliases its argument).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
import pytest
from numba import njit, types
from numba.core.errors import TypingError
from numba.extending import overload

from stickslip_fast.base.jit import OVERLOAD, borrow, overload_call
from stickslip_fast.core.driver import PoincareObserver, Section

Rec = namedtuple("Rec", ["a", "k", "flag", "m", "inner"])
Inner = namedtuple("Inner", ["x", "up"])


@njit
def _fields(r):
    b = borrow(r)
    return (
        b.k, b.flag, b.a.sum(), b.m.shape[0], b.m.shape[1], b.m.strides[0], b.m.strides[1],
        b.inner.x, b.inner.up, b.m[2, 1],
    )  # fmt: skip


def test_borrow_keeps_values_shapes_strides():
    m = np.arange(24.0).reshape(4, 6)[:, ::2]  # non-contiguous: strides must survive
    r = Rec(np.arange(5.0), 7, True, m, Inner(-3, False))
    assert _fields(r) == (7, True, 10.0, 4, 3, 48, 16, -3, False, m[2, 1])


@njit
def _write_direct(a, r):
    b = borrow(a)
    b[1] = 5.0
    rb = borrow(r)
    rb.m[1, 1] = 9.0
    v = rb.a[2:]  # a view of a borrowed array writes through too
    v[0] = 4.0


def test_writes_through_a_borrowed_value_reach_the_original():
    a = np.zeros(3)
    r = Rec(np.zeros(4), 0, False, np.zeros((2, 2)), Inner(0, True))
    _write_direct(a, r)
    np.testing.assert_array_equal(a, [0.0, 5.0, 0.0])
    np.testing.assert_array_equal(r.m, [[0.0, 0.0], [0.0, 9.0]])
    np.testing.assert_array_equal(r.a, [0.0, 0.0, 4.0, 0.0])


def _record_crossing(obs, i):  # noqa: ARG001 - resolved by overload
    pass


@overload(_record_crossing, **OVERLOAD)
def _record_crossing_impl(obs, i):
    def impl(obs, i):
        obs.tpts[i % 3] = 10.0 + i

    return impl


@njit
def _inlined_writes(obs, k):
    obs = borrow(obs)
    for i in range(k):
        _record_crossing(obs, i)


def test_inlined_overload_writes_into_a_borrowed_record_are_kept():
    """The regression: without the alias rule these stores were dead code (t_poincare
    came back uninitialised, a Lyapunov run drifted to max_steps)."""
    obs = PoincareObserver(
        Section(1, True), 0.0, np.zeros((6, 2)), np.zeros(6), np.zeros((0, 2)), 0.1,
        np.zeros(2), np.zeros(2), np.zeros(2, dtype=np.int64),
    )  # fmt: skip
    _inlined_writes(obs, 5)
    np.testing.assert_array_equal(obs.tpts, [13.0, 14.0, 12.0, 0.0, 0.0, 0.0])


def test_borrow_refuses_values_it_cannot_borrow():
    @njit
    def f(x):
        return borrow(x)

    with pytest.raises(TypingError):
        f("text")


def test_poll_flag_reads_the_first_entry_of_an_integer_flag():
    from stickslip_fast.base.jit import poll_flag

    @njit
    def read(flag):
        return poll_flag(flag)

    assert read(np.array([3, 0], dtype=np.int64)) == 3
    assert read(np.zeros(1, dtype=np.int64)) == 0
    with pytest.raises(TypingError):
        read(np.zeros(1))  # a float array is not a flag


# ------------------------------------------------------------ jit.overload_call
def _scale_into(rec, factor, label):  # noqa: ARG001 - resolved by overload
    pass


@overload_call(_scale_into)
def _scale_into_impl(rec, factor, label):
    if isinstance(label, types.UnicodeType):  # not borrowable: passed as it is

        def impl(rec, factor, label):
            for i in range(rec.a.size):
                rec.a[i] *= factor
            rec.m[0, 0] = len(label)
            return rec.a.sum()

        return impl


@njit
def _local_record_scaled(n):
    # the record is a call's result and is written only inside the overload_call
    # function: the writes must survive Numba's dead-code elimination
    rec = Rec(np.ones(n), 0, False, np.zeros((2, 2)), Inner(0, True))
    total = _scale_into(rec, 3.0, "four")
    return total, rec.a.copy(), rec.m[0, 0]


def test_overload_call_writes_reach_the_caller():
    total, a, m00 = _local_record_scaled(5)
    assert total == 15.0
    assert np.array_equal(a, np.full(5, 3.0))
    assert m00 == 4.0


def test_a_refused_run_reports_counts_and_times_not_garbage():
    # integrate() on parameters it refuses (a NaN): status "error", no steps, no
    # crossings and a finite motion measure. The refusal writes into the observer
    # record that integrate() made; inlining _run at the Numba IR level once
    # lost those writes (the motion measure came back as 9.9e203).
    import stickslip_fast as ssf
    from stickslip_fast.base.status import ST_ERROR
    from stickslip_fast.core import trajectory

    m = trajectory.M_RODAS5P
    p = ssf.System.preset("asymmetric").to_array()
    p[0] = np.nan
    stat_i = np.full(4, 7, dtype=np.int64)
    stat_f = np.full(4, 7.0)
    y_end = np.full(4, 7.0)
    status = trajectory.integrate(
        m, np.zeros(4), p, 1, False, trajectory.method_variant(m, 1, False),
        trajectory.run_settings(100.0, 0.0, 1e-6, 1e-8), np.full((4, 4), 7.0), np.full(4, 7.0),
        np.empty((0, 4)), 1.0, y_end, stat_i, stat_f, np.zeros(1, dtype=np.int64),
    )  # fmt: skip
    assert status == ST_ERROR
    assert np.array_equal(stat_i, np.zeros(4, dtype=np.int64))
    assert stat_f[trajectory.F_T_FINAL] == 0.0
    assert stat_f[trajectory.F_AMPLITUDE] == 0.0
    assert np.isnan(stat_f[trajectory.F_T_CONVERGED])
