"""Status codes of a run, shared by the kernels, the file schema and the API.

The codes are stored in result files (``status`` dataset, CF ``flag_values``),
so new statuses are only ever appended.
"""

from __future__ import annotations

import numpy as np

__all__ = ["STATUS_NAMES", "ORBIT_STATUSES", "FAILURE_STATUSES", "status_names"]

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
