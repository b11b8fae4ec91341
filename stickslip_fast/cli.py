"""Command line: ``stickslip-fast simulate | sweep | census | basins | continue | info``.

A thin layer over the public API: it parses a TOML config (see
:mod:`stickslip_fast.config`) and/or flags, calls :func:`simulate` /
:func:`sweep`, and prints or writes the results.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .config import ConfigError, RunConfig, load_config, parse_config
from .system import DRIVES, PRESETS
from .trajectory import METHODS

__all__ = ["main"]


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

    from .io import _make_parent

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


def _cmd_simulate(args: argparse.Namespace) -> int:
    from .simulate import simulate

    cfg = _config_from_args(args)
    # check the outputs before computing: a bad path should not cost a whole run
    if args.output:
        _check_writable(args.output, "-o")
    if args.save:
        _check_writable(args.save, "--save")
    res = simulate(cfg.system, y0=cfg.y0, sample_dt=cfg.sample_dt, **cfg.integration)
    if args.output:
        from .io import write_trajectory

        write_trajectory(args.output, res, cfg)
        print(f"wrote {args.output}", file=sys.stderr)
    if args.json:
        out = {
            "system": cfg.system.to_dict(),
            "settings": res.settings.to_dict(),
            "status": res.status,
            "period": res.period,
            "n_steps": res.n_steps,
            "n_rejected": res.n_rejected,
            "n_crossings": res.n_crossings,
            "state_names": res.state_names,
            "t_poincare": res.t_poincare.tolist(),
            "poincare": res.poincare.tolist(),
        }
        json.dump(out, sys.stdout, indent=1)
        print()
        return 0
    s = cfg.system
    print(f"# {cfg.title or 'simulate'}")
    print(
        f"# drive={s.drive} N={s.n_oscillators} eta={s.eta:g} m={s.m:g} k12={s.k12:g} "
        f"mu={s.mu:g} eps={s.eps:g} method={res.method} rtol={res.settings['rtol']:g}"
    )
    print(
        f"# t_end={res.settings['t_end']:g} t_transient={res.settings['t_transient']:g} "
        f"steps={res.n_steps} rejected={res.n_rejected} crossings={res.n_crossings}"
    )
    print(f"status: {res.status}")
    print(f"period: {res.period if res.period else 'none detected (0)'}")
    shown = args.show
    pts = res.poincare[-shown:] if shown else res.poincare[:0]
    tp = res.t_poincare[-shown:] if shown else res.t_poincare[:0]
    if len(pts):
        print(f"Poincare points (local minima of x1), last {len(pts)} of {len(res.t_poincare)}:")
        cols = ["t"] + res.state_names
        print("  ".join(f"{c:>14s}" for c in cols))
        for t, row in zip(tp, pts):
            print("  ".join(f"{v:14.8g}" for v in np.concatenate([[t], row])))
    if args.save:
        np.savez(args.save, t_poincare=res.t_poincare, poincare=res.poincare,
                 state_names=np.array(res.state_names), t=res.t if res.t is not None else [],
                 y=res.y if res.y is not None else [])  # fmt: skip
        print(f"saved {args.save}")
    return 0


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .sweep import sweep

    cfg = _config_from_args(args)
    if cfg.sweep is None:
        raise ConfigError(f"{cfg.source}: a sweep needs a [sweep] section with param and values")
    sw = cfg.sweep
    integ = dict(cfg.integration)
    integ.setdefault("max_points", 256)
    backend = args.backend or ("dask" if args.scheduler or args.workers else "local")
    try:
        res = sweep(
            cfg.system, sw["param"], sw["values"], y0=cfg.y0, mode=sw.get("mode", "restart"),
            chunk_size=sw.get("chunk_size"), out=args.output, threads=args.threads,
            progress=False if args.quiet else None, backend=backend, scheduler=args.scheduler,
            n_workers=args.workers, title=cfg.title, notes=cfg.notes,
            analyses=sw.get("analyses", ()), **integ,
        )  # fmt: skip
    except RuntimeError as exc:
        if backend != "cuda":
            raise
        raise ValueError(str(exc)) from None  # no GPU: one line, not a traceback
    if not args.quiet:
        print(_report(res.path) if res.path is not None else repr(res))
    return 0


def _cmd_census(args: argparse.Namespace) -> int:
    from .census import census

    cfg = _config_from_args(args)
    if cfg.census is None:
        raise ConfigError(f"{cfg.source}: a census needs a [census] section with param and values")
    c = dict(cfg.census)
    integ = dict(cfg.integration)
    if "stop" in integ:  # [integration].stop applies unless [census].stop says otherwise
        if "stop" in c and c["stop"] != integ["stop"]:
            raise ConfigError(
                f"{cfg.source}: [integration].stop = {integ['stop']!r} and [census].stop = "
                f"{c['stop']!r} disagree; give one"
            )
        c["stop"] = integ.pop("stop")
    backend = args.backend or ("dask" if (args.scheduler or args.workers) else "local")
    try:
        census(
            cfg.system, c.pop("param"), c.pop("values"), out=args.output, threads=args.threads,
            progress=False if args.quiet else None, backend=backend, scheduler=args.scheduler,
            n_workers=args.workers, title=cfg.title, notes=cfg.notes, **c, **integ,
        )  # fmt: skip
    except RuntimeError as exc:
        if backend != "cuda":
            raise
        raise ValueError(str(exc)) from None  # no GPU: one line, not a traceback
    if not args.quiet:
        print(_census_report(args.output))
    return 0


def _cmd_basins(args: argparse.Namespace) -> int:
    from .basins_cli import cmd_basins

    return cmd_basins(_config_from_args(args), args)


def _cmd_continue(args: argparse.Namespace) -> int:
    from .continuation import continue_equilibrium, continue_orbit, join_branches, switch_branch

    cfg = _config_from_args(args)
    if cfg.continuation is None:
        raise ConfigError(
            f"{cfg.source}: continuation needs a [continue] section with param and bounds"
        )
    _check_writable(args.output, "-o")
    c = dict(cfg.continuation)
    param, bounds = c.pop("param"), c.pop("bounds")
    start = c.pop("start", "orbit")
    direction = c.pop("direction", 1.0)
    switch = c.pop("switch", False)
    say = (lambda *a: None) if args.quiet else (lambda *a: print(*a, file=sys.stderr))
    if start == "orbit":
        first, follow = _orbit_from_config(cfg, param, c.pop("period", None), say), continue_orbit
    else:
        first, follow = _equilibrium_from_config(cfg, param, start, say), continue_equilibrium
    say(f"continuing in {param} over {list(bounds)} ...")
    if direction == "both":
        branch = join_branches(follow(first, param, bounds, direction=-1.0, **c),
                               follow(first, param, bounds, direction=1.0, **c))  # fmt: skip
    else:
        branch = follow(first, param, bounds, direction=direction, **c)
    branch.to_hdf5(args.output)
    if not args.quiet:
        print(f"file:      {args.output}  (branch)")
        print(branch.summary())
    if switch:
        _switch_and_follow(branch, bounds, c, args, say, switch_branch, continue_orbit)
    return 0


def _switch_and_follow(branch, bounds, settings, args, say, switch_branch, continue_orbit):
    """[continue].switch: from each period-doubling of ``branch``, the doubled orbit's
    branch, continued away from it, into OUTPUT's stem + ``.pd<k>.h5``."""
    out = Path(args.output)
    pds = [b for b in branch.bifurcations if b.kind == "period-doubling"]
    if not pds:
        say("switch: the branch has no period-doubling")
    for k, pd in enumerate(pds, start=1):
        say(f"switching at the period-doubling at {branch.param} = {pd.value:.10g} ...")
        orbit = switch_branch(branch, pd, tol=settings.get("tol", 1e-10))
        if not orbit.converged:
            print(f"period-doubling {k} at {pd.value:.10g}: {orbit.message}", file=sys.stderr)
            continue
        value = getattr(orbit.system, branch.param)
        away = 1.0 if value >= pd.value else -1.0
        doubled = continue_orbit(orbit, branch.param, bounds, direction=away, **settings)
        path = out.with_name(f"{out.stem}.pd{k}{out.suffix or '.h5'}")
        doubled.to_hdf5(path)
        if not args.quiet:
            print(f"file:      {path}  (period-{orbit.period} branch from the "
                  f"period-doubling at {pd.value:.10g})")  # fmt: skip
            print(doubled.summary())


