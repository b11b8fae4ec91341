"""Reading sweep files: whole files, single datasets, summaries, integrity."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import numpy as np

from ..base.messages import plain
from .base import ResultFileError, _short, open_h5
from .layout import ANALYSIS_FIELDS, PER_VALUE_FIELDS, SCHEMA_VERSION
from .verify import scan_sweep, stored_config


def read_dataset(path: str | Path, name: str) -> np.ndarray:
    """One whole dataset of a result file (KeyError naming the file if it has none).

    Raises
    ------
    ResultFileError
        If the file or the dataset cannot be read (truncated or corrupted).
    """
    with open_h5(path) as h5:
        if name not in h5:
            raise KeyError(f"{path} has no {name!r} dataset")
        try:
            return h5[name][...]
        except (OSError, RuntimeError) as exc:
            raise ResultFileError(
                f"{path}: {name!r} cannot be read ({_short(exc)}); the file is corrupted"
            ) from None


def sweep_summary(path: str | Path) -> dict[str, Any]:
    """What ``stickslip-fast info`` shows of a sweep file, read in one go.

    Returns
    -------
    dict
        ``config`` (parsed, checked against its SHA-256), ``attrs`` (the root
        attributes ``title``, ``package_version``, ``schema_version``,
        ``label_rules``, ``created`` where present), ``axes`` (name -> values), ``done`` (bool),
        ``status`` and ``period``.

    Raises
    ------
    ResultFileError
        If the file is not a sweep file, or what the summary needs cannot be read.
    """
    with open_h5(path) as h5:
        try:
            if "config" not in h5.attrs or "done" not in h5:
                raise ResultFileError(
                    f"{path}: an HDF5 file, but not a stickslip_fast sweep file "
                    "(no 'config' attribute or 'done' dataset)"
                )
            config = stored_config(h5)
            keys = ("title", "package_version", "schema_version", "label_rules", "created")
            return {
                "config": config,
                "attrs": {k: h5.attrs[k] for k in keys if k in h5.attrs},
                "axes": {name: h5[name][...] for name in config["param"]},
                "done": h5["done"][...].astype(bool),
                "status": h5["status"][...],
                "period": h5["period"][...],
                "fletcher32": bool(h5["done"].fletcher32),
            }
        except (OSError, RuntimeError, KeyError) as exc:
            raise ResultFileError(
                f"{path}: cannot be summarised, the file is damaged ({_short(exc)})"
            ) from None


def read_root_attrs(path: str | Path) -> dict[str, Any]:
    """Every root attribute of a result file of any kind (``config`` is its JSON text).

    Opened as :func:`~stickslip_fast.io.base.open_h5` does: readable while a writer
    appends, and a damaged file fails at once naming itself.
    """
    with open_h5(path) as h5:
        return dict(h5.attrs)


def file_kind(path: str | Path) -> str:
    """``"trajectory"`` (``simulate -o``), ``"census"``, ``"branch"`` (``continue``), else ``"sweep"``."""
    with open_h5(path) as h5:
        try:
            kind = h5.attrs.get("kind")
        except (OSError, RuntimeError, KeyError):
            return "sweep"  # the sweep reader reports what is wrong
    return kind if kind in ("trajectory", "census", "branch") else "sweep"


def verify_sweep(path: str | Path) -> tuple[list[str], np.ndarray]:
    """Read every chunk of a sweep file and check its SHA-256s (see :func:`scan_sweep`)."""
    with open_h5(path) as h5:
        return scan_sweep(h5)


def read_sweep(path: str | Path) -> dict[str, Any]:
    """Read a whole sweep file into memory: arrays, coordinates and configuration.

    Raises
    ------
    ResultFileError
        If the file is not a sweep file, is truncated or corrupted (the message
        names the file, and the dataset that cannot be read).
    """
    out: dict[str, Any] = {}
    with open_h5(path) as h5:
        name = "attributes"
        try:
            if h5.attrs.get("schema_version") != SCHEMA_VERSION:
                raise ResultFileError(
                    f"{path}: not a stickslip_fast sweep file (schema_version missing)"
                )
            if h5.attrs.get("kind") == "trajectory":
                raise ResultFileError(
                    f"{path} is a trajectory file (simulate -o); read it with read_trajectory"
                )
            out["config"] = stored_config(h5)
            out["attrs"] = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
            params = tuple(str(h5.attrs["param"]).split(","))
            out["param"] = params
            name = "coordinates"
            out["axes"] = tuple(h5[p][...] for p in params)
            out["branches"] = "branch" in h5
            out["state_names"] = [
                s.decode() if isinstance(s, bytes) else s for s in h5["state"][...]
            ]
            for name in ("points", "t_points", "final_state", "done", *PER_VALUE_FIELDS):
                out[name] = h5[name][...]
            out["analyses"] = {}
            for name in (*ANALYSIS_FIELDS, "t_converged"):
                if name in h5:
                    out["analyses"][name] = h5[name][...]
        except (OSError, RuntimeError, KeyError, ValueError) as exc:
            if isinstance(exc, ResultFileError):
                raise
            raise ResultFileError(
                f"{path}: {name!r} cannot be read ({_short(exc)}); the file is corrupted"
            ) from None
    for p, axis, want in zip(params, out["axes"], out["config"].get("values_sha256", ())):
        got = hashlib.sha256(np.ascontiguousarray(axis, dtype="<f8").tobytes()).hexdigest()
        if got != want:
            raise ResultFileError(
                f"{path}: the stored values of {plain(p)} do not match their SHA-256 in the "
                "configuration; the file is corrupted"
            )
    return out
