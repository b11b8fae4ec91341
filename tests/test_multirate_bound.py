"""benchmarks/multirate_bound.py: its one-disk problem (multirate_disk.py) and its relaxation
compute the model.

Run in a subprocess with a cache folder of its own: the driver's Numba cache index
records the benchmark's problem record, a type from outside the package.
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    import stickslip_fast as ssf
    from benchmarks import multirate_bound as mb
    from benchmarks import multirate_disk as md

    # 1. v_b constant: one disk of the benchmark is a constant-belt simulate
    one = ssf.System.preset("asymmetric", n_oscillators=1)
    p = one.to_array()
    y0 = np.array([1e-3, 0.0, -5e-4, 0.0])
    t_end, ds = 40.0, 0.01
    grid = np.arange(int(round(t_end / ds)) + 1) * ds
    coef = md.quintic(grid, np.full(grid.size, one.vb))
    z = np.zeros((1, md.N_STATE))
    z[0, :4] = y0
    steps = np.zeros((1, 2), dtype=np.int64)
    st = md.integrate_disks(p, z, 0.0, ds, coef, 0.0, t_end, t_end,
                            np.empty((1, 2, md.N_STATE)), 1e-10, 1e-13, steps)
    ref = ssf.simulate(one, t_end, y0=y0, rtol=1e-10, atol=1e-13, max_points=10)
    out = dict(status=int(st), t=float(z[0, 4]),
               constant_belt_error=float(np.max(np.abs(z[0, :4] - ref.final_state))))

    # 2. the whole benchmark, small: two disks, a window of 0.5, two windows
    mb.main(["--n", "2", "--t-end", "1", "--settle", "5", "--ds", "0.002", "--window", "0.5",
             "--rounds", "1", "--out", sys.argv[1]])
    print(json.dumps(out))
    """
)


def test_benchmark_disks_and_relaxation_agree_with_the_model(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(ROOT))
    out_json = tmp_path / "mr.json"
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(out_json)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    check = json.loads(proc.stdout.strip().splitlines()[-1])
    assert check["status"] == 0 and abs(check["t"] - 40.0) < 1e-9  # t is integrated too
    # the same tableau, controller and arithmetic of f: the states agree to ~1e-12
    assert check["constant_belt_error"] < 1e-9

    row = json.loads(out_json.read_text())["rows"][0]
    assert row["N"] == 2
    mono, orc, wr = row["monolithic"], row["oracle"], row["relaxation"]
    assert mono["error"] < 5e-8  # the monolithic run at rtol 1e-8 against rtol 1e-11
    assert orc["status"] == 0 and orc["error"] < 1e-7  # v_b interpolated on the grid
    # the relaxation converges to the coupled solution: v_b from the motor quadratures
    assert wr["windows_not_converged"] == 0 and wr["passes_max"] <= 12
    assert wr["vb_error"] < 1e-9 and wr["error"] < 1e-7
    assert len(wr["change_over_tol"]) == 2 and wr["change_over_tol"][0][-1] <= 1.0