def _orbit_from_config(cfg: RunConfig, param: str, period, say):
    """The orbit of the config's system: a simulation from [initial], then Newton."""
    from .orbits import find_orbit
    from .simulate import simulate

    value = getattr(cfg.system, param)
    say(f"settling at {param} = {value:g} (t_end {cfg.integration['t_end']:g}) ...")
    sim = simulate(cfg.system, y0=cfg.y0, **cfg.integration)
    if sim.status != "ok" or sim.period < 1:
        raise ValueError(
            f"the simulation at {param} = {value:g} ended {sim.status!r} with period "
            f"{sim.period}: no periodic orbit to continue; change [system].{param}, "
            "[initial] or [integration].t_end"
        )
    orbit = find_orbit(cfg.system, sim, period)
    if not orbit.converged:
        raise ValueError(
            f"Newton on the return map did not converge at {param} = {value:g} "
            f"(status {orbit.status!r}: {orbit.message})"
        )
    lead = np.abs(orbit.multipliers).max() if orbit.multipliers.size else float("nan")
    say(f"orbit: period {orbit.period}, T = {orbit.T:.10g}, residual {orbit.residual:.2g}, "
        f"|leading multiplier| {lead:.4g}")  # fmt: skip
    return orbit


def _equilibrium_from_config(cfg: RunConfig, param: str, start: str, say):
    """The config's system's rest point (``start`` "sliding" or "stall")."""
    from .orbits import find_equilibrium

    eq = find_equilibrium(cfg.system, start)
    if not eq.converged:
        raise ValueError(
            f"no {start} equilibrium found at {param} = {getattr(cfg.system, param):g} "
            f"(residual {eq.residual:.2g}); change [system] or [continue].start"
        )
    say(f"equilibrium ({eq.kind}): stable {eq.stable}, leading eigenvalue "
        f"{eq.eigenvalues[0]:.4g}")  # fmt: skip
    return eq


