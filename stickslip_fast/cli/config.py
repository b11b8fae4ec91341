"""TOML run configurations: one file describes a simulation or a sweep.

Layout (every section optional except what the command needs)::

    title = "Fig. 6: asymmetric springs, constant belt"
    notes = "free text kept in the result file"

    [system]              # a preset plus overrides, or every field spelled out
    preset = "asymmetric"
    eta = 1.5
    drive = "constant"
    n_oscillators = 1

    [initial]             # at most one of these; default: the zero state
    y0 = [0.0, 0.0, 0.0, 0.0]                     # state layout x1, dx1, phi1, dphi1, ...
    # y0_paper = [x1, x2, dx1, dx2, phi1, phi2, dphi1, dphi2]   (the paper's N = 2 order)
    # vb = 0.0            # DC motor: initial belt speed when y0_paper is used

    [integration]
    t_end = 3000.0
    t_transient = 2000.0
    method = "rodas5p"    # rodas5p | dopri5 | dopri5-fixed | rodas4p | rodas4p2 | auto
    rtol = 1e-9
    atol = 1e-11
    # h = 1e-5            # fixed step (dopri5-fixed)
    max_points = 256

    [simulate]
    sample_dt = 0.05

    [sweep]
    param = "eta"                                  # or ["eta", "k12"]
    values = { start = 1.0, stop = 10.0, num = 1000 }   # or a list; 2-D: a list of two
    mode = "restart"                               # restart | continuation | continuation-both
    chunk_size = 64
    analyses = ["sync"]                            # extra per-value results (io.ANALYSES)

    [census]              # stickslip-fast census: every start at every value
    param = "eta"                                  # or ["eta", "k12"]: a census over the plane
    values = { start = 1.0, stop = 10.0, num = 200 }   # two parameters: a list of two
    n_starts = 64         # the zero state included (include_zero = true)
    seed = 0
    # box = [[lo, hi], ...]     one pair per state variable (default: census.default_box)
    # starts = [[...], ...]     explicit initial states instead of the sampler
    stop = "fixed"        # fixed | converged
    # identity_tol, track_threshold, chunk_size

    [continue]            # stickslip-fast continue: follow an orbit or equilibrium in one parameter
    param = "eta"         # the orbit is found at the [system]'s value (simulated from [initial]
    bounds = [1.5, 3.5]   #   with [integration], then Newton on the return map)
    start = "orbit"       # orbit | sliding | stall (equilibria: find_equilibrium, no simulation)
    # period = 1          # default: the period the simulation finds
    direction = "both"    # 1: towards larger values; -1: smaller; "both": one branch through the start
    # ds, ds_min, ds_max, max_points, tol   (see continue_orbit)
    # shooting = "single"|"multiple"|"auto", segments, remesh, max_segments   (multiple shooting)
    # param2, bounds2, direction2, kinds2   (the codim-1 points' curves in a 2nd parameter)
    # switch = true       # also follow the orbits born at each PD / SB / branch point
    # sharp_ends = false  # do not retry with tighter settings where the corrector fails
    # stick_events = false  # do not count stick phases (branch and curves)

Unknown sections or keys, and bad values, raise :class:`ConfigError` naming them.
"""

from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..base.messages import plain
from ..bifurcation.multishoot import DEFAULT_SEGMENTS
from ..core.settings import Settings
from ..model.system import SWEEPABLE, System
from .config_values import ConfigError, _values_from_spec  # noqa: F401  (re-exported)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["ConfigError", "RunConfig", "load_config", "parse_config", "paper_order_to_state"]

#: [integration] keys: the fields of Settings, with their declared types.
_SETTING_TYPES = {f.name: str(f.type) for f in dataclasses.fields(Settings)}
_TOML_TYPES = {
    "float": ("a number", (int, float)),
    "int": ("an integer", int),
    "str": ("a string", str),
}

_SECTIONS = {
    "title": None,
    "notes": None,
    "system": None,  # keys checked by System
    "initial": {"y0", "y0_paper", "vb"},
    "integration": set(_SETTING_TYPES),  # every field of Settings
    "simulate": {"sample_dt"},
    "sweep": {"param", "values", "mode", "chunk_size", "analyses"},
    "census": {
        "param", "values", "n_starts", "seed", "include_zero", "box", "starts", "stop",
        "chunk_size", "identity_tol", "track_threshold",
    },
    "basins": None,  # keys checked by cli.basins.parse_basins_table
    "continue": {
        "param", "bounds", "start", "period", "direction", "ds", "ds_min", "ds_max",
        "max_points", "tol", "switch", "sharp_ends", "stick_events", "shooting", "segments",
        "remesh", "max_segments", "param2", "bounds2", "direction2", "kinds2",
    },
}  # fmt: skip


