"""Status codes of a run, shared by the kernels, the file schema and the API.

The codes are stored in result files (``status`` dataset, CF ``flag_values``),
so new statuses are only ever appended.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "STATUS_NAMES", "ORBIT_STATUSES", "FAILURE_STATUSES", "LABEL_RULES", "status_names",
    "stale_labels",
]  # fmt: skip

STATUS_NAMES = (
    "ok",
    "equilibrium",
    "stalled",
    "no-crossings",
    "nonfinite",
    "step-underflow",
    "max-steps",
    "error",
    "interrupted",
    "unsettled",
)
(
    ST_OK,
    ST_EQUILIBRIUM,
    ST_STALLED,
    ST_NO_CROSSINGS,
    ST_NONFINITE,
    ST_UNDERFLOW,
    ST_MAX_STEPS,
    ST_ERROR,
    ST_INTERRUPTED,
    ST_UNSETTLED,
) = range(10)
#: Written into kernel outputs before a value runs: a value that still holds it
#: afterwards was never computed, and the caller refuses to store it.
ST_NOT_COMPUTED = -1

#: The version of the rules that decide a run's status at the end of its window,
#: stored in every result file (root attribute ``label_rules``; a file without it was
#: written under rules 1). Raised whenever a change can give a finished run another
#: status:
#:
#: 1. a window that ends undecided is labelled where it ends: "unsettled" (at rest, or
#:    disk 1 at rest, for less than the tail) or "no-crossings" (disk 1 moves but has
#:    not crossed within the tail);
#: 2. (2026-11-27) such a window looks past its end, for up to ``dwell``, until the run
#:    is decided (:func:`stickslip_fast.core.stoprules.past_end`). Only runs that rules 1
#:    labelled "unsettled" or "no-crossings" can end differently.
LABEL_RULES = 2
#: The statuses that a finished run may have under older :data:`LABEL_RULES` and not
#: under the current ones (see :func:`stale_labels`).
LABELS_CHANGED_SINCE = {1: ("no-crossings", "unsettled")}

#: Statuses for which a run has an orbit to report.
ORBIT_STATUSES = ("ok",)
#: Statuses of a run that did not finish: its final state is no start for the next value.
FAILURE_STATUSES = ("nonfinite", "step-underflow", "max-steps", "error", "interrupted")


def status_names(codes: np.ndarray) -> np.ndarray:
    """The status name of every code (an object array of the shape of ``codes``).

    A negative code (:data:`ST_NOT_COMPUTED`: a value not computed yet, e.g. in the
    file of an interrupted run) is named "missing". The ``status`` of sweep and census
    results."""
    names = np.array(STATUS_NAMES + ("missing",), dtype=object)
    return names[np.where(codes < 0, len(STATUS_NAMES), codes)]


def stale_labels(rules: int, codes: np.ndarray) -> np.ndarray:
    """Which stored statuses the current :data:`LABEL_RULES` could decide differently.

    Parameters
    ----------
    rules : int
        The ``label_rules`` the statuses were computed under.
    codes : ndarray of int
        Status codes of finished runs.

    Returns
    -------
    ndarray of bool
        True where a run of that status under ``rules`` could end with another status
        now (all False when ``rules`` is current). A run of any other status ended
        where, and as, the current rules end it.
    """
    names = set()
    for old in range(rules, LABEL_RULES):
        names.update(LABELS_CHANGED_SINCE[old])
    return np.isin(codes, [STATUS_NAMES.index(n) for n in sorted(names)])