def _census_report(path) -> str:
    """A text summary of a census file: configuration, progress, attractors per value."""
    import h5py

    from .census import load_census
    from .poincare import STATUS_NAMES

    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        attrs = dict(h5.attrs)
    cfg = json.loads(attrs["config"])
    res = load_census(path)
    done = res.raw["done"].astype(bool)
    lines = [f"file:      {path}  (census)"]
    if attrs.get("title"):
        lines.append(f"title:     {attrs['title']}")
    lines.append(
        f"package:   stickslip_fast {attrs.get('package_version', '?')}, "
        f"schema {attrs.get('schema_version')}, created {attrs.get('created', '?')}"
    )
    sysd = {k: v for k, v in cfg["system"].items() if v is not None}
    lines.append("system:    " + " ".join(f"{k}={v}" for k, v in sysd.items()))
    v = res.values
    lines.append(
        f"census:    {res.param} in [{v.min():g}, {v.max():g}] ({v.size} values) x "
        f"{len(res.starts)} starts, stop={cfg['stop']}"
    )
    st = cfg["settings"]
    lines.append(
        f"settings:  method={st['method']} rtol={st['rtol']:g} atol={st['atol']:g} "
        f"t_end={st['t_end']:g} t_transient={st['t_transient']:g} max_points={st['max_points']}"
    )
    lines.append(
        f"progress:  {int(done.sum())} of {done.size} runs done ({100 * done.mean():.1f}%)"
    )
    if done.any():
        codes, counts = np.unique(res.status_code[done], return_counts=True)
        lines.append(
            "status:    " + ", ".join(f"{STATUS_NAMES[c]} {n}" for c, n in zip(codes, counts))
        )
        lines.append(f"tracks:    {len(res.tracks)} (classified from the runs done so far)"
                     if not done.all() else f"tracks:    {len(res.tracks)}")  # fmt: skip
        for t in res.tracks:
            desc = t.kind if t.kind != "orbit" else f"orbit P{'/P'.join(map(str, t.periods))}"
            frac = res.fractions()[t.birth : t.death + 1, t.id]
            lines.append(
                f"  #{t.id:<3d} {desc:<22s} {res.param} {v[t.birth]:g}..{v[t.death]:g}"
                f"{'  born' if t.born else ''}{'  dies' if t.dies else ''}"
                f"  basin {frac.min():.2f}-{frac.max():.2f}"
            )
    return "\n".join(lines)


