"""A first run compiles only what it needs (issue 30): counted, not timed.

A fresh process with an empty ``NUMBA_CACHE_DIR`` runs one ``simulate`` and
records every compilation (Numba's ``numba:compile`` events, overload
implementations included). Before the method family became a compile-time
choice, a first Rodas5P ``simulate`` compiled the Dormand-Prince driver as well
(two ``drive`` specialisations, about 40 % of the cold start); a first
Dormand-Prince run compiled all of the Rosenbrock machinery. The explicit family is
the cheaper compile, so that is the run checked here; timings live in
benchmarks/first_run.py.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import stickslip_fast

ROOT = Path(stickslip_fast.__file__).resolve().parents[1]

SNIPPET = """
import json
import numpy as np
from numba.core import event

compiled = []


class Listener(event.Listener):
    def on_start(self, ev):
        pass

    def on_end(self, ev):
        d = ev.data["dispatcher"]
        wrapped = not d.targetoptions.get("no_cpython_wrapper", False)
        compiled.append(
            [d.py_func.__module__, d.py_func.__qualname__, str(ev.data["args"]), wrapped]
        )


event.register("numba:compile", Listener())
import stickslip_fast as ssf
from stickslip_fast.core import driver, trajectory

res = ssf.simulate(ssf.System.preset("asymmetric", eta=9.99), 20.0, method="dopri5")
# a method index of the other family than the variant says: an error, and no compile
m = trajectory.M_RODAS5P
try:
    out = int(trajectory.integrate(
        m, np.zeros(4), ssf.System.preset("asymmetric").to_array(), 1, False, None,
        trajectory.run_settings(1.0, 0.0, 1e-6, 1e-8), np.empty((4, 4)), np.empty(4),
        np.empty((0, 4)), 1.0, np.empty(4), np.zeros(4, dtype=np.int64), np.zeros(4),
        np.zeros(1, dtype=np.int64),
    ))
except Exception as exc:  # reported, and asserted on after the counts
    out = repr(exc)[:300]
