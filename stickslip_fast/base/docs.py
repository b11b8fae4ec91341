"""Docstring blocks shared by several public functions, filled in where they are defined."""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from typing import TypeVar

F = TypeVar("F", bound=Callable)


def fill_doc(**blocks: str) -> Callable[[F], F]:
    """Replace each line ``{name}`` of the decorated function's docstring by ``blocks[name]``.

    The block is indented like the placeholder line, so one text serves functions whose
    docstrings are indented differently (and Python versions that dedent docstrings).
    """

    def decorate(func: F) -> F:
        lines = []
        for line in (func.__doc__ or "").splitlines(keepends=True):
            key = line.strip()[1:-1] if line.strip().startswith("{") else None
            if key in blocks:
                indent = line[: len(line) - len(line.lstrip())]
                lines.append(textwrap.indent(textwrap.dedent(blocks[key]).strip("\n"), indent))
                lines.append("\n")
            else:
                lines.append(line)
        func.__doc__ = "".join(lines)
        return func

    return decorate