def _report(path, verify: bool = False) -> str:
    """A text summary of a result file: configuration, progress, periods, statuses.

    A trajectory file (``simulate -o``) gets its own summary. With ``verify``,
    every chunk of a sweep file is read (checksums) and the swept values are
    checked against their SHA-256; a damaged file raises
    :class:`~stickslip_fast.io.ResultFileError` after the summary is printed.
    """
    from .io import file_kind, open_h5, sweep_summary, verify_sweep, writer_alive

    if file_kind(path) == "trajectory":
        with open_h5(path) as h5:
            return _trajectory_report(path, h5)
    text, has_fletcher = _sweep_report(path, sweep_summary(path))
    if not verify:
        return text
    if writer_alive(path):
        return text + "\nintegrity: not checked (a sweep is writing this file now)"
    problems, bad = verify_sweep(path)
    if problems:
        print(text)
        from .io import ResultFileError

        raise ResultFileError(
            f"{path} is corrupted: {'; '.join(problems)} ({int(bad.sum())} of {bad.size} "
            "values affected). Run the same sweep again to recompute them."
        )
    checksums = "Fletcher-32 and SHA-256 verified" if has_fletcher else "SHA-256 verified"
    return text + f"\nintegrity: ok (every chunk read; {checksums})"


def _sweep_report(path, info: dict) -> tuple[str, bool]:
    from .poincare import STATUS_NAMES

    cfg, attrs = info["config"], info["attrs"]
    done, status, period = info["done"], info["status"], info["period"]
    lines = [f"file:      {path}"]
    if attrs.get("title"):
        lines.append(f"title:     {attrs['title']}")
    lines.append(
        f"package:   stickslip_fast {attrs.get('package_version', '?')}, "
        f"schema {attrs.get('schema_version')}, created {attrs.get('created', '?')}"
    )
    sysd = {k: v for k, v in cfg["system"].items() if v is not None}
    lines.append("system:    " + " ".join(f"{k}={v}" for k, v in sysd.items()))
    axes = [f"{n} in [{a.min():g}, {a.max():g}] ({a.size} values)" for n, a in info["axes"].items()]
    lines.append("sweep:     " + " x ".join(axes) + f", mode {cfg['mode']}")
    st = cfg["settings"]
    lines.append(
        f"settings:  method={st['method']} rtol={st['rtol']:g} atol={st['atol']:g} "
        f"t_end={st['t_end']:g} t_transient={st['t_transient']:g} max_points={st['max_points']}"
    )
    lines.append(
        f"progress:  {int(done.sum())} of {done.size} values done ({100 * done.mean():.1f}%)"
    )
    if done.any():
        codes, counts = np.unique(status[done], return_counts=True)
        lines.append(
            "status:    "
            + ", ".join(
                f"{STATUS_NAMES[c] if 0 <= c < len(STATUS_NAMES) else f'code {c}'} {n}"
                for c, n in zip(codes, counts)
            )
        )
        ok = done & (status == 0)
        if ok.any():
            per, pc = np.unique(period[ok], return_counts=True)
            hist = ", ".join(f"{'none' if p == 0 else f'P{p}'}: {n}" for p, n in zip(per, pc))
            lines.append(f"periods:   {hist}")
    return "\n".join(lines), bool(info.get("fletcher32"))


