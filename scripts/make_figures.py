"""Regenerate every figure of the paper (Figs. 2-7 and 9-18) from the configs in data/.

Usage::

    python scripts/make_figures.py [--out figures/] [--quick] [--only 6,7] [--format png]

For each figure it runs the sweep (:func:`stickslip_fast.sweep`, streamed and
resumable: re-running continues an interrupted sweep) or the single run
(:func:`stickslip_fast.simulate`, skipped when its file exists with the same
configuration) into ``OUT/data/*.h5``, then draws ``OUT/figNN.png`` from those
HDF5 files only (scripts/plot_bifurcation.py, scripts/plot_timeseries.py).
Figs. 1 and 8 are schematics, not results. The N = 2 sweeps (Figs. 14, 16) also
store the cheap synchronization measure (``analyses = ["sync"]`` in their configs).

``--quick`` (for CI) uses 12 values per sweep and a tenth of the times
(t_end and t_transient divided by 10); its data files get a ``_quick`` suffix so
they never clash with the full ones.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

import plot_bifurcation  # noqa: E402
import plot_timeseries  # noqa: E402

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.cli.config import RunConfig, load_config  # noqa: E402
from stickslip_fast.io import _jsonable, write_trajectory  # noqa: E402

__all__ = ["FIGURES", "Figure", "run_config", "make_figures", "main"]

DATA = ROOT / "data"


@dataclass(frozen=True)
class Figure:
    """One paper figure: its number, kind and the config file(s) it is drawn from."""

    number: str
    kind: str  # "sweep" | "run"
    configs: tuple[str, ...]
    variables: tuple[str, ...] | None = None


FIGURES: tuple[Figure, ...] = (
    Figure("02", "sweep", ("fig02_literature_constant.toml",)),
    Figure("03", "run", ("fig03_literature_constant_eta2.7.toml",)),
    Figure("04", "sweep", ("fig04_symmetric_constant.toml",)),
    Figure("05", "run", ("fig05_symmetric_constant_eta9.95.toml",)),
    Figure("06", "sweep", ("fig06_asymmetric_constant.toml",)),
    Figure("07", "run", ("fig07_asymmetric_constant_eta9.99.toml",)),
    Figure("09", "sweep", ("fig09_literature_dcmotor.toml",)),
    Figure("10", "run", ("fig10_literature_dcmotor_eta2.7.toml",)),
    Figure("11", "run", ("fig11_symmetric_dcmotor_eta9.95.toml",)),
    Figure("12", "sweep", ("fig12_asymmetric_dcmotor.toml",)),
    Figure("13", "run", ("fig13_asymmetric_dcmotor_eta9.99.toml",)),
    Figure("14", "sweep", ("fig14_symmetric_dcmotor_N2.toml",)),
    Figure(
        "15",
        "run",
        ("fig15ab_symmetric_dcmotor_N2_eta1.1.toml", "fig15_symmetric_dcmotor_N2_eta9.99.toml"),
    ),  # fmt: skip
    Figure("16", "sweep", ("fig16_asymmetric_dcmotor_N2.toml",)),
    Figure("17", "run", ("fig17_asymmetric_dcmotor_N2_eta1.5.toml",)),
    Figure("18", "run", ("fig18_asymmetric_dcmotor_N2_eta8.toml",)),
)

QUICK_VALUES = 12
QUICK_TIME_FACTOR = 0.1


def _quick(cfg: RunConfig) -> RunConfig:
    """A cheaper version of a config: 12 values, a tenth of the times."""
    integ = dict(cfg.integration)
    integ["t_end"] = float(integ["t_end"]) * QUICK_TIME_FACTOR
    integ["t_transient"] = float(integ.get("t_transient", 0.0)) * QUICK_TIME_FACTOR
    integ["max_points"] = min(int(integ.get("max_points", 256)), 64)
    sweep = None
    if cfg.sweep is not None:
        sweep = dict(cfg.sweep)
        v = sweep["values"]
        if isinstance(v, tuple):
            sweep["values"] = tuple(np.linspace(a[0], a[-1], min(len(a), 4)) for a in v)
        else:
            sweep["values"] = np.linspace(v[0], v[-1], min(len(v), QUICK_VALUES))
    raw = json.loads(json.dumps(_jsonable(cfg.raw)))
    raw["integration"] = integ
    return RunConfig(system=cfg.system, integration=integ, y0=cfg.y0, sample_dt=cfg.sample_dt,
                     sweep=sweep, title=cfg.title + " [quick]", notes=cfg.notes,
                     source=cfg.source, raw=raw)  # fmt: skip


def run_config(cfg: RunConfig, out: Path, threads: int | None = None) -> Path:
    """Compute one config into an HDF5 file: a sweep (resumable) or a single run.

    Parameters
    ----------
    cfg : RunConfig
    out : Path
        The HDF5 file. A sweep resumes an existing file of the same
        configuration; a single run is skipped when ``out`` holds the same
        configuration and recomputed otherwise.
    threads : int, optional
        Numba threads for sweeps.

    Returns
    -------
    Path
        ``out``.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*gave no orbit.*")
        if cfg.sweep is not None:
            sw = cfg.sweep
            integ = dict(cfg.integration)
            integ.setdefault("max_points", 256)
            ssf.sweep(
                cfg.system, sw["param"], sw["values"], y0=cfg.y0, mode=sw.get("mode", "restart"),
                chunk_size=sw.get("chunk_size"), out=out, threads=threads, progress=False,
                title=cfg.title, notes=cfg.notes, analyses=sw.get("analyses", ()), **integ,
            )  # fmt: skip
            return out
        if out.exists():
            import h5py

            try:
                with h5py.File(out, "r") as h5:
                    stored = json.loads(h5.attrs["config"]).get("source")
                if stored == json.loads(json.dumps(_jsonable(cfg.raw))):
                    return out
            except (OSError, KeyError, ValueError):
                pass
        res = ssf.simulate(cfg.system, y0=cfg.y0, sample_dt=cfg.sample_dt, **cfg.integration)
        write_trajectory(out, res, cfg)
        return out


