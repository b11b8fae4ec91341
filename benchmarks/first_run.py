"""The first run on a fresh install: cold compiles, each in a fresh process on an empty cache.

Two jobs, each in a fresh interpreter with ``NUMBA_CACHE_DIR`` set to an empty
temporary folder (what a new install, a CI run or a new Dask worker pays), then
once more on the cache it filled:

- ``first_simulate``: import + the README's first ``ssf.simulate`` (asymmetric
  eta = 9.99, t_end 3000, t_transient 2000).
- ``driver_floor``: the part of a first ``simulate`` that no change above the
  driver can remove: ``trajectory._run`` (the classified run around ``drive``, the
  step loop) compiled on its own, called from Python with records that a small
  compiled setup built first (timed apart, in the same process). A first
  ``simulate`` cannot compile in less than this without a smaller driver.
- ``readme_orbits``: the orbit lines of the README's Python quick start, a
  converged ``simulate`` at eta = 2, ``find_orbit`` and ``continue_orbit`` in eta
  to 3.3, each timed apart in the child (most of it is the variational kernel's
  compile, which the two orbit calls share since 2026-11-28).
- ``dask_warm_up``: what a fresh Dask worker pays before its first task,
  ``backends.dask.warm_up`` (a restart chunk of one value and a continuation
  chunk), with the number of ``run_lane`` specialisations it compiled (two until
  2026-11-29: the one-value chunk's start was a read-only view).
- ``readme_main_job``: the README's first command,
  ``stickslip-fast sweep data/fig06_asymmetric_constant.toml -o out.h5`` (the Fig. 6
  diagram, 1000 values, all cores), as ``python -m stickslip_fast.cli``.

Each cold run is repeated (``--repeats``, default 3) and reported as the median,
with the process's CPU time (user + system) beside the wall time: on a shared
machine the wall time of a compile varies by +-30 %, its CPU time much less.
``--root`` benchmarks another checkout (for a before/after comparison, run both
in one invocation with ``--root A --root B``: they alternate, repeat by repeat).

Usage: ``python -m benchmarks.first_run [--repeats 3] [--root DIR ...] [--out FILE]``.
Timing only: no assertion here (tests/test_first_compile.py checks what is compiled).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from .common import ROOT

_SIMULATE = textwrap.dedent(
    """
    import stickslip_fast as ssf
    res = ssf.simulate(ssf.System.preset("asymmetric", eta=9.99), 3000, 2000)
    assert (res.status, res.period) == ("ok", 2), (res.status, res.period)
    """
)


_DRIVER_FLOOR = textwrap.dedent(
    """
    import json, time
    import numpy as np
    from numba import njit
    import stickslip_fast as ssf
    from stickslip_fast.base import jit
    from stickslip_fast.core import trajectory as tr

    # Python calls setup: the options with Numba's wrappers (ENTRY; JIT before it existed);
    # code from -c has no file to cache against
    @njit(**dict(getattr(jit, "ENTRY", jit.JIT), cache=False))
    def setup(method, n, n_osc, dc, variant, rs, pts, tpts, samples):
        obs = tr._make_observer(rs, pts, tpts, samples, 1.0, n)
        rec = tr.method_record(method, variant)
        stop = tr._stop_rule(rs, n_osc, dc, n)
        return rec, obs, stop, tr.alloc_bordered_linear(n_osc, n), tr.alloc_workspace(rec, n)

    system = ssf.System.preset("asymmetric", eta=9.99)
    n_osc, dc = system.n_oscillators, system.is_dc_motor
    n = 4 * n_osc + int(dc)
    rs = ssf.core.settings.Settings.resolve(t_end=3000.0, t_transient=2000.0).run_settings()
    variant = tr.method_variant(0, n_osc, dc)
    t0 = time.perf_counter()
    rec, obs, stop, lin, ws = setup(0, n, n_osc, dc, variant, rs, np.empty((64, n)),
                                    np.empty(64), np.empty((0, n)))
    t1 = time.perf_counter()
    istat = np.zeros(2 + tr.N_AUTO_STATS, dtype=np.int64)
    status = tr._run(rec, system.initial_state(None), system.to_array(), n_osc, dc, variant, rs,
                     np.empty(tr.N_PARAMS), lin, ws, obs, stop, np.empty(n), istat, np.zeros(2),
                     tr.NO_ABORT)
    t2 = time.perf_counter()
    assert status == 0 and obs.counts[0] > 0, (status, obs.counts)
    print(json.dumps(dict(setup_s=round(t1 - t0, 2), driver_s=round(t2 - t1, 2))))
    """
)


_ORBITS = textwrap.dedent(
    """
    import json, time
    import stickslip_fast as ssf
    low = ssf.System.preset("asymmetric", eta=2.0)
    t0 = time.perf_counter()
    res = ssf.simulate(low, 3000, stop="converged")
    t1 = time.perf_counter()
    orbit = ssf.find_orbit(low, res)
    t2 = time.perf_counter()
    branch = ssf.continue_orbit(orbit, "eta", (2.0, 3.3))
    t3 = time.perf_counter()
    assert orbit.converged and len(branch.values) > 10, (orbit.status, len(branch.values))
    print(json.dumps(dict(simulate_s=round(t1 - t0, 2), find_orbit_s=round(t2 - t1, 2),
                          continue_orbit_s=round(t3 - t2, 2))))
    """
)


_DASK_WARM_UP = textwrap.dedent(
    """
    import json
    from stickslip_fast.backends.dask import warm_up
    rec = warm_up()
    print(json.dumps(dict(warm_up_s=round(rec["seconds"], 2), **rec["overloads"])))
    """
)


def _child(root: Path, cache: str, job: str, workdir: str) -> dict:
    """One fresh process: its wall time and CPU time (user + system of the child)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=str(root))
    if job == "first_simulate":
        cmd = [sys.executable, "-c", _SIMULATE]
    elif job == "driver_floor":
        cmd = [sys.executable, "-c", _DRIVER_FLOOR]
    elif job == "readme_orbits":
        cmd = [sys.executable, "-c", _ORBITS]
    elif job == "dask_warm_up":
        cmd = [sys.executable, "-c", _DASK_WARM_UP]
    else:
        config = str(root / "data" / "fig06_asymmetric_constant.toml")
        out = os.path.join(workdir, "fig06.h5")
        if os.path.exists(out):
            os.remove(out)  # the command would resume a finished file
        cmd = [sys.executable, "-m", "stickslip_fast.cli", "sweep", config, "-o", out]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=workdir, capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{job} failed in {root}:\n{proc.stderr[-3000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rec = dict(wall_s=round(wall, 2), cpu_s=round(cpu, 2))
    if job in ("driver_floor", "readme_orbits", "dask_warm_up"):  # the child's own report
        rec.update(json.loads(proc.stdout.strip().splitlines()[-1]))
    return rec


def _summary(runs: list[dict]) -> dict:
    return dict(
        runs=runs,
        median_wall_s=statistics.median(r["wall_s"] for r in runs),
        median_cpu_s=statistics.median(r["cpu_s"] for r in runs),
    )


JOBS = ("first_simulate", "driver_floor", "readme_orbits", "readme_main_job", "dask_warm_up")


def run(roots=(ROOT,), repeats: int = 3, log=print, jobs=JOBS) -> dict:
    """Cold (empty cache) and cached runs of ``jobs`` for each checkout in ``roots``."""
    roots = [Path(r).resolve() for r in roots]
    cold = {(str(r), j): [] for r in roots for j in jobs}
    cached = {}
    with tempfile.TemporaryDirectory(prefix="ssf_first_run_") as work:
        for k in range(repeats):
            for root in roots:
                for job in jobs:
                    cache = tempfile.mkdtemp(prefix="cache_", dir=work)
                    rec = _child(root, cache, job, work)
                    cold[(str(root), job)].append(rec)
                    log(f"  {root.name} {job} cold #{k + 1}: {rec['wall_s']:.1f} s wall, "
                        f"{rec['cpu_s']:.1f} s CPU")  # fmt: skip
                    if k == 0:  # the same job again on the cache it filled
                        cached[(str(root), job)] = again = _child(root, cache, job, work)
                        log(f"  {root.name} {job} cached: {again['wall_s']:.1f} s wall")
    out = {}
    for root in roots:
        out[str(root)] = {
            job: dict(cold=_summary(cold[(str(root), job)]), cached=cached[(str(root), job)])
            for job in jobs
        }
    return dict(
        repeats=repeats,
        jobs=list(jobs),
        load_average=os.getloadavg(),
        targets=dict(first_simulate_cold_s=10.0, readme_main_job_cold_s=25.0),
        results=out,
    )


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--root", action="append", help="checkout to benchmark (repeatable)")
    ap.add_argument("--jobs", nargs="*", choices=JOBS, default=list(JOBS))
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "first_run.json"))
    args = ap.parse_args(argv)
    res = run(args.root or [ROOT], args.repeats, jobs=args.jobs)
    Path(args.out).write_text(json.dumps(res, indent=1))
    print(json.dumps({r: {j: v["cold"]["median_wall_s"] for j, v in d.items()}
                      for r, d in res["results"].items()}, indent=1))  # fmt: skip


if __name__ == "__main__":
    main()
