"""Command line: ``stickslip-fast simulate | sweep | census | basins | continue | info`` (and ``--version``).

A thin layer over the public API: it parses a TOML config (see
:mod:`stickslip_fast.cli.config`) and/or flags, calls :func:`simulate` /
:func:`sweep`, and prints or writes the results.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from pathlib import Path

import numpy as np

from ..base.version import package_version
from . import precompile
from .arguments import (  # noqa: F401
    _add_common,
    _check_writable,
    _config_from_args,
    _parse_value,
)
from .config import ConfigError
from .continuation import (  # noqa: F401
    _cmd_continue,
    _equilibrium_from_config,
    _orbit_from_config,
    _switch_and_follow,
)
from .report import (  # noqa: F401
    _census_report,
    _report,
    _sweep_report,
    _trajectory_report,
)

__all__ = ["main"]


def _cmd_simulate(args: argparse.Namespace) -> int:
    from ..analysis.simulate import simulate

    cfg = _config_from_args(args)
    # check the outputs before computing: a bad path should not cost a whole run
    if args.output:
        _check_writable(args.output, "-o")
    if args.save:
        _check_writable(args.save, "--save")
    res = simulate(cfg.system, y0=cfg.y0, sample_dt=cfg.sample_dt, **cfg.integration)
    if args.output:
        from ..io import write_trajectory

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


@contextlib.contextmanager
def _no_gpu_in_one_line(backend: str):
    """With the CUDA backend, a RuntimeError (no GPU, no driver) becomes one line, not a traceback."""
    try:
        yield
    except RuntimeError as exc:
        if backend != "cuda":
            raise
        raise ValueError(str(exc)) from None


def _cmd_sweep(args: argparse.Namespace) -> int:
    from ..analysis.sweep import sweep

    cfg = _config_from_args(args)
    if cfg.sweep is None:
        raise ConfigError(f"{cfg.source}: a sweep needs a [sweep] section with param and values")
    sw = cfg.sweep
    integ = dict(cfg.integration)
    integ.setdefault("max_points", 256)
    backend = args.backend or ("dask" if args.scheduler or args.workers else "local")
    with _no_gpu_in_one_line(backend):
        res = sweep(
            cfg.system, sw["param"], sw["values"], y0=cfg.y0, mode=sw.get("mode", "restart"),
            chunk_size=sw.get("chunk_size"), out=args.output, threads=args.threads,
            progress=False if args.quiet else None, backend=backend, scheduler=args.scheduler,
            n_workers=args.workers, title=cfg.title, notes=cfg.notes,
            analyses=sw.get("analyses", ()), **integ,
        )  # fmt: skip
    if not args.quiet:
        print(_report(res.path) if res.path is not None else repr(res))
    return 0


def _cmd_census(args: argparse.Namespace) -> int:
    from ..analysis.census import census

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
    with _no_gpu_in_one_line(backend):
        census(
            cfg.system, c.pop("param"), c.pop("values"), out=args.output, threads=args.threads,
            progress=False if args.quiet else None, backend=backend, scheduler=args.scheduler,
            n_workers=args.workers, title=cfg.title, notes=cfg.notes, **c, **integ,
        )  # fmt: skip
    if not args.quiet:
        print(_census_report(args.output))
    return 0


def _cmd_basins(args: argparse.Namespace) -> int:
    from .basins import cmd_basins

    return cmd_basins(_config_from_args(args), args)


def _cmd_info(args: argparse.Namespace) -> int:
    from ..io import file_kind, read_root_attrs

    if file_kind(args.file) == "branch":
        from ..bifurcation.continuation import Branch

        b = Branch.from_hdf5(args.file)
        print(f"file:      {args.file}  (branch)")
        print(f"system:    {' '.join(f'{k}={v}' for k, v in b.system.to_dict().items())}")
        print(b.summary())
        return 0
    if file_kind(args.file) == "census":
        from .basins import basins_report, is_basins_file

        print(basins_report(args.file) if is_basins_file(args.file) else _census_report(args.file))
        if args.json:
            print(json.dumps(json.loads(read_root_attrs(args.file)["config"]), indent=1))
        return 0
    print(_report(args.file, verify=True))
    if args.json:
        from ..io import sweep_summary

        if file_kind(args.file) == "trajectory":
            print(json.dumps(json.loads(read_root_attrs(args.file)["config"]), indent=1))
        else:
            print(json.dumps(sweep_summary(args.file)["config"], indent=1))
    return 0


def _add_batch_options(p: argparse.ArgumentParser, where: str, per: str) -> None:
    """The options of the commands that run many values into a file (sweep, census)."""
    _add_common(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT.h5", help="HDF5 result file")
    p.add_argument("--threads", type=int, help="Numba threads (default: all cores)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no report")
    p.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, help="start a local Dask cluster with N workers")
    p.add_argument(
        "--backend",
        choices=("local", "dask", "cuda"),
        help=f"where {where} (default: local, or dask with --scheduler/--workers); "
        f"cuda: one GPU run per {per} (docs/gpu.md)",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="stickslip-fast",
        description="Bifurcation engine for coupled translational-rotational stick-slip oscillators.",
    )
    # one source: the installed metadata (pyproject.toml's version), as stickslip_fast.__version__
    parser.add_argument("--version", action="version", version=f"%(prog)s {package_version()}")
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
    _add_batch_options(p, "values run", "value")
    p.set_defaults(func=_cmd_sweep)

    p = sub.add_parser("census", help="attractor census: every start at every value (resumable)")
    _add_batch_options(p, "runs go", "(value, start)")
    p.set_defaults(func=_cmd_census)

    p = sub.add_parser("basins", help="basins of attraction on a plane of starts (resumable)")
    _add_batch_options(p, "runs go", "cell")
    p.set_defaults(func=_cmd_basins)

    p = sub.add_parser(
        "continue",
        help="follow a periodic orbit in one parameter into a branch file (docs/orbits.md)",
    )
    _add_common(p)
    p.add_argument("-o", "--output", required=True, metavar="BRANCH.h5", help="HDF5 branch file")
    p.add_argument("--quiet", action="store_true", help="no progress and no report")
    p.set_defaults(func=_cmd_continue)

    precompile.add_parser(sub)

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
    from ..base.interrupt import lost_interrupts_raised

    if getattr(args, "quiet", False):
        from ..base import compile_notice

        compile_notice.set_enabled(False)
    try:
        with lost_interrupts_raised():
            return int(args.func(args) or 0)
    except KeyboardInterrupt:
        # the compiled work stops within about a second (interrupt.call_interruptible)
        return _interrupted(args)
    except Exception as exc:
        if _from_an_interrupt(exc):
            # Ctrl-C inside Numba's compiler, which then failed otherwise (base/interrupt.py)
            return _interrupted(args)
        return _error_status(exc)


def _error_status(exc: Exception) -> int:
    """Report an error the user can act on in one line, exit status 2; re-raise any other."""
    if isinstance(exc, (ConfigError, ValueError, ImportError)):  # ImportError: a missing extra
        print(f"stickslip-fast: error: {_one_line(exc)}", file=sys.stderr)
    elif isinstance(exc, OSError):  # a path that cannot be read or written, a full disk
        print(f"stickslip-fast: error: {_os_message(exc)}", file=sys.stderr)
    elif isinstance(exc, MemoryError):
        print(
            f"stickslip-fast: error: out of memory: {_one_line(exc) or 'allocation failed'}; "
            "ask for fewer values, points or samples",
            file=sys.stderr,
        )
    else:
        raise exc
    return 2


def _from_an_interrupt(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is among the causes and contexts of ``exc``."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


def _interrupted(args: argparse.Namespace) -> int:
    """Say what an interrupted command left behind; the exit status 130 (128 + SIGINT)."""
    out = getattr(args, "output", None)
    if args.command in ("sweep", "census", "basins") and out is not None and Path(out).exists():
        msg = (
            f"stickslip-fast: interrupted; finished chunks are in {out}, "
            "run the same command again to resume"
        )
    elif args.command == "continue" and out is not None and Path(f"{out}.checkpoint").exists():
        msg = (
            f"stickslip-fast: interrupted; the integrations so far are in {out}.checkpoint, "
            "run the same command again to resume"
        )
    else:  # nothing was written yet (or there is nothing to resume)
        msg = "stickslip-fast: interrupted"
    print(msg, file=sys.stderr)
    return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