def make_figures(
    out: str | Path = "figures",
    *,
    quick: bool = False,
    only: set[str] | None = None,
    fmt: str = "png",
    threads: int | None = None,
    verbose: bool = True,
) -> dict[str, Path]:
    """Run every figure's computation into HDF5 and draw the figures from those files.

    Parameters
    ----------
    out : str or Path
        Output folder: ``figNN.<fmt>`` per figure, data in ``out/data/``.
    quick : bool
        Fewer values and shorter times (CI).
    only : set of str, optional
        Figure numbers to make ("2", "06", ...); default all.
    fmt : str
        Image format / extension ("png", "pdf").
    threads : int, optional
        Numba threads for the sweeps.
    verbose : bool
        Print one line per figure with its time.

    Returns
    -------
    dict
        Figure number -> image path.
    """
    out = Path(out)
    data_dir = out / "data"
    data_dir.mkdir(parents=True, exist_ok=True)
    wanted = None if only is None else {s.zfill(2) for s in only}
    made: dict[str, Path] = {}
    t_all = time.perf_counter()
    for fig in FIGURES:
        if wanted is not None and fig.number not in wanted:
            continue
        t0 = time.perf_counter()
        files = []
        for name in fig.configs:
            cfg = load_config(DATA / name)
            if quick:
                cfg = _quick(cfg)
            h5 = data_dir / (Path(name).stem + ("_quick" if quick else "") + ".h5")
            files.append(run_config(cfg, h5, threads))
        image = out / f"fig{fig.number}.{fmt}"
        if fig.kind == "sweep":
            plot_bifurcation.plot_sweep(files[0], image, fig.variables, period_panel=True,
                                        title=f"Fig. {int(fig.number)} (engine): "
                                        + load_config(DATA / fig.configs[0]).title.split(": ", 1)[-1])  # fmt: skip
        else:
            plot_timeseries.plot_runs(files, image,
                                      title=f"Fig. {int(fig.number)} (engine): "
                                      + load_config(DATA / fig.configs[0]).title.split(": ", 1)[-1])  # fmt: skip
        made[fig.number] = image
        if verbose:
            print(f"fig{fig.number}: {time.perf_counter() - t0:7.1f} s  -> {image}", flush=True)
    if verbose:
        print(f"total: {time.perf_counter() - t_all:.1f} s", flush=True)
    return made


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="figures", help="output folder (default figures/)")
    p.add_argument("--quick", action="store_true", help="few values, short times (CI)")
    p.add_argument("--only", help="comma-separated figure numbers, e.g. 6,7")
    p.add_argument("--format", default="png", help="image format: png or pdf")
    p.add_argument("--threads", type=int, help="Numba threads for the sweeps")
    args = p.parse_args(argv)
    only = {s.strip() for s in args.only.split(",")} if args.only else None
    make_figures(args.out, quick=args.quick, only=only, fmt=args.format, threads=args.threads)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("MPLBACKEND", "Agg")
    sys.exit(main())
