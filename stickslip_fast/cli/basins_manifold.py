"""The ``[basins.manifold]`` table: a saddle orbit's stable manifold after a basin map.

TOML layout (a sub-table of ``[basins]``; see docs/basins.md)::

    [basins.manifold]
    point = [0.0726, 0.0, 0.1222, -0.0067]   # a state on the section near the saddle
    period = 1                               # find_orbit's period (default 1)
    seeds = "boundary"                       # the refined boundary's points (needs
                                             # [basins.refine]) or "scan" (from the saddle)
    ds = 2e-3                                # stable_manifold's tracing settings:
    r_local = 1e-6                           # ds, ds_min, ds_max, tol, r_local, n_max,
    n_max = 40                               # max_points, max_angle, seed_radius,
                                             # skip_radius; rtol, atol (the return map)
    [basins.manifold.scan]                   # seeds = "scan" only: manifold_seeds' grid
    grid = 24                                # (n x n over the box; default the map's own),
    r_scan = 1e-2                            # r_scan, n_max, r_local, tol

The saddle is found by :func:`~stickslip_fast.bifurcation.orbits.find_orbit` from
``point``; the curve by :func:`~stickslip_fast.bifurcation.stable_manifold.stable_manifold`
and stored in the map's ``/basins/manifold``, with the table in its settings
(``settings["config"]``): a rerun on the same file with the same table (and, for
``seeds = "boundary"``, the same ``[basins.refine]``) does not recompute it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["parse_manifold_table", "run_manifold", "manifold_line", "MANIFOLD_KEYS"]

#: Tracing settings of stable_manifold (trace_manifold's keywords) and the return map's
#: tolerances, with their types; every value must be > 0.
_TRACE = {"ds": float, "ds_min": float, "ds_max": float, "tol": float, "r_local": float,
          "n_max": int, "max_points": int, "max_angle": float, "seed_radius": float,
          "skip_radius": float, "rtol": float, "atol": float}  # fmt: skip
#: manifold_seeds' settings for seeds = "scan" (grid: n for an n x n grid over the box).
_SCAN = {"grid": int, "n_max": int, "r_scan": float, "r_local": float, "tol": float}
#: The defaults filled in (trace_manifold's and manifold_seeds'; the others stay unset).
_DEFAULTS = {"period": 1, "seeds": "boundary", "ds": 1e-3, "ds_min": 1e-7, "tol": 1e-11,
             "r_local": 1e-4, "n_max": 30, "max_points": 400, "max_angle": 0.3}  # fmt: skip
_SCAN_DEFAULTS = {"r_scan": 1e-2}
MANIFOLD_KEYS = {"point", "period", "seeds", "scan", *_TRACE}


def _number(value: Any, want: type, key: str) -> Any:
    """``value`` as ``want`` (int or float), finite and > 0, or a ConfigError naming ``key``."""
    from .config_values import ConfigError

    ok_types = (int, float) if want is float else int
    if isinstance(value, bool) or not isinstance(value, ok_types):
        raise ConfigError(f"{key} must be {want.__name__}, got {value!r}")
    if not math.isfinite(value) or value <= 0:
        raise ConfigError(f"{key} must be > 0, got {value!r}")
    return want(value)


def _scan_table(table: Any) -> dict:
    from .config_values import ConfigError, typed_table

    if not isinstance(table, dict):
        raise ConfigError(f"[basins.manifold].scan must be a table, got {table!r}")
    checked = typed_table(table, "basins.manifold.scan", _SCAN)
    out = {k: _number(v, _SCAN[k], f"[basins.manifold.scan].{k}") for k, v in checked.items()}
    if out.get("grid", 2) < 2:
        raise ConfigError(f"[basins.manifold.scan].grid must be >= 2, got {out['grid']}")
    return {**_SCAN_DEFAULTS, **out}


def parse_manifold_table(table: Any, *, has_refine: bool, n_state: int | None = None) -> dict:
    """Validate a ``[basins.manifold]`` table; the defaults filled in (see the module doc).

    ``has_refine``: whether the config has ``[basins.refine]`` (``seeds = "boundary"``
    needs it); ``n_state``: the system's state length (``point`` must have it).
    """
    from .config_values import ConfigError

    if not isinstance(table, dict):
        raise ConfigError("[basins.manifold] must be a table")
    unknown = sorted(set(table) - MANIFOLD_KEYS)
    if unknown:
        raise ConfigError(f"unknown key [basins.manifold].{unknown[0]}; known: "
                          f"{sorted(MANIFOLD_KEYS)}")  # fmt: skip
    if "point" not in table:
        raise ConfigError("[basins.manifold] needs 'point' (a state near the saddle orbit)")
    p = table["point"]
    if (not isinstance(p, list) or not p
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in p)):  # fmt: skip
        raise ConfigError(f"[basins.manifold].point must be a list of numbers, got {p!r}")
    if n_state is not None and len(p) != n_state:
        raise ConfigError(f"[basins.manifold].point must have {n_state} entries (the system's "
                          f"state), got {len(p)}")  # fmt: skip
    out: dict[str, Any] = {**_DEFAULTS, "point": [float(x) for x in p]}
    if "period" in table:
        out["period"] = _number(table["period"], int, "[basins.manifold].period")
    seeds = table.get("seeds", "boundary")
    if seeds not in ("boundary", "scan"):
        raise ConfigError(f'[basins.manifold].seeds must be "boundary" or "scan", got {seeds!r}')
    if seeds == "boundary" and not has_refine:
        raise ConfigError('[basins.manifold].seeds = "boundary" needs [basins.refine] (the '
                          'refined boundary\'s points are the seeds); or use seeds = "scan"')  # fmt: skip
    out["seeds"] = seeds
    for k in sorted(set(table) & set(_TRACE)):
        out[k] = _number(table[k], _TRACE[k], f"[basins.manifold].{k}")
    if "scan" in table and seeds != "scan":
        raise ConfigError('[basins.manifold].scan is an option of seeds = "scan"')
    if seeds == "scan":
        out["scan"] = _scan_table(table.get("scan", {}))
    return out


def _saddle(system: Any, c: dict) -> Any:
    """The saddle orbit found from ``c["point"]``; a ConfigError naming the key otherwise."""
    from ..bifurcation.orbits import find_orbit
    from .config_values import ConfigError

    tol = {k: c[k] for k in ("rtol", "atol") if k in c}
    key = "[basins.manifold].point"
    try:
        orb = find_orbit(system, np.array(c["point"]), c["period"], **tol)
    except ValueError as exc:
        raise ConfigError(f"{key}: {exc}") from None
    if not orb.converged:
        raise ConfigError(f"{key}: find_orbit (period {c['period']}) from it did not converge "
                          f"({orb.status}: {orb.message})")  # fmt: skip
    mu = np.asarray(orb.multipliers)
    out = mu[np.abs(mu) > 1.0]
    if len(out) != 1 or abs(out[0].imag) > 1e-12:
        what = "a stable orbit" if len(out) == 0 else "no saddle of index one"
        raise ConfigError(
            f"{key}: find_orbit converged onto {what} (|multipliers| "
            f"{', '.join(f'{abs(z):.4g}' for z in mu)}); the stable manifold needs a saddle: "
            "exactly one real multiplier outside the unit circle"
        )
    return orb


def _fingerprint(c: dict, refine: dict | None) -> dict:
    """What the stored manifold is compared by on a rerun (JSON round trip)."""
    fp = {"manifold": c, "refine": refine if c["seeds"] == "boundary" else None}
    return json.loads(json.dumps(fp))


def _stored(path: Any) -> Any:
    """The StableManifold stored in a basins file, or None."""
    from ..analysis.basins import read_extras

    return read_extras(path)[2]


def run_manifold(result: Any, c: dict, refine: dict | None = None) -> tuple[Any, bool]:
    """Trace the ``[basins.manifold]`` table's manifold on a basin map (stored in its file).

    Returns (StableManifold, computed): ``computed`` is False when the file already
    held a manifold of the same table (and refine settings), which is returned as is.
    """
    from ..bifurcation.stable_manifold import stable_manifold, store_manifold

    fp = _fingerprint(c, refine)
    if result.path is not None:
        old = _stored(result.path)
        if old is not None and old.settings.get("config") == fp:
            result.manifold = old
            return old, False
    orb = _saddle(result.system, c)
    kw = {k: c[k] for k in _TRACE if k in c}
    if c["seeds"] == "scan":
        kw.update(seeds="scan", scan=dict(c["scan"]))
    # its integrations go to a checkpoint beside the map until the manifold is stored: the
    # same command resumes after a kill, bit-identically (base/journal.py)
    checkpoint = None if result.path is None else Path(f"{result.path}.checkpoint")
    m = stable_manifold(result, orb, store=False, checkpoint=checkpoint, **kw)
    m.settings["config"] = fp
    store_manifold(result, m)
    if checkpoint is not None:
        checkpoint.unlink(missing_ok=True)
    return m, True


def manifold_line(m: Any) -> str:
    """One line on a stored manifold (for the report)."""
    st = m.settings.get("seed_status", [])
    seeds = m.settings.get("seeds", "boundary")
    ends = ", ".join(f"{k} {m.branch_status.count(k)}" for k in sorted(set(m.branch_status)))
    mu = ", ".join(f"{abs(z):.4g}" for z in np.atleast_1d(m.mu)[:3])
    return (f"manifold:  {len(m.u)} points on {len(m.branch_status)} branches ({ends or 'none'}) "
            f"of the period-{m.saddle_period} saddle (|mu| {mu}); seeds: {seeds}, "
            f"{st.count('traced')} of {len(st)} traced; {m.n_evals} evaluations")  # fmt: skip
