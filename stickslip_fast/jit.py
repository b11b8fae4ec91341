"""Compilation options shared by every compiled module, and the record-type test.

``error_model="numpy"`` makes a division by zero give inf/NaN instead of
raising: no kernel can raise (see docs/developing.md, "The kernel rules").
"""

from __future__ import annotations

from numba import types

__all__ = ["JIT", "OVERLOAD", "is_record"]

#: Options of every ``@njit`` of the package.
JIT = dict(cache=True, nogil=True, error_model="numpy")
#: Options of every ``@overload`` implementation. Inlined into the caller at
#: Numba IR level: records (namedtuples of arrays) passed across a call boundary
#: cost an atomic incref/decref per array field, which made a step of the generic
#: driver ~1.5x slower than the hand-written loop it replaced; inlined, the
#: reference counts are pruned and the step costs what it did.
OVERLOAD = dict(jit_options=JIT, inline="always")


def is_record(typ, cls) -> bool:
    """At compile time: is the Numba type ``typ`` the namedtuple record class ``cls``?"""
    return isinstance(typ, types.BaseNamedTuple) and typ.instance_class is cls