@dataclass
class RunConfig:
    """A parsed configuration; see the module docstring for the file layout."""

    system: System
    integration: dict[str, Any]
    y0: np.ndarray | None = None
    sample_dt: float | None = None
    sweep: dict[str, Any] | None = None
    census: dict[str, Any] | None = None
    continuation: dict[str, Any] | None = None
    basins: dict[str, Any] | None = None
    title: str = ""
    notes: str = ""
    source: str = ""
    raw: dict[str, Any] = field(default_factory=dict)


def paper_order_to_state(values: Any, n_oscillators: int, vb: float | None) -> np.ndarray:
    """Convert the paper's (x1..xN, dx1..dxN, phi1..phiN, dphi1..dphiN) order.

    The paper writes initial conditions for N = 2 as
    (x1, x2, dx1, dx2, phi1, phi2, dphi1, dphi2); the engine's state is grouped
    per disk (x1, dx1, phi1, dphi1, x2, ...). ``vb`` appends the DC motor's
    initial belt speed.
    """
    arr = np.asarray(values, dtype=float)
    n = n_oscillators
    if arr.shape != (4 * n,):
        raise ConfigError(f"initial.y0_paper must have {4 * n} entries, got {arr.size}")
    out = arr.reshape(4, n).T.reshape(-1)
    if vb is not None:
        out = np.append(out, float(vb))
    return out


def _analyses(value: Any) -> tuple[str, ...]:
    from ..io import ANALYSES

    if not isinstance(value, list) or not all(isinstance(a, str) for a in value):
        raise ConfigError(f"[sweep].analyses must be a list of names, got {plain(value)}")
    unknown = [a for a in value if a not in ANALYSES]
    if unknown:
        raise ConfigError(f"[sweep].analyses: unknown {unknown}; choose from {sorted(ANALYSES)}")
    return tuple(value)


def parse_config(data: dict[str, Any], source: str = "<dict>") -> RunConfig:
    """Validate a configuration mapping (as read from TOML)."""
    _check_sections(data)
    system = _parse_system(data)
    y0 = _parse_initial(data.get("initial", {}), system)
    integration = _parse_integration(data)
    sample_dt = _parse_sample_dt(data)
    sweep = _parse_sweep(dict(data["sweep"])) if "sweep" in data else None
    census = _parse_census(data["census"]) if "census" in data else None
    continuation = _parse_continue(data["continue"]) if "continue" in data else None
    basins = None
    if "basins" in data:
        from .basins import parse_basins_table

        basins = parse_basins_table(data["basins"], n_state=system.n_state)

    title = data.get("title", "")
    notes = data.get("notes", "")
    if not isinstance(title, str) or not isinstance(notes, str):
        raise ConfigError("title and notes must be strings")
    return RunConfig(
        system=system,
        integration=integration,
        y0=y0,
        sample_dt=None if sample_dt is None else float(sample_dt),
        sweep=sweep,
        census=census,
        continuation=continuation,
        basins=basins,
        title=title,
        notes=notes,
        source=source,
        raw=data,
    )


def _check_sections(data: dict[str, Any]) -> None:
    """Every section and key is known, and every section that must be a table is one."""
    for section, value in data.items():
        if section not in _SECTIONS:
            raise ConfigError(f"unknown section or key {section!r}; allowed: {sorted(_SECTIONS)}")
        allowed = _SECTIONS[section]
        if allowed is not None:
            if not isinstance(value, dict):
                raise ConfigError(
                    f"{section!r} must be a table ([{section}] with its keys), got {plain(value)}"
                )
            unknown = sorted(set(value) - allowed)
            if unknown:
                raise ConfigError(
                    f"unknown key(s) {unknown} in [{section}]; allowed: {sorted(allowed)}"
                )


