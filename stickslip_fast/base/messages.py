"""Plain text for error messages: numbers as numbers, whatever their type.

NumPy 2 writes a scalar's repr as ``np.float64(-1.0)``; a message naming a bad
value should say ``-1.0``, the number the user typed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plain"]


def plain(value: Any) -> str:
    """``repr`` of ``value`` with NumPy scalars (also inside lists, tuples and arrays) as Python's.

    >>> plain(np.float64(-1.0)), plain([np.int64(2), "a"]), plain(np.array([1.5, 2.0]))
    ('-1.0', "[2, 'a']", '[1.5, 2.0]')
    """
    if isinstance(value, np.generic):
        return repr(value.item())
    if isinstance(value, np.ndarray):
        return repr(value.tolist())
    if isinstance(value, (list, tuple)):
        inner = ", ".join(plain(v) for v in value)
        if isinstance(value, tuple):
            return f"({inner},)" if len(value) == 1 else f"({inner})"
        return f"[{inner}]"
    return repr(value)
