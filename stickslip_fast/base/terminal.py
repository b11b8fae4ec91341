"""Whether output goes to a person: the rule behind progress bars and compile notices.

Progress bars (sweeps, censuses, continuations) and the compile notice are shown by
default only where standard error is a terminal, so logs, pipes and notebooks stay clean.
"""

from __future__ import annotations

import sys

__all__ = ["on_terminal", "show_progress"]


def on_terminal(stream=None) -> bool:
    """True if ``stream`` (default: ``sys.stderr`` now) is a terminal; False for a pipe, a
    file, a closed stream, or none at all (``pythonw``)."""
    stream = sys.stderr if stream is None else stream
    isatty = getattr(stream, "isatty", None)
    try:
        return bool(isatty and isatty())
    except (ValueError, OSError):  # a closed or odd stream
        return False


def show_progress(progress) -> bool:
    """A ``progress=`` argument: shown if true, hidden if false, and by default (None) on a
    terminal (:func:`on_terminal`)."""
    return on_terminal() if progress is None else bool(progress)