def _parse_system(data: dict[str, Any]) -> System:
    """The ``[system]`` table: a preset with overrides, or every field."""
    if not isinstance(data.get("system", {}), dict):
        raise ConfigError(
            f"'system' must be a table ([system] with preset = ... and fields), "
            f"got {data['system']!r}"
        )
    sys_table = dict(data.get("system", {}))
    preset = sys_table.pop("preset", None)
    try:
        system = System.preset(preset, **sys_table) if preset else System.from_dict(sys_table)
    except (ValueError, TypeError) as exc:
        raise ConfigError(f"[system]: {exc}") from None
    return system


def _parse_initial(initial: dict[str, Any], system: System) -> np.ndarray | None:
    """The ``[initial]`` table: ``y0`` in state order, or ``y0_paper`` (with ``vb``)."""
    y0 = None
    if "y0" in initial and "y0_paper" in initial:
        raise ConfigError("[initial]: give y0 or y0_paper, not both")
    if "vb" in initial and "y0_paper" not in initial:
        raise ConfigError("[initial].vb is only used with y0_paper (y0 includes vb)")
    try:
        if "y0" in initial:
            y0 = system.initial_state(initial["y0"])
        elif "y0_paper" in initial:
            vb = initial.get("vb", 0.0 if system.is_dc_motor else None)
            if vb is not None and not system.is_dc_motor:
                raise ConfigError("[initial].vb needs drive = 'dc-motor'")
            y0 = system.initial_state(
                paper_order_to_state(initial["y0_paper"], system.n_oscillators, vb)
            )
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:
        key = "y0" if "y0" in initial else "y0_paper"
        raise ConfigError(f"[initial].{key}: {exc}") from None
    return y0


def _parse_integration(data: dict[str, Any]) -> dict[str, Any]:
    """The ``[integration]`` table, its types checked (its values are checked by Settings)."""
    integration = dict(data.get("integration", {}))
    for key, value in integration.items():
        kind, types = _TOML_TYPES[_SETTING_TYPES[key]]
        if isinstance(value, bool) or not isinstance(value, types):
            raise ConfigError(f"[integration].{key} must be {kind}, got {plain(value)}")
    return integration


def _parse_sample_dt(data: dict[str, Any]) -> float | int | None:
    """``[simulate].sample_dt``: a number > 0, or None."""
    sample_dt = data.get("simulate", {}).get("sample_dt")
    if sample_dt is not None and (
        isinstance(sample_dt, bool) or not isinstance(sample_dt, (int, float)) or sample_dt <= 0
    ):
        raise ConfigError(f"[simulate].sample_dt must be a number > 0, got {plain(sample_dt)}")
    return sample_dt


def _parse_sweep(sw: dict[str, Any]) -> dict[str, Any]:
    """The ``[sweep]`` table: one or two parameters with their values, mode, chunking, analyses."""
    if "param" not in sw or "values" not in sw:
        raise ConfigError("[sweep] needs 'param' and 'values'")
    param = sw["param"]
    if isinstance(param, list):
        if len(param) != 2 or not all(isinstance(p, str) for p in param):
            raise ConfigError(f"[sweep].param must be a name or a list of two names, got {param!r}")
        vals = sw["values"]
        if not isinstance(vals, list) or len(vals) != 2:
            raise ConfigError("[sweep].values must be a list of two value specs for a 2-D sweep")
        values: Any = tuple(
            _values_from_spec(v, f"[sweep].values[{i}]") for i, v in enumerate(vals)
        )
        param = tuple(param)
    elif isinstance(param, str):
        values = _values_from_spec(sw["values"], "[sweep].values")
    else:
        raise ConfigError(f"[sweep].param must be a string, got {param!r}")
    for name in (param,) if isinstance(param, str) else param:
        if name not in SWEEPABLE:
            raise ConfigError(
                f"[sweep].param {name!r} cannot be swept; choose from {list(SWEEPABLE)}"
            )
    sweep = {"param": param, "values": values}
    if "mode" in sw:
        modes = ("restart", "continuation", "continuation-both")
        if sw["mode"] not in modes:
            raise ConfigError(f"[sweep].mode must be one of {modes}, got {sw['mode']!r}")
        sweep["mode"] = sw["mode"]
    if "chunk_size" in sw:
        cs = sw["chunk_size"]
        if isinstance(cs, bool) or not isinstance(cs, int) or cs < 1:
            raise ConfigError(f"[sweep].chunk_size must be an integer >= 1, got {cs!r}")
        sweep["chunk_size"] = cs
    if "analyses" in sw:
        sweep["analyses"] = _analyses(sw["analyses"])
    return sweep


