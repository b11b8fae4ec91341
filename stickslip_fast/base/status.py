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
#:    labelled "unsettled" or "no-crossings" can end differently;
#: 3. (2026-12-02) an "ok" run whose points repeat while they still drift towards the
#:    rest state is an oscillation dying out: period 0, "none found"
#:    (:func:`stickslip_fast.core.poincare.orbit_period`). Only "ok" runs with a period
#:    can be labelled differently; their status stays "ok";
#: 4. (2026-12-02, later) the same for two modes dying out at once, whose points change
#:    unevenly from period to period: the envelope of the window's last points heads for
#:    rest (:func:`stickslip_fast.core.poincare.envelope_decays`). Again only "ok" runs
#:    with a period can be labelled differently.
LABEL_RULES = 4
#: The statuses that a finished run may have under older :data:`LABEL_RULES` and not
#: under the current ones (see :func:`stale_labels`).
LABELS_CHANGED_SINCE = {1: ("no-crossings", "unsettled"), 2: (), 3: ()}
#: The rules after which an "ok" run with a period may have another period now.
PERIODS_CHANGED_SINCE = frozenset({2, 3})

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


def stale_labels(rules: int, codes: np.ndarray, periods: np.ndarray | None = None) -> np.ndarray:
    """Which stored labels the current :data:`LABEL_RULES` could decide differently.

    Parameters
    ----------
    rules : int
        The ``label_rules`` the labels were computed under.
    codes : ndarray of int
        Status codes of finished runs.
    periods : ndarray of int, optional
        Their periods (shape of ``codes``). Without them every "ok" run counts as one
        with a period.

    Returns
    -------
    ndarray of bool
        True where a run of that status (and period) under ``rules`` could end with
        another status or period now (all False when ``rules`` is current). Any other
        run ended where, and as, the current rules end it.
    """
    names = set()
    orbits = False
    for old in range(rules, LABEL_RULES):
        names.update(LABELS_CHANGED_SINCE[old])
        orbits = orbits or old in PERIODS_CHANGED_SINCE
    stale = np.isin(codes, [STATUS_NAMES.index(n) for n in sorted(names)])
    if orbits:
        with_period = codes == ST_OK
        if periods is not None:
            with_period &= np.asarray(periods) > 0
        stale |= with_period
    return stale
