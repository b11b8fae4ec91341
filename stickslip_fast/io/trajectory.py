"""Single runs (``simulate -o``) to and from HDF5."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .base import (
    ResultFileError,
    _make_parent,
    _os_error,
    _short,
    atomic_h5,
    config_digest,
    open_h5,
)
from .layout import SCHEMA_VERSION, write_root_attrs


# ------------------------------------------------------------- single runs
def _jsonable(obj: Any) -> Any:
    """Plain JSON-compatible values (arrays to lists, Paths to str)."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    return obj


def write_trajectory(path: str | Path, result: Any, config: Any = None) -> Path:
    """Store one :class:`~stickslip_fast.SimulationResult` in an HDF5 file.

    The layout is the trajectory schema in this module's docstring. The file is
    written to ``<path>.partial`` and renamed, so it appears only when complete;
    an existing file is replaced.

    Parameters
    ----------
    path : str or Path
        Output file (``.h5``).
    result : SimulationResult
        What :func:`~stickslip_fast.simulate` returned (with ``sample_dt`` for
        the time grid ``t``, ``y``; without it they are stored empty).
    config : RunConfig or dict, optional
        The run's configuration: a :class:`~stickslip_fast.cli.config.RunConfig`
        (its TOML mapping, title, notes, y0 and sample_dt are stored) or any
        JSON-serialisable mapping (stored under ``"user"``).

    Returns
    -------
    Path
        The written file.
    """
    path = Path(path)
    cfg, title, notes = _trajectory_config(result, config)
    text, digest = config_digest(_jsonable(cfg))
    _make_parent(path)
    try:
        with atomic_h5(path, libver="latest") as h5:
            _write_trajectory_file(h5, result, text, digest, title, notes)
    except OSError as exc:
        if not exc.filename:
            raise _os_error(path, exc) from None
        raise
    return path


def _trajectory_config(result: Any, config: Any) -> tuple[dict[str, Any], str, str]:
    """The configuration mapping a trajectory file stores, with its title and notes."""
    cfg: dict[str, Any] = {
        "system": result.system.to_dict(),
        "settings": result.settings.to_dict(),
        "method": result.method,
    }
    title = notes = ""
    if config is not None and hasattr(config, "raw") and hasattr(config, "system"):
        cfg["source"] = config.raw
        cfg["y0"] = None if config.y0 is None else np.asarray(config.y0).tolist()
        cfg["sample_dt"] = config.sample_dt
        title, notes = config.title, config.notes
    elif isinstance(config, dict):
        cfg["user"] = config
        title = str(config.get("title", ""))
        notes = str(config.get("notes", ""))
    elif config is not None:
        raise TypeError(f"config must be a RunConfig or a dict, got {type(config).__name__}")
    if result.t is not None and len(result.t) > 1:
        cfg.setdefault("sample_dt", float(result.t[1] - result.t[0]))
    return cfg, title, notes


def _write_trajectory_file(h5: h5py.File, result: Any, text, digest, title, notes) -> None:
    """Write the root attributes, the coordinates and the datasets of one trajectory."""
    from ..base.version import package_version

    system = result.system
    n_state = len(result.state_names)
    t = np.zeros(0) if result.t is None else np.asarray(result.t, dtype="f8")
    y = np.zeros((0, n_state)) if result.y is None else np.asarray(result.y, dtype="f8")
    tp = np.asarray(result.t_poincare, dtype="f8")
    pts = np.asarray(result.poincare, dtype="f8").reshape(len(tp), n_state)
    a = h5.attrs
    write_root_attrs(a, text, digest, title, notes, package_version(), kind="trajectory")
    a["status"] = result.status
    a["period"] = int(result.period)
    a["method"] = result.method
    for key in ("n_steps", "n_rejected", "n_crossings"):
        a[key] = int(getattr(result, key))
    a["t_final"] = float(result.t_final)
    a["amplitude"] = float(result.amplitude)
    a["rest_time"] = float(result.rest_time)
    for key, value in system.to_dict().items():
        a[f"system.{key}"] = value

    def scale(name: str, data: np.ndarray, long_name: str, **kw: Any) -> h5py.Dataset:
        d = h5.create_dataset(name, data=data, **kw)
        d.make_scale(name)
        d.attrs["long_name"] = long_name
        return d

    st = scale("state", np.array(result.state_names, dtype=object), "state variable",
               dtype=h5py.string_dtype())  # fmt: skip
    ts = scale("t", t, "time (nondimensional)", maxshape=(None,))
    cs = scale("crossing", np.arange(len(tp), dtype="i4"),
               "index of the Poincare point, in time order", maxshape=(None,))  # fmt: skip
    specs = {
        "y": (y, (ts, st), "State sampled every sample_dt from t_transient"),
        "t_poincare": (tp, (cs,), "Times of the Poincare points (local minima of x1)"),
        "poincare": (pts, (cs, st), "Full state at each Poincare point"),
        "final_state": (np.asarray(result.final_state, dtype="f8"), (st,), "State at t_end"),
    }
    for name, (data, dims, desc) in specs.items():
        d = h5.create_dataset(
            name, data=data, maxshape=(None,) * data.ndim,
            compression="gzip" if data.size else None,
            compression_opts=1 if data.size else None, fletcher32=True,
        )  # fmt: skip
        for i, sc in enumerate(dims):
            d.dims[i].attach_scale(sc)
        d.attrs["description"] = desc


