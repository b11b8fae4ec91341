"""Issue 30's speed targets and the floors under them, measured inside the full suite run.

Issue 30 asks that each of its targets be met, or that a benchmark show, with numbers
from one run, why it cannot be. Three standalone studies hold that evidence; these
sections of ``benchmarks/run.py`` run them in the full run, so that every target and its
floor come from one run on one machine (``summary_targets.py`` tabulates them):

``first_run``
    :mod:`benchmarks.first_run`'s ``first_simulate``, ``driver_floor`` and
    ``readme_main_job``, each cold (a fresh process on an empty Numba cache) twice,
    then once cached. The targets: a first ``simulate`` <= 10 s, the README's main job
    <= 25 s. The floor: the classified driver run ``trajectory._run`` compiled alone.
``auto_tolerance_rules``
    :mod:`benchmarks.atol_rules` at eta = 2.0 and 9.99: ``method="auto"`` against
    numbalsoda's LSODA at matched accuracy (points within 1e-6 and 1e-8 of the Radau
    reference), with the fair benchmark's one tolerance rule and with each solver at its
    best rule, and ``auto``'s floor at both picks (its attempts at the bare cost of an
    attempt: a free driver). The targets: >= 3x at 1e-6, >= 2x at 1e-8.
``multirate_bound``
    :mod:`benchmarks.multirate_bound` with its defaults (N = 8 ... 512 desynchronised
    disks on one DC motor): what a partitioned integrator could gain, against the
    ``n_scaling`` section's cost per disk (target <= 1.5x from N = 8 to 512). It runs
    in a child process, which compiles into a Numba cache of its own.

Each compiles cold or times one core for minutes, so ``--quick`` records them as
skipped.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from . import atol_rules, first_run, peers
from .common import ROOT

SKIPPED = dict(status="skipped", why="full run only: cold compiles and minutes of timing")
FIRST_RUN_JOBS = ("first_simulate", "driver_floor", "readme_main_job")
AUTO_ETAS = (2.0, 9.99)


def first_run_section(mode: str, log) -> dict:
    """Cold and cached first runs (two cold runs of each job, alternating)."""
    if mode == "quick":
        return dict(SKIPPED)
    res = first_run.run(repeats=2, log=log, jobs=FIRST_RUN_JOBS)
    (root_result,) = res["results"].values()  # one checkout: this one
    return dict(status="ok", **{k: v for k, v in res.items() if k != "results"},
                jobs_result=root_result)  # fmt: skip


def auto_section(mode: str, log, rounds: int = 7) -> dict:
    """``auto`` and LSODA at matched accuracy under each tolerance rule, with the floor."""
    if mode == "quick":
        return dict(SKIPPED)
    peers.warm_up()
    cases = {f"{eta:g}": atol_rules.case(eta, rounds, log) for eta in AUTO_ETAS}
    return dict(
        status="ok", ladder=list(atol_rules.LADDER), rules=list(atol_rules.RULES),
        targets=list(atol_rules.TARGETS), rounds=rounds,
        peer_available=peers.numbalsoda_available()[0], cases=cases,
    )  # fmt: skip


def multirate_section(mode: str, log, args: tuple[str, ...] = ()) -> dict:
    """:mod:`benchmarks.multirate_bound` with its defaults (or ``args``), in a child process."""
    if mode == "quick":
        return dict(SKIPPED)
    with tempfile.TemporaryDirectory(prefix="ssf_multirate_") as work:
        out = Path(work) / "multirate_bound.json"
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]))  # fmt: skip
        env.pop("NUMBA_CACHE_DIR", None)  # the child picks its own cache folder
        proc = subprocess.run(
            [sys.executable, "-m", "benchmarks.multirate_bound", "--out", str(out), *args],
            cwd=ROOT, env=env, capture_output=True, text=True, timeout=3600,
        )  # fmt: skip
        for line in proc.stdout.splitlines():
            log("  " + line)
        if proc.returncode != 0:
            raise RuntimeError(f"multirate_bound failed:\n{proc.stderr[-3000:]}")
        result = json.loads(out.read_text())
    result.pop("machine", None)  # the run's own machine record is the suite's
    return dict(status="ok", **result)