def _trajectory_report(path, h5) -> str:
    """The summary of a single-run file written by ``simulate -o``."""
    a = h5.attrs
    cfg = json.loads(a["config"])
    st = cfg.get("settings", {})
    lines = [f"file:      {path} (single run, simulate -o)"]
    if a.get("title"):
        lines.append(f"title:     {a['title']}")
    lines.append(
        f"package:   stickslip_fast {a.get('package_version', '?')}, "
        f"schema {a.get('schema_version')}, created {a.get('created', '?')}"
    )
    sysd = {k: v for k, v in cfg.get("system", {}).items() if v is not None}
    lines.append("system:    " + " ".join(f"{k}={v}" for k, v in sysd.items()))
    if st:
        lines.append(
            f"settings:  method={a.get('method', st.get('method'))} rtol={st['rtol']:g} "
            f"atol={st['atol']:g} t_end={st['t_end']:g} t_transient={st['t_transient']:g}"
        )
    period = int(a["period"])
    lines.append(
        f"result:    status {a['status']}, period {period if period else 'none detected'}, "
        f"{int(a['n_steps'])} steps ({int(a['n_rejected'])} rejected), "
        f"{int(a['n_crossings'])} Poincare crossings"
    )
    n_t = h5["t"].shape[0]
    sample = cfg.get("sample_dt")
    lines.append(
        f"data:      {h5['poincare'].shape[0]} Poincare points, {n_t} samples"
        + (f" every {sample:g}" if n_t and sample else "")
        + f"; state {', '.join(s.decode() if isinstance(s, bytes) else str(s) for s in h5['state'][...])}"
    )
    return "\n".join(lines)