def _parse_census(table: dict[str, Any]) -> dict[str, Any]:
    """Validate a ``[census]`` table (types only; census() checks the values)."""
    sw = dict(table)
    if "param" not in sw or "values" not in sw:
        raise ConfigError("[census] needs 'param' and 'values'")
    param, values = sw["param"], sw["values"]
    if isinstance(param, list):  # a census over a plane: two names, two value specs
        if len(param) != 2 or not all(isinstance(p, str) for p in param):
            raise ConfigError(f"[census].param must be a name or a list of two, got {param!r}")
        if not isinstance(values, list) or len(values) != 2:
            raise ConfigError("[census].values must be a list of two value specs for two params")
        param = tuple(param)
        values = tuple(_values_from_spec(v, f"[census].values[{i}]") for i, v in enumerate(values))
    elif isinstance(param, str):
        values = _values_from_spec(values, "[census].values")
    else:
        raise ConfigError(f"[census].param must be a string, got {param!r}")
    out: dict[str, Any] = {"param": param, "values": values}
    for key in ("n_starts", "seed", "chunk_size"):
        if key in sw:
            v = sw[key]
            if isinstance(v, bool) or not isinstance(v, int):
                raise ConfigError(f"[census].{key} must be an integer, got {plain(v)}")
            out[key] = v
    for key in ("identity_tol", "track_threshold"):
        if key in sw:
            v = sw[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ConfigError(f"[census].{key} must be a number, got {plain(v)}")
            out[key] = float(v)
    if "include_zero" in sw:
        if not isinstance(sw["include_zero"], bool):
            raise ConfigError(
                f"[census].include_zero must be true or false, got {sw['include_zero']!r}"
            )
        out["include_zero"] = sw["include_zero"]
    if "stop" in sw:
        if not isinstance(sw["stop"], str):
            raise ConfigError(f"[census].stop must be a string, got {sw['stop']!r}")
        out["stop"] = sw["stop"]
    for key in ("box", "starts"):
        if key in sw:
            try:
                out[key] = np.asarray(sw[key], dtype=float)
            except (TypeError, ValueError) as exc:
                raise ConfigError(
                    f"[census].{key} must be a list of lists of numbers: {exc}"
                ) from None
    return out


def _parse_continue(table: dict[str, Any]) -> dict[str, Any]:
    """Validate a ``[continue]`` table (types only; continue_orbit() checks the values)."""
    if "param" not in table or "bounds" not in table:
        raise ConfigError("[continue] needs 'param' and 'bounds'")
    param = table["param"]
    if not isinstance(param, str) or param not in SWEEPABLE:
        raise ConfigError(f"[continue].param must be one of {list(SWEEPABLE)}, got {param!r}")
    b = table["bounds"]
    if (
        not isinstance(b, list)
        or len(b) != 2
        or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in b)
    ):
        raise ConfigError(f"[continue].bounds must be a list of two numbers, got {b!r}")
    out: dict[str, Any] = {"param": param, "bounds": (float(b[0]), float(b[1]))}
    starts = ("orbit", "sliding", "stall")
    if "start" in table:
        if table["start"] not in starts:
            raise ConfigError(f"[continue].start must be one of {starts}, got {table['start']!r}")
        out["start"] = table["start"]
    if "period" in table and out.get("start", "orbit") != "orbit":
        raise ConfigError("[continue].period applies to start = 'orbit' only")
    for key in ("period", "max_points"):
        if key in table:
            v = table[key]
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ConfigError(f"[continue].{key} must be an integer >= 1, got {plain(v)}")
            out[key] = v
    if "direction" in table:
        d = table["direction"]
        if isinstance(d, bool) or d not in (1, -1, "both"):
            raise ConfigError(f'[continue].direction must be 1, -1 or "both", got {d!r}')
        out["direction"] = d if d == "both" else float(d)
    for key in ("ds", "ds_min", "ds_max", "tol"):
        if key in table:
            v = table[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
                raise ConfigError(f"[continue].{key} must be a number > 0, got {plain(v)}")
            out[key] = float(v)
    if "switch" in table:
        if not isinstance(table["switch"], bool):
            raise ConfigError(f"[continue].switch must be true or false, got {table['switch']!r}")
        if table["switch"] and out.get("start", "orbit") != "orbit":
            raise ConfigError("[continue].switch applies to start = 'orbit' only")
        out["switch"] = table["switch"]
    for key in ("sharp_ends", "stick_events"):  # switches of orbit branches
        if key in table:
            v = table[key]
            if not isinstance(v, bool):
                raise ConfigError(f"[continue].{key} must be true or false, got {plain(v)}")
            if out.get("start", "orbit") != "orbit":
                raise ConfigError(f"[continue].{key} applies to start = 'orbit' only")
            out[key] = v
    _parse_issue28_keys(table, out)
    return out


def _parse_issue28_keys(table: dict[str, Any], out: dict[str, Any]) -> None:
    """[continue].shooting / segments / remesh / max_segments (multiple shooting) and
    param2 / bounds2 / direction2 (the two-parameter curves of the branch's folds and
    period-doublings, or of an equilibrium branch's folds and Hopf points), into ``out``."""
    orbit = out.get("start", "orbit") == "orbit"
    if "shooting" in table:
        if table["shooting"] not in ("single", "multiple", "auto") or not orbit:
            raise ConfigError('[continue].shooting must be "single", "multiple" or "auto" '
                              f"(start = 'orbit' only), got {table['shooting']!r}")  # fmt: skip
        out["shooting"] = table["shooting"]
    for key in ("segments", "max_segments"):  # max_segments: at least segments
        least = out.get("segments", DEFAULT_SEGMENTS) if key == "max_segments" else 1
        if key in table:
            v = table[key]
            if isinstance(v, bool) or not isinstance(v, int) or v < least or not orbit:
                raise ConfigError(f"[continue].{key} must be an integer >= {least} (start = "
                                  f"'orbit' only), got {plain(v)}")  # fmt: skip
            out[key] = v
    if "remesh" in table:
        out["remesh"] = v = table["remesh"]
        if not isinstance(v, bool) or (v and out.get("shooting", "single") == "single"):
            raise ConfigError(f"[continue].remesh must be true or false (true needs shooting = "
                              f"'multiple' or 'auto'), got {plain(v)}")  # fmt: skip
    if "param2" not in table:
        if "bounds2" in table or "direction2" in table or "kinds2" in table:
            raise ConfigError("[continue].bounds2, direction2 and kinds2 need param2")
        return
    p2, b2 = table["param2"], table.get("bounds2")
    if not isinstance(p2, str) or p2 not in SWEEPABLE or p2 in (out["param"], "n_oscillators"):
        raise ConfigError(f"[continue].param2 must be one of {list(SWEEPABLE)} other than param "
                          f"and n_oscillators, got {p2!r}")  # fmt: skip
    if not (isinstance(b2, list) and len(b2) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in b2)):  # fmt: skip
        raise ConfigError(f"[continue].bounds2 must be a list of two numbers, got {b2!r}")
    d2 = table.get("direction2", 1)
    if isinstance(d2, bool) or d2 not in (1, -1):
        raise ConfigError(f"[continue].direction2 must be 1 or -1, got {d2!r}")
    out["param2"], out["bounds2"], out["direction2"] = p2, (float(b2[0]), float(b2[1])), float(d2)
    if "kinds2" in table:
        allowed = CURVE_KINDS2 if orbit else ("fold", "hopf")
        k2 = table["kinds2"]
        if not (isinstance(k2, list) and k2 and all(k in allowed for k in k2)):
            raise ConfigError(f"[continue].kinds2 must be a non-empty list of {list(allowed)}, "
                              f"got {k2!r}")  # fmt: skip
        out["kinds2"] = tuple(k2)


#: The kinds of an orbit branch's points [continue].kinds2 may name (default: the first three).
CURVE_KINDS2 = ("fold", "period-doubling", "neimark-sacker", "stick-phase", "symmetry-breaking")


def load_config(path: str | Path) -> RunConfig:
    """Read and validate a TOML configuration file."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"config file not found: {path}") from None
    except IsADirectoryError:
        raise ConfigError(f"{path} is a directory, not a TOML config file") from None
    except PermissionError:
        raise ConfigError(f"{path}: permission denied reading the config file") from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the config file ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"{path}: not a TOML text file (invalid UTF-8 at byte {exc.start}; is it binary?)"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: invalid TOML: {exc}") from None
    try:
        return parse_config(data, source=str(path))
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None
