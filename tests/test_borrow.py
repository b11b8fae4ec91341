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
from numba import njit
from numba.core.errors import TypingError
from numba.extending import overload

from stickslip_fast.base.jit import OVERLOAD, borrow
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
