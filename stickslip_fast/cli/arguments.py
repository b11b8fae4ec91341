"""What every command shares: the common options, a config with the command line's overrides
applied, and the early check that an output path can be written."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from ..core.trajectory import METHODS
from ..model.system import DRIVES, PRESETS
from .config import ConfigError, RunConfig, load_config, parse_config


def _parse_value(text: str) -> Any:
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def _config_from_args(args: argparse.Namespace) -> RunConfig:
    """A config file (if given) with the command-line overrides applied on top."""
    data: dict[str, Any] = {}
    if args.config:
        base = load_config(args.config)
        data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.raw.items()}
    system = data.setdefault("system", {})
    if args.preset:
        system.clear()
        system["preset"] = args.preset
    elif not args.config:
        system["preset"] = "asymmetric"
    for name in ("eta", "drive", "n_oscillators"):
        value = getattr(args, name)
        if value is not None:
            system[name] = value
    for item in args.set or []:
        if "=" not in item:
            raise ConfigError(f"--set expects KEY=VALUE, got {item!r}")
        key, value = item.split("=", 1)
        system[key.strip()] = _parse_value(value.strip())
    integ = data.setdefault("integration", {})
    for name in ("t_end", "t_transient", "method", "rtol", "atol", "h", "max_points"):
        value = getattr(args, name, None)
        if value is not None:
            integ[name] = value
    integ.setdefault("t_end", 3000.0)
    integ.setdefault("t_transient", 2000.0 if integ["t_end"] > 2000.0 else 0.0)
    if getattr(args, "sample_dt", None) is not None:
        data.setdefault("simulate", {})["sample_dt"] = args.sample_dt
    return parse_config(data, source=args.config or "<command line>")


def _add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument("config", nargs="?", help="TOML configuration file (see docs/configs.md)")
    p.add_argument("--preset", choices=sorted(PRESETS), help="parameter set (default: asymmetric)")
    p.add_argument("--eta", type=float, help="static/kinetic friction ratio eta in [1, 10]")
    p.add_argument("--drive", choices=DRIVES)
    p.add_argument("--n-oscillators", dest="n_oscillators", type=int)
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a System field")
    p.add_argument("--t-end", dest="t_end", type=float)
    p.add_argument("--t-transient", dest="t_transient", type=float)
    p.add_argument("--method", choices=METHODS)
    p.add_argument("--rtol", type=float)
    p.add_argument("--atol", type=float)
    p.add_argument("--h", type=float, help="fixed step (dopri5-fixed)")
    p.add_argument("--max-points", dest="max_points", type=int)


def _check_writable(path: str, what: str) -> None:
    """Fail now, with one line naming the path, if ``path`` cannot be written later."""

    from ..io import _make_parent

    p = Path(path)
    if p.is_dir():
        raise IsADirectoryError(f"{what} {p} is a directory; give a file name")
    if what == "--save":  # np.savez does not create folders
        if not p.parent.is_dir():
            raise FileNotFoundError(f"cannot write {what} {p}: no directory {p.parent}")
    else:
        _make_parent(p)
    if not os.access(p.parent, os.W_OK | os.X_OK) or (p.exists() and not os.access(p, os.W_OK)):
        raise PermissionError(f"cannot write {what} {p}: permission denied")
