"""Start-up cost: a fresh process with an empty Numba cache, then one with that cache.

In quick mode (the smoke test) the empty-cache run is skipped: ``cold`` is None.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time

from .common import ROOT

_CHILD = textwrap.dedent(
    """
    import json, sys, time
    t0 = time.perf_counter()
    sys.path.insert(0, {root!r})
    import stickslip_fast as ssf
    t1 = time.perf_counter()
    res = ssf.simulate(ssf.System.preset("asymmetric", eta=9.99), 3000, 2000)
    t2 = time.perf_counter()
    out = dict(import_s=t1 - t0, first_simulate_s=t2 - t1, status=res.status, period=res.period)
    if {with_sweep}:
        sys.path.insert(0, {root!r})
        from benchmarks.common import run_sweep
        run_sweep(ssf.System.preset("asymmetric"), "eta", [2.0, 9.0], t_end=100.0, t_transient=50.0)
        out["first_sweep_s"] = time.perf_counter() - t2
    print(json.dumps(out))
    """
)


def _child(cache_dir, with_sweep):
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    code = _CHILD.format(root=str(ROOT), with_sweep=with_sweep)
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=900
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr[-3000:])
    rec = json.loads(proc.stdout.strip().splitlines()[-1])
    rec["process_wall_s"] = wall
    return rec


def run(mode, log, with_sweep=True):
    if mode == "quick":
        # the smoke test's mode: compiling everything into an empty cache took ~75 s of
        # the test suite; a fresh process on the package's own cache checks the same path
        log("start-up (quick): fresh process on the package's cache, no empty-cache run ...")
        _child(None, with_sweep)  # fills that cache if it is cold
        cold, warm = None, _child(None, with_sweep)
        log(f"  cached: {warm['process_wall_s']:.1f} s")
    else:
        with tempfile.TemporaryDirectory(prefix="ssf_numba_cache_") as cache:
            log("start-up: fresh process, empty cache (compiles) ...")
            cold = _child(cache, with_sweep)
            log(f"  cold: {cold['process_wall_s']:.1f} s")
            warm = _child(cache, with_sweep)
            log(f"  cached: {warm['process_wall_s']:.1f} s")
    # the headline: interpreter start + import + first simulate() (sweep kernel excluded)
    cached_first_call = warm["process_wall_s"] - warm.get("first_sweep_s", 0.0)
    return dict(
        call="simulate(asymmetric eta=9.99, t_end=3000, t_transient=2000)"
        + (" then a 2-value sweep" if with_sweep else ""),
        cold=cold,
        cached=warm,
        cached_start_s=cached_first_call,
        target_s=3.0,
    )