def _read(path: str | Path, body: Callable[[h5py.File], Any]) -> tuple[dict, list[str], Any]:
    """(root attributes with numbers as Python numbers, state names, ``body(h5)``) of a
    single-run file (ResultFileError for another file, or a damaged one)."""
    with open_h5(path) as h5:
        if h5.attrs.get("schema_version") != SCHEMA_VERSION or h5.attrs.get("kind") != "trajectory":
            raise ResultFileError(f"{path}: not a stickslip_fast trajectory file")
        try:
            attrs = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
            names = [s.decode() if isinstance(s, bytes) else str(s) for s in h5["state"][...]]
            return attrs, names, body(h5)
        except (OSError, RuntimeError, KeyError) as exc:
            raise ResultFileError(f"{path}: corrupted ({_short(exc)})") from None


def read_trajectory_header(path: str | Path) -> dict[str, Any]:
    """What a summary of a single-run file needs, without reading its arrays: ``attrs``,
    ``config`` (parsed), ``state_names``, ``n_samples`` and ``n_points``.

    Raises
    ------
    ValueError
        If the file is not a trajectory file of this schema.
    """
    attrs, names, (n_samples, n_points) = _read(
        path, lambda h5: (h5["t"].shape[0], h5["poincare"].shape[0])
    )
    return {"attrs": attrs, "config": json.loads(attrs["config"]), "state_names": names,
            "n_samples": int(n_samples), "n_points": int(n_points)}  # fmt: skip


def read_trajectory(path: str | Path) -> dict[str, Any]:
    """Read a file written by :func:`write_trajectory`.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    dict
        ``t``, ``y``, ``t_poincare``, ``poincare``, ``final_state`` (arrays),
        ``state_names``, ``status``, ``period``, ``title``, ``notes``,
        ``config`` (the stored JSON, parsed), ``attrs`` (all root attributes),
        ``system`` (a :class:`~stickslip_fast.System`) and ``result`` (a
        :class:`~stickslip_fast.SimulationResult` rebuilt from the file).

    Raises
    ------
    ValueError
        If the file is not a trajectory file of this schema.
    """
    from ..core.results import SimulationResult
    from ..core.settings import Settings
    from ..model.system import System

    fields = ("t", "y", "t_poincare", "poincare", "final_state")
    attrs, names, data = _read(path, lambda h5: {name: h5[name][...] for name in fields})
    config = json.loads(attrs["config"])
    system = System.from_dict(config["system"])
    result = SimulationResult(
        system=system,
        method=str(attrs["method"]),
        state_names=names,
        t_poincare=data["t_poincare"],
        poincare=data["poincare"],
        n_crossings=int(attrs["n_crossings"]),
        period=int(attrs["period"]),
        status=str(attrs["status"]),
        n_steps=int(attrs["n_steps"]),
        n_rejected=int(attrs["n_rejected"]),
        t_final=float(attrs["t_final"]),
        final_state=data["final_state"],
        amplitude=float(attrs["amplitude"]),
        rest_time=float(attrs.get("rest_time", -1.0)),  # files of 0.1.0 lack it
        t=data["t"],
        y=data["y"],
        settings=Settings.from_dict(config["settings"]),
    )
    return {
        **data,
        "state_names": names,
        "status": result.status,
        "period": result.period,
        "title": str(attrs.get("title", "")),
        "notes": str(attrs.get("notes", "")),
        "config": config,
        "attrs": attrs,
        "system": system,
        "result": result,
    }