def _cmd_info(args: argparse.Namespace) -> int:
    from .io import file_kind

    if file_kind(args.file) == "branch":
        from .continuation import Branch

        b = Branch.from_hdf5(args.file)
        print(f"file:      {args.file}  (branch)")
        print(f"system:    {' '.join(f'{k}={v}' for k, v in b.system.to_dict().items())}")
        print(b.summary())
        return 0
    if file_kind(args.file) == "census":
        from .basins_cli import basins_report, is_basins_file

        print(basins_report(args.file) if is_basins_file(args.file) else _census_report(args.file))
        if args.json:
            import h5py

            with h5py.File(args.file, "r", libver="latest", swmr=True) as h5:
                print(json.dumps(json.loads(h5.attrs["config"]), indent=1))
        return 0
    print(_report(args.file, verify=True))
    if args.json:
        from .io import file_kind, open_h5, sweep_summary

        if file_kind(args.file) == "trajectory":
            with open_h5(args.file) as h5:
                print(json.dumps(json.loads(h5.attrs["config"]), indent=1))
        else:
            print(json.dumps(sweep_summary(args.file)["config"], indent=1))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="stickslip-fast",
        description="Bifurcation engine for coupled translational-rotational stick-slip oscillators.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("simulate", help="one trajectory: Poincare points and period")
    _add_common(p)
    p.add_argument("--sample-dt", dest="sample_dt", type=float, help="also sample a time grid")
    p.add_argument("--show", type=int, default=12, help="how many points to print (default 12)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--save", metavar="FILE.npz", help="save points and samples to an .npz file")
    p.add_argument(
        "-o", "--output", metavar="RUN.h5",
        help="write the run (samples, Poincare points, status, config) to an HDF5 file",
    )  # fmt: skip
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser("sweep", help="bifurcation sweep into an HDF5 file (resumable)")
    _add_common(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT.h5", help="HDF5 result file")
    p.add_argument("--threads", type=int, help="Numba threads (default: all cores)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no report")
    p.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, help="start a local Dask cluster with N workers")
    p.add_argument(
        "--backend",
        choices=("local", "dask", "cuda"),
        help="where values run (default: local, or dask with --scheduler/--workers); "
        "cuda: one GPU thread per value (docs/gpu.md)",
    )
    p.set_defaults(func=_cmd_sweep)

    p = sub.add_parser("census", help="attractor census: every start at every value (resumable)")
    _add_common(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT.h5", help="HDF5 result file")
    p.add_argument("--threads", type=int, help="Numba threads (default: all cores)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no report")
    p.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, help="start a local Dask cluster with N workers")
    p.add_argument(
        "--backend",
        choices=("local", "dask", "cuda"),
        help="where runs go (default: local, or dask with --scheduler/--workers); "
        "cuda: one GPU thread per (value, start) (docs/gpu.md)",
    )
    p.set_defaults(func=_cmd_census)

    p = sub.add_parser("basins", help="basins of attraction on a plane of starts (resumable)")
    _add_common(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT.h5", help="HDF5 result file")
    p.add_argument("--threads", type=int, help="Numba threads (default: all cores)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no report")
    p.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, help="start a local Dask cluster with N workers")
    p.add_argument("--backend", choices=("local", "dask", "cuda"), help="as for census")
    p.set_defaults(func=_cmd_basins)

    p = sub.add_parser(
        "continue",
        help="follow a periodic orbit in one parameter into a branch file (docs/orbits.md)",
    )
    _add_common(p)
    p.add_argument("-o", "--output", required=True, metavar="BRANCH.h5", help="HDF5 branch file")
    p.add_argument("--quiet", action="store_true", help="no progress and no report")
    p.set_defaults(func=_cmd_continue)

    p = sub.add_parser("info", help="summarise a result file")
    p.add_argument("file", metavar="OUT.h5")
    p.add_argument("--json", action="store_true", help="also print the stored configuration")
    p.set_defaults(func=_cmd_info)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one plain line for command-line users (no source excerpt)."""
    print(f"stickslip-fast: warning: {message}", file=file or sys.stderr)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


def _os_message(exc: OSError) -> str:
    """An OSError as one line that names the path."""
    if exc.filename is not None and exc.strerror:
        extra = f" -> {exc.filename2}" if exc.filename2 else ""
        return f"{exc.filename}{extra}: {exc.strerror}"
    return _one_line(exc) or type(exc).__name__


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    import warnings

    warnings.showwarning = _show_warning
    try:
        return int(args.func(args) or 0)
    except (ConfigError, ValueError, ImportError) as exc:  # ImportError: a missing extra
        print(f"stickslip-fast: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:  # a path that cannot be read or written, a full disk
        print(f"stickslip-fast: error: {_os_message(exc)}", file=sys.stderr)
        return 2
    except MemoryError as exc:
        print(
            f"stickslip-fast: error: out of memory: {_one_line(exc) or 'allocation failed'}; "
            "ask for fewer values, points or samples",
            file=sys.stderr,
        )
        return 2
    except KeyboardInterrupt:
        # the compiled work stops within about a second (interrupt.call_interruptible)
        out = getattr(args, "output", None)
        if args.command in ("sweep", "census", "basins") and out is not None and Path(out).exists():
            msg = (
                f"stickslip-fast: interrupted; finished chunks are in {out}, "
                "run the same command again to resume"
            )
        else:  # nothing was written yet (or there is nothing to resume)
            msg = "stickslip-fast: interrupted"
        print(msg, file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