print(json.dumps(dict(
    status=res.status, n_steps=res.n_steps, mismatch=out, compiled=compiled,
    integrate=len(trajectory.integrate.signatures), drive=len(driver.drive.signatures),
)))
"""


def _first_run(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(ROOT))
    out = subprocess.run(
        [sys.executable, "-c", SNIPPET], env=env, capture_output=True, text=True,
        timeout=900, check=True, cwd=tmp_path,
    ).stdout  # fmt: skip
    return json.loads(out.strip().splitlines()[-1])


def test_first_simulate_compiles_one_method_family(tmp_path):
    from stickslip_fast.base.status import ST_ERROR

    rec = _first_run(tmp_path)
    # 20 time units: less than one oscillation, so no crossing of the section yet
    assert rec["status"] == "no-crossings" and rec["n_steps"] > 0
    compiled = [c[:3] for c in rec["compiled"]]
    assert compiled, "nothing compiled: the cache folder was not empty"
    # Numba's CPython wrapper only for what Python calls, here integrate (no crossing,
    # so no period to detect): every other function of the package is compiled without
    # one, since a wrapper is optimised again in every caller that links it (base.jit)
    wrapped = {name for mod, name, _, w in rec["compiled"] if w and mod.startswith("stickslip_")}
    assert wrapped == {"integrate"}, wrapped
    # one specialisation of the trajectory kernel, of the driver and of the method's
    # step (compiled once as a function of its own: jit.overload_call)
    assert rec["integrate"] == 1
    assert rec["drive"] == 1
    drives = [args for mod, name, args in compiled if name == "drive"]
    assert len(drives) == 1 and drives[0].startswith("(ExplicitRKMethod(")
    steps = [(mod, args) for mod, name, args in compiled if name == "stepper_step"]
    assert len(steps) == 1 and steps[0][0] == "stickslip_fast.core.steppers"
    assert steps[0][1].startswith("(ExplicitRKMethod(")
    # none of the Rosenbrock machinery (stages, Jacobian, factorisation) was compiled
    rosenbrock = [(name, args[:80]) for _, name, args in compiled if "RosenbrockMethod" in args]
    assert rosenbrock == []
    # nor the switching method of method="auto" (a family of its own, compiled on demand)
    assert not any("AutoMethod" in args or "AutoWorkspace" in args for _, _, args in compiled)
    assert not any(mod.endswith("autoswitch") for mod, _, _ in compiled)
    assert not any(name.startswith(("_small_", "jacobian_blocks")) for _, name, _ in compiled)
    # the method index must belong to the variant's family, else an error, never a run
    assert rec["mismatch"] == ST_ERROR


def test_the_compile_command_fills_the_cache_that_a_first_simulate_loads(tmp_path):
    # `stickslip-fast compile` in a fresh cache, then the first run above in a new process
    # on that cache: it compiles nothing (Numba's compile events fire only on a cache miss)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(ROOT))
    cmd = [sys.executable, "-m", "stickslip_fast.cli", "compile", "--kernels", "simulate",
           "--methods", "dopri5", "--drives", "constant", "--jobs", "1"]  # fmt: skip
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900, check=True,
                         cwd=tmp_path).stdout  # fmt: skip
    assert "simulate  dopri5" in out and f"cache: {tmp_path / 'cache'}" in out, out
    rec = _first_run(tmp_path)
    assert rec["compiled"] == [], rec["compiled"][:5]
    assert rec["integrate"] == 1 and rec["drive"] == 0  # integrate loaded; drive linked in it


def test_compile_jobs_and_bad_arguments():
    from stickslip_fast.cli.precompile import compile_jobs, precompile

    jobs = compile_jobs(("simulate", "orbits"), ("rodas5p", "auto"), (1, 2), ("dc-motor",))
    assert jobs == [
        ("simulate", "rodas5p", 1, "dc-motor"), ("simulate", "auto", 1, "dc-motor"),
        ("simulate", "rodas5p", 2, "dc-motor"), ("simulate", "auto", 2, "dc-motor"),
        ("orbits", "rodas5p", 1, "dc-motor"), ("orbits", "rodas5p", 2, "dc-motor"),
    ]  # fmt: skip
    for kw, name in ((dict(kernels=("sim",)), "kernel"), (dict(methods=("rk4",)), "method"),
                     (dict(drives=("belt",)), "drive"), (dict(oscillators=(0,)), "oscillators"),
                     (dict(jobs=0), "jobs")):  # fmt: skip
        with pytest.raises(ValueError, match=name):
            precompile(**kw)


def test_sweep_chunks_of_any_size_and_input_share_one_compiled_entry(monkeypatch):
    # Numba types an array by layout and read-only flag. A chunk of one value broadcast
    # its start to a read-only view, so run_lane compiled twice (~5 s each, cold): a
    # one-value sweep or tail chunk, the Dask warm-up. Every chunk, read-only input
    # too, must reach the entry with the same argument types.
    import numba
    import numpy as np

    from stickslip_fast.backends.local import compute_continuation_chunk, compute_restart_chunk
    from stickslip_fast.core import sweep_kernels
    from stickslip_fast.core.settings import Settings
    from stickslip_fast.core.trajectory import SWEEP_INT_FIELDS

    seen = []

    def record(*args):  # the entry's types, then the lane's values marked as run
        seen.append(tuple(str(numba.typeof(a)) for a in args))
        args[14][:, SWEEP_INT_FIELDS.index("status")] = 0

    monkeypatch.setattr(sweep_kernels, "run_lane", record)
    system = stickslip_fast.System.preset("asymmetric")
    settings = Settings.resolve("rodas5p", 1.0, 0.0, max_points=2)
    y0 = system.initial_state(None)
    frozen = np.array([[2.0], [3.0], [4.0]])
    frozen.flags.writeable = False
    for values in (np.array([[2.0]]), np.array([[2.0], [3.0]]), frozen):
        compute_restart_chunk(system, ("eta",), values, y0, settings)
    starts = np.broadcast_to(y0, (3, y0.size))  # read-only, one start per value
    compute_restart_chunk(system, ("eta",), frozen, starts, settings)
    compute_continuation_chunk(system, ("eta",), frozen[None], y0[None, :], y0, settings)
    assert len(seen) >= 5
    assert len(set(seen)) == 1, sorted(set(seen))
