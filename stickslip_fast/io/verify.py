"""Verifying result files: the stored configuration and its SHA-256, every chunk's checksum."""

from __future__ import annotations

import hashlib
import json

import h5py
import numpy as np

from .base import ResultFileError, _short, config_digest
from .layout import ANALYSES, PER_VALUE_FIELDS, SweepLayout


def _data_fields(layout: SweepLayout) -> tuple[str, ...]:
    return (*layout.result_fields, "done")


def scan_sweep(
    h5: h5py.File, layout: SweepLayout | None = None, config: dict | None = None
) -> tuple[list[str], np.ndarray]:
    """Verify a sweep file by reading every chunk of every per-value dataset.

    Reading checks each chunk's Fletcher-32 checksum and its compression; the
    swept values are checked against their SHA-256 in the stored configuration.

    Parameters
    ----------
    h5 : h5py.File
        An open sweep file.
    layout : SweepLayout, optional
        The expected layout (default: taken from the file).
    config : dict, optional
        The expected configuration (default: the file's own, after checking it
        against the stored ``config_sha256``).

    Returns
    -------
    problems : list of str
        What is wrong, one phrase each (empty for a sound file).
    bad : ndarray of bool, grid shape
        Values with at least one unreadable piece.
    """
    problems: list[str] = []
    if config is None:
        cfg = stored_config(h5)
    else:
        cfg = json.loads(config_digest(config)[0])
        try:
            stored_config(h5)
        except ResultFileError as exc:
            problems.append(str(exc).split(": ", 1)[-1])
    if layout is None:
        fields, grid = _expected_fields(h5, cfg)
    else:
        fields = _data_fields(layout)
        grid = layout.grid_shape
    problems += _check_value_digests(h5, cfg)
    bad = np.zeros(grid, dtype=bool)
    problems += _scan_chunks(h5, fields, grid, bad)
    return problems, bad


def _expected_fields(h5: h5py.File, cfg: dict) -> tuple[tuple[str, ...], tuple[int, ...]]:
    """The per-value datasets and the grid shape a file's own configuration implies."""
    fields = ("points", "t_points", "final_state", "done", *PER_VALUE_FIELDS)
    fields += tuple(f for a in cfg.get("analyses", ()) for f in ANALYSES[a])
    if "t_converged" in h5:
        fields += ("t_converged",)
    grid = (2,) if cfg["mode"] == "continuation-both" else ()
    grid += tuple(int(n) for n in cfg["n_values"])
    return fields, grid


def _check_value_digests(h5: h5py.File, cfg: dict) -> list[str]:
    """Check the swept values against their SHA-256 in the configuration."""
    problems = []
    params = [cfg["param"]] if isinstance(cfg["param"], str) else list(cfg["param"])  # census: str
    value_digests = cfg.get("values_sha256", ())
    if isinstance(value_digests, str):
        value_digests = [value_digests]
    for name, want in zip(params, value_digests):
        try:
            got = hashlib.sha256(np.ascontiguousarray(h5[name][...], dtype="<f8").tobytes())
            if got.hexdigest() != want:
                problems.append(
                    f"the stored values of {name!r} do not match their SHA-256 in the "
                    "configuration (corrupted coordinate)"
                )
        except (OSError, RuntimeError, KeyError, ValueError) as exc:
            problems.append(f"the values of {name!r} cannot be read ({_short(exc)})")
    return problems


def _scan_chunks(h5: h5py.File, fields, grid: tuple[int, ...], bad: np.ndarray) -> list[str]:
    """Read every chunk of ``fields``; mark the values of unreadable ones in ``bad``."""
    problems = []
    g = len(grid)
    unreadable: list[str] = []
    first = ""
    for name in fields:
        try:
            ds = h5[name]
            if ds.shape[:g] != grid:
                raise ValueError(f"shape {ds.shape} does not match the grid {grid}")
            chunks = list(ds.iter_chunks()) if ds.chunks else [(slice(None),) * ds.ndim]
        except (OSError, RuntimeError, KeyError, ValueError) as exc:
            problems.append(f"dataset {name!r} cannot be read ({_short(exc)})")
            bad[...] = True
            continue
        n_bad = 0
        for sel in chunks:
            try:
                ds[sel]
            except (OSError, RuntimeError, ValueError) as exc:
                bad[sel[:g]] = True
                n_bad += 1
                first = first or _short(exc)
        if n_bad:
            unreadable.append(f"{name} ({n_bad} of {len(chunks)})")
    if unreadable:
        problems.append(
            f"unreadable chunks (checksum or decompression failed: {first}) in "
            + ", ".join(unreadable)
        )
    return problems


def stored_config(h5: h5py.File) -> dict:
    """The configuration stored in a result file, checked against its SHA-256.

    Raises
    ------
    ResultFileError
        If the attribute is missing, is not JSON, or does not match
        ``config_sha256``.
    """
    name = h5.filename
    try:
        text = h5.attrs["config"]
        want = h5.attrs.get("config_sha256")
    except (OSError, RuntimeError, KeyError) as exc:
        raise ResultFileError(f"{name}: the configuration cannot be read ({_short(exc)})") from None
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    if want is not None and hashlib.sha256(str(text).encode()).hexdigest() != want:
        raise ResultFileError(
            f"{name}: the stored configuration does not match its SHA-256 (corrupted attribute)"
        )
    try:
        return json.loads(text)
    except (TypeError, ValueError):
        raise ResultFileError(f"{name}: the stored configuration is not valid JSON") from None
