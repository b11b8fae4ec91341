"""The error of a bad configuration and the value lists of a TOML config (shared by the parsers).

A module of its own below :mod:`.config` and :mod:`.basins`, so that the
``[basins]`` table's parser can use them while the config parser calls it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..base.messages import plain

__all__ = ["ConfigError", "typed_table"]


class ConfigError(ValueError):
    """A configuration file has an unknown key or a bad value (the message names it)."""


def typed_table(table: Any, name: str, types: dict) -> dict:
    """A TOML sub-table ``[name]`` checked against ``types`` (key -> int or float): its
    values converted, or a ConfigError naming an unknown key or a value of a wrong type."""
    if not isinstance(table, dict):
        raise ConfigError(f"[{name}] must be a table")
    out = {}
    for k, v in table.items():
        if k not in types:
            raise ConfigError(f"unknown key [{name}].{k}; known: {sorted(types)}")
        want = types[k]
        if isinstance(v, bool) or not isinstance(v, (int, float) if want is float else int):
            raise ConfigError(f"[{name}].{k} must be {want.__name__}, got {v!r}")
        out[k] = want(v)
    return out


def _values_from_spec(spec: Any, key: str) -> np.ndarray:
    if isinstance(spec, dict):
        unknown = sorted(set(spec) - {"start", "stop", "num"})
        if unknown or not {"start", "stop", "num"} <= set(spec):
            raise ConfigError(
                f"{key} must be a list or {{start, stop, num}}, got keys {sorted(spec)}"
            )
        num = spec["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise ConfigError(f"{key}.num must be an integer >= 1, got {plain(num)}")
        for end in ("start", "stop"):
            v = spec[end]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ConfigError(f"{key}.{end} must be a number, got {plain(v)}")
        return np.linspace(float(spec["start"]), float(spec["stop"]), num)
    if isinstance(spec, list) and spec:
        for i, v in enumerate(spec):  # no "3.0" -> 3.0 or true -> 1.0 conversions
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ConfigError(f"{key} must hold numbers, but {key}[{i}] is {plain(v)}")
        return np.asarray(spec, dtype=float)
    raise ConfigError(f"{key} must be a non-empty list or {{start, stop, num}}, got {plain(spec)}")
