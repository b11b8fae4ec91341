"""Regenerate every figure of the paper (Figs. 2-7 and 9-18) from the configs in data/.

Usage::

    python scripts/make_figures.py [--out figures/] [--quick] [--only 6,7|planes|eta_k12]
        [--format png]

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

After the paper's figures it draws **the paper in the plane** (issue 28, docs/census.md):
the censuses over (η, k12), (η, v_b) and, with the DC motor, (η, v_b0) for one and two
disks, from the configs in ``data/maps/`` (streamed and resumable like the sweeps), into
``OUT/census_plane_<name>.png``; ``eta_k12_folds``, ``eta_vb_folds``,
``eta_vb0_dcmotor_folds`` and ``eta_vb0_dcmotor_N2_folds`` lay the fold curves of
``data/curves/`` (``scripts/fold_curves_eta_k12.py``, ``scripts/fold_curves_eta_vb.py``)
over the maps. In ``--quick`` a plane has 4 x 4 cells and 4 starts, at the full times.
``--only planes`` makes the planes alone, ``--only eta_vb`` one of them.
"""

from __future__ import annotations

import argparse
import dataclasses
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
import plot_census_plane  # noqa: E402
import plot_timeseries  # noqa: E402

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.cli.config import RunConfig, load_config  # noqa: E402
from stickslip_fast.io import _jsonable, write_trajectory  # noqa: E402

__all__ = ["FIGURES", "PLANES", "Figure", "Plane", "run_config", "run_census", "make_figures",
           "main"]  # fmt: skip

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


@dataclass(frozen=True)
class Plane:
    """A census over a plane: its name, its config in data/maps/ and the curves laid over it."""

    name: str  # the image is census_plane_<name>.<fmt>
    config: str
    curves: tuple[str, ...] = ()  # curve files in data/curves/


_FOLDS = tuple(f"p1_fold_{name}_eta_k12.h5"
               for name in ("upper", "lower", "upper_resumed", "lower_resumed", "closing"))  # fmt: skip

_FOLDS_VB = tuple(f"p1_fold_{which}_{way}_eta_vb.h5"
                  for which in ("upper", "lower") for way in ("up", "down"))  # fmt: skip

PLANES: tuple[Plane, ...] = (
    Plane("eta_k12", "census_plane_eta_k12.toml"),
    Plane("eta_k12_folds", "census_plane_eta_k12.toml", _FOLDS),
    Plane("eta_vb", "census_plane_eta_vb.toml"),
    Plane("eta_vb_folds", "census_plane_eta_vb.toml", _FOLDS_VB),
    Plane("eta_vb0_dcmotor", "census_plane_eta_vb0_dcmotor.toml"),
    Plane(
        "eta_vb0_dcmotor_folds",
        "census_plane_eta_vb0_dcmotor.toml",
        ("p1_fold_upper_up_eta_vb0_dcmotor.h5", "p1_fold_upper_down_eta_vb0_dcmotor.h5"),
    ),
    Plane("eta_vb0_dcmotor_N2", "census_plane_eta_vb0_dcmotor_N2.toml"),
    # in phase, two disks are one disk (Fig. 12's curve); apart, their own fold curve
    Plane(
        "eta_vb0_dcmotor_N2_folds",
        "census_plane_eta_vb0_dcmotor_N2.toml",
        (
            "p1_fold_upper_up_eta_vb0_dcmotor.h5",
            "p1_fold_upper_down_eta_vb0_dcmotor.h5",
            "p1_fold_apart_up_eta_vb0_dcmotor_N2.h5",
            "p1_fold_apart_down_eta_vb0_dcmotor_N2.h5",
        ),
    ),
)

QUICK_VALUES = 12
QUICK_TIME_FACTOR = 0.1
QUICK_PLANE = 4  # cells per parameter and starts per cell of a quick census plane


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
    return dataclasses.replace(cfg, integration=integ, sweep=sweep,
                               title=cfg.title + " [quick]", raw=raw)  # fmt: skip


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


