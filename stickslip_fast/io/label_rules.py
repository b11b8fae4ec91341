"""Which labels of a file begun under older labelling rules the current rules decide otherwise.

A file records the :data:`~stickslip_fast.base.status.LABEL_RULES` that labelled it
(root attribute ``label_rules``; none: rules 1). It resumes only if none of its finished
runs would be labelled otherwise now, so that one file never holds labels of two sets of
rules (docs/file-format.md, "label_rules"). Where a later rule is a function of what the
file stores, the stored runs are judged again instead of being refused on suspicion:
rules 3 read a period from the stored Poincare points (:func:`poincare.orbit_period`),
which the file holds, with the system of each run, which its configuration and
coordinates give.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import h5py
import numpy as np

from ..base.status import LABEL_RULES, PERIODS_CHANGED_SINCE, ST_OK, stale_labels, status_names
from ..core.poincare import MAX_PERIOD, orbit_period
from ..core.settings import period_tolerance
from ..model.system import SWEEPABLE, System
from .base import ConfigMismatchError, _short
from .verify import stored_config

#: Rows of the leading axis read at once while the stored periods are judged again.
_ROWS = 256


def check_label_rules(path: Path, src: h5py.File) -> None:
    """Refuse to resume a file whose finished runs the current rules would label otherwise.

    Raises
    ------
    ConfigMismatchError
        For a file of newer rules than this version applies; for one whose statuses
        cannot be read; and for one with finished runs that the current rules label
        otherwise (the message counts them and names their statuses).
    """
    rules = int(src.attrs.get("label_rules", 1))
    if rules > LABEL_RULES:
        raise ConfigMismatchError(
            f"{path} was begun by a newer version of stickslip_fast (label_rules {rules}; "
            f"this version applies {LABEL_RULES}): its values may be labelled by rules this "
            "version does not know. Finish it with that version, or write to another output "
            "path."
        )
    if rules == LABEL_RULES:
        return
    try:
        done = np.asarray(src["done"][...]) != 0
        codes = np.asarray(src["status"][...])
        periods = np.asarray(src["period"][...])
        stale = done & stale_labels(rules, codes, periods)
        if any(old in PERIODS_CHANGED_SINCE for old in range(rules, LABEL_RULES)):
            asked = stale & (codes == ST_OK)
            stale &= ~(asked & _periods_stand(src, asked, periods))
    except (OSError, RuntimeError, KeyError, ValueError) as exc:
        raise ConfigMismatchError(
            f"{path} was begun under older labelling rules (label_rules {rules}; this version "
            f"applies {LABEL_RULES}), and its labels cannot be read to check which of its "
            f"values they would change ({_short(exc)}). Write to another output path, or "
            "delete the file to start over."
        ) from None
    if stale.any():
        names = sorted(set(status_names(codes[stale])))
        said = " or ".join("'ok' with another period" if n == "ok" else repr(n) for n in names)
        raise ConfigMismatchError(
            f"{path} was begun under older labelling rules (label_rules {rules}; this version "
            f"applies {LABEL_RULES}): {int(stale.sum())} of its {int(done.sum())} finished "
            f"values are labelled {said}, which the current rules decide differently "
            "(docs/file-format.md, 'label_rules'). Resuming would mix two sets of rules in "
            "one file. Finish it with the version that began it, or write to another output "
            "path (or delete the file) to compute every value under the current rules."
        )


def _periods_stand(src: h5py.File, asked: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """True where a run of ``asked`` has the period that the current rules read from its points.

    Each run's system is the configuration's, with the swept fields at the run's
    coordinates (the dimension scales of ``period`` that name a System field).
    """
    config = stored_config(src)
    base = {k: v for k, v in config["system"].items() if v is not None}
    settings = config["settings"]
    tol = settings.get("period_tol") or period_tolerance(settings["rtol"])
    coords = []
    for dim in src["period"].dims:
        scale = next(iter(dim.values()), None)
        name = None if scale is None else scale.name.rsplit("/", 1)[-1]
        coords.append((name, scale[...]) if name in SWEEPABLE else None)

    @lru_cache(maxsize=4096)
    def model(swept: tuple) -> tuple:
        system = System.from_dict({**base, **dict(swept)})
        return system.to_array(), system.n_oscillators, system.is_dc_motor

    stands = np.ones(asked.shape, dtype=bool)
    for row0 in range(0, asked.shape[0], _ROWS):
        block = asked[row0 : row0 + _ROWS]
        if not block.any():
            continue
        points = src["points"][row0 : row0 + _ROWS]
        count = src["count"][row0 : row0 + _ROWS]
        for idx in zip(*np.nonzero(block)):
            at = (row0 + idx[0], *idx[1:])
            swept = tuple((c[0], float(c[1][k])) for c, k in zip(coords, at) if c is not None)
            p, n_osc, dc = model(swept)
            n = int(count[idx])
            now = orbit_period(points[idx][:n], n, tol, MAX_PERIOD, p, n_osc, dc)
            stands[at] = now == periods[at]
    return stands
