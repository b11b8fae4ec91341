"""Snapshot the engine's results on every config in data/, to prove a refactor changes nothing.

For each sweep config: a 50-value grid over its own range (each axis of a 2-D
sweep gets 7 values), with the config's integration settings and mode. For each
single-run config: the run itself (points, samples, final state). Also a
Lyapunov exponent on two presets, and periodic orbits with their multipliers
(``--only orbits``). Each census config of data/census/ runs through the CLI on a
50-value grid with 4 starts, and each continuation config of data/continuation/
through the CLI with at most 8 points (``--only census`` / ``--only continue``);
their result files' datasets go into the snapshot. Everything goes into one ``.npz`` file;
``--compare OLD.npz`` then reports, array by array, whether the new results
are bit-identical and the largest difference where they are not.

Usage::

    python3 scripts/regression_snapshot.py -o before.npz
    # ... change the code, clear the Numba cache ...
    python3 scripts/regression_snapshot.py -o after.npz --compare before.npz
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

import stickslip_fast as ssf
from stickslip_fast.cli.config import load_config

ROOT = Path(__file__).resolve().parents[1]
GRID = 50
GRID_2D = 7


def _grid(values: np.ndarray, num: int) -> np.ndarray:
    return np.linspace(float(values[0]), float(values[-1]), num)


def snapshot(only: str | None = None) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for path in sorted((ROOT / "data").glob("*.toml")):
        if only and only not in path.name:
            continue
        cfg = load_config(path)
        integ = dict(cfg.integration)
        key = path.stem
        if cfg.sweep is not None:
            param = cfg.sweep["param"]
            if isinstance(param, tuple):
                values = tuple(_grid(v, GRID_2D) for v in cfg.sweep["values"])
            else:
                values = _grid(cfg.sweep["values"], GRID)
            res = ssf.sweep(
                cfg.system, param, values, y0=cfg.y0, mode=cfg.sweep.get("mode", "restart"),
                progress=False, **integ,
            )  # fmt: skip
            out[f"{key}/points"] = res.points
            out[f"{key}/period"] = res.period
            out[f"{key}/status"] = np.asarray(res.status).astype("U16")
            out[f"{key}/n_steps"] = res.n_steps
            out[f"{key}/final_state"] = res.final_state
        else:
            res = ssf.simulate(cfg.system, y0=cfg.y0, sample_dt=cfg.sample_dt, **integ)
            out[f"{key}/points"] = res.poincare
            out[f"{key}/t_points"] = res.t_poincare
            out[f"{key}/period"] = np.array(res.period)
            out[f"{key}/status"] = np.array(res.status)
            out[f"{key}/n_steps"] = np.array([res.n_steps, res.n_rejected])
            out[f"{key}/final_state"] = res.final_state
            if res.y is not None:
                out[f"{key}/samples"] = res.y
        print(f"{key}: done", file=sys.stderr, flush=True)
    if not only or "lyapunov" in only:
        for preset, eta in (("asymmetric", 2.0), ("literature", 2.7)):
            lr = ssf.largest_lyapunov(ssf.System.preset(preset, eta=eta), 1500, 500)
            key = f"lyapunov_{preset}_{eta}"
            out[f"{key}/exponent"] = np.array([lr.exponent, lr.exponent_fit])
            out[f"{key}/convergence"] = lr.convergence
            out[f"{key}/n_steps"] = np.array([lr.n_steps, lr.n_rejected])
            out[f"{key}/final_state"] = lr.final_state
        print("lyapunov: done", file=sys.stderr, flush=True)
    if not only or "orbits" in only:
        out.update(_orbits())
        print("orbits: done", file=sys.stderr, flush=True)
    if not only or "census" in only:
        out.update(_cli_runs("census", CENSUS_GRID))
    if not only or "continue" in only:
        out.update(_cli_runs("continuation", CONTINUE_POINTS))
    return out


CENSUS_GRID = 50  # values per census config (4 starts each)
CONTINUE_POINTS = 8  # points per continuation config


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    return "[" + ", ".join(_toml_value(x) for x in v) + "]"


def _toml(data: dict) -> str:
    """A minimal TOML writer for the raw mapping of a config (tomllib only reads)."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"[{k}]")
            lines += [f"{kk} = {_toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def _h5_arrays(path: Path, key: str) -> dict[str, np.ndarray]:
    import h5py

    out: dict[str, np.ndarray] = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            a = obj[()]
            out[f"{key}/{name}"] = np.asarray(a).astype("U64") if a.dtype.kind in "OSU" else a

    with h5py.File(path, "r") as h5:
        h5.visititems(visit)
    return out


def _cli_runs(folder: str, size: int) -> dict[str, np.ndarray]:
    """Run every config of data/<folder>/ through the CLI, cut down to ``size``."""
    from stickslip_fast.cli import main as cli_main

    out: dict[str, np.ndarray] = {}
    for path in sorted((ROOT / "data" / folder).glob("*.toml")):
        cfg = load_config(path)
        raw = {k: (dict(v) if isinstance(v, dict) else v) for k, v in cfg.raw.items()}
        if folder == "census":
            vals = np.asarray(cfg.census["values"], dtype=float)
            raw["census"]["values"] = [float(x) for x in _grid(vals, size)]
            raw["census"]["n_starts"] = 4
            cmd = "census"
        else:
            raw["continue"]["max_points"] = size
            cmd = "continue"
        with tempfile.TemporaryDirectory() as tmp:
            cfg_path, res_path = Path(tmp) / path.name, Path(tmp) / "out.h5"
            cfg_path.write_text(_toml(raw))
            rc = cli_main([cmd, str(cfg_path), "-o", str(res_path), "--quiet"])
            out[f"{folder}_{path.stem}/rc"] = np.array(rc)
            for res in sorted(Path(tmp).glob("*.h5")):
                out.update(_h5_arrays(res, f"{folder}_{path.stem}/{res.name}"))
        print(f"{folder}/{path.stem}: done", file=sys.stderr, flush=True)
    return out


def _orbits() -> dict[str, np.ndarray]:
    """Newton solves, multipliers, a short continuation and a DC-motor Lyapunov exponent.

    These run the tangent problem (the variational equations) for one and two
    disks, constant belt and DC motor.
    """
    out: dict[str, np.ndarray] = {}
    cases = (
        ("fig06_asymmetric_constant.toml", 2.0),
        ("fig06_asymmetric_constant.toml", 9.99),
        ("fig12_asymmetric_dcmotor.toml", 3.0),
        ("fig16_asymmetric_dcmotor_N2.toml", 1.5),
    )
    for name, eta in cases:
        system = load_config(ROOT / "data" / name).system.replace(eta=eta)
        orbit = ssf.find_orbit(system, ssf.simulate(system, 4000.0, stop="converged"))
        key = f"orbit_{Path(name).stem}_{eta}"
        out[f"{key}/points"] = orbit.points
        out[f"{key}/T"] = np.array([orbit.T, orbit.residual, orbit.iterations])
        out[f"{key}/multipliers"] = orbit.multipliers
        out[f"{key}/status"] = np.array(orbit.status)
        if name.startswith("fig06") and eta == 2.0:
            branch = ssf.continue_orbit(orbit, "eta", (1.9, 2.2), ds=0.02, max_points=6)
            out[f"{key}/branch_values"] = branch.values
            out[f"{key}/branch_multipliers"] = branch.multipliers
        if name.startswith("fig12"):
            lr = ssf.largest_lyapunov(system, 1500, 500)
            out[f"{key}/lyapunov"] = np.array([lr.exponent, lr.exponent_fit, lr.n_steps])
    return out


def compare(new: dict[str, np.ndarray], old_path: Path) -> int:
    old = dict(np.load(old_path))
    bad = 0
    for key in sorted(set(old) | set(new)):
        if key not in new or key not in old:
            print(f"MISSING  {key}")
            bad += 1
            continue
        a, b = old[key], new[key]
        if a.shape != b.shape:
            print(f"SHAPE    {key}: {a.shape} vs {b.shape}")
            bad += 1
        elif a.dtype.kind in "fc":
            same = np.array_equal(a, b, equal_nan=True)
            if not same:
                d = np.nanmax(np.abs(a - b)) if a.size else 0.0
                print(f"DIFFER   {key}: max |diff| = {d:.3g}")
                bad += 1
        elif not np.array_equal(a, b):
            print(f"DIFFER   {key}: {np.count_nonzero(a != b)} entries")
            bad += 1
    print(f"{len(set(old) | set(new))} arrays, {bad} not bit-identical")
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", required=True, type=Path)
    ap.add_argument("--compare", type=Path, help="an earlier snapshot to compare with")
    ap.add_argument("--only", help="only configs whose file name contains this")
    args = ap.parse_args()
    snap = snapshot(args.only)
    np.savez_compressed(args.out, **snap)
    return compare(snap, args.compare) if args.compare else 0


if __name__ == "__main__":
    raise SystemExit(main())