def _quick_plane(cfg: RunConfig) -> RunConfig:
    """A cheaper census plane: 4 x 4 cells and 4 starts, the times unchanged.

    64 runs are cheap at the full times, and shorter ones would leave most runs
    "unsettled".
    """
    census = dict(cfg.census)
    census["values"] = tuple(np.linspace(a[0], a[-1], min(len(a), QUICK_PLANE))
                             for a in census["values"])  # fmt: skip
    census["n_starts"] = min(int(census.get("n_starts", QUICK_PLANE)), QUICK_PLANE)
    return dataclasses.replace(cfg, census=census, title=cfg.title + " [quick]")


def run_census(cfg: RunConfig, out: Path, threads: int | None = None) -> Path:
    """Compute a census config into an HDF5 file (resumable), as ``stickslip-fast census``.

    Parameters
    ----------
    cfg : RunConfig
        A config with a ``[census]`` table.
    out : Path
        The census file; an existing file of the same configuration is resumed (a
        finished one is only read back), one of another configuration is refused.
    threads : int, optional
        Numba threads.

    Returns
    -------
    Path
        ``out``.
    """
    c = dict(cfg.census)
    integ = dict(cfg.integration)
    if "stop" in integ:  # [integration].stop applies unless [census].stop says otherwise
        c.setdefault("stop", integ.pop("stop"))
    ssf.census(cfg.system, c.pop("param"), c.pop("values"), out=out, threads=threads,
               progress=False, title=cfg.title, notes=cfg.notes, **c, **integ)  # fmt: skip
    return out


def _make_plane(plane: Plane, out: Path, quick: bool, fmt: str, threads: int | None) -> Path:
    """Run one census plane (or resume it) and draw its maps with its curves."""
    cfg = load_config(DATA / "maps" / plane.config)
    if quick:
        cfg = _quick_plane(cfg)
    h5 = out / "data" / (Path(plane.config).stem + ("_quick" if quick else "") + ".h5")
    run_census(cfg, h5, threads)
    image = out / f"census_plane_{plane.name}.{fmt}"
    curves = [DATA / "curves" / name for name in plane.curves]
    return plot_census_plane.plot_plane(h5, image, curves, title=cfg.title)


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
        Figure numbers ("2", "06", ...) and plane names ("eta_k12", ...; "planes": all
        of them) to make; default all.
    fmt : str
        Image format / extension ("png", "pdf").
    threads : int, optional
        Numba threads for the sweeps.
    verbose : bool
        Print one line per figure with its time.

    Returns
    -------
    dict
        Figure number or plane name -> image path.
    """
    out = Path(out)
    data_dir = out / "data"
    data_dir.mkdir(parents=True, exist_ok=True)
    wanted = None if only is None else {s.zfill(2) if s.isdigit() else s for s in only}
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
    for plane in PLANES:
        if wanted is not None and not wanted & {plane.name, "planes"}:
            continue
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*gave no orbit.*")
            made[plane.name] = _make_plane(plane, out, quick, fmt, threads)
        if verbose:
            print(f"{plane.name}: {time.perf_counter() - t0:7.1f} s  -> {made[plane.name]}",
                  flush=True)  # fmt: skip
    if verbose:
        print(f"total: {time.perf_counter() - t_all:.1f} s", flush=True)
    return made


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="figures", help="output folder (default figures/)")
    p.add_argument("--quick", action="store_true", help="few values, short times (CI)")
    p.add_argument("--only", help="comma-separated figure numbers and plane names, e.g. 6,7 or "
                   "planes or eta_k12_folds")  # fmt: skip
    p.add_argument("--format", default="png", help="image format: png or pdf")
    p.add_argument("--threads", type=int, help="Numba threads for the sweeps")
    args = p.parse_args(argv)
    only = {s.strip() for s in args.only.split(",")} if args.only else None
    make_figures(args.out, quick=args.quick, only=only, fmt=args.format, threads=args.threads)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("MPLBACKEND", "Agg")
    sys.exit(main())
