"""The CUDA backend, run in numba's CUDA simulator (CI has no GPU).

The reference is the CPU backend (``backend="local"``, itself checked against
SciPy elsewhere): status and period must be identical, Poincare points within
1e-9. On a GPU the points are not bit-identical (fused multiply-adds); in the
simulator, which runs the kernel as Python, they happen to be. Cost: ~100 s on the
shared 2-core AMD EPYC VM with the kernels cached (the simulator runs ~2 000 Rodas5P
steps per second), so each test keeps its runs few and short.

On a machine with a GPU, ``STICKSLIP_TEST_REAL_GPU=1 pytest tests/test_cuda_backend.py``
runs the same comparisons on the device instead of the simulator.
"""

import os
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

# numba.cuda chooses the simulator or the driver when it is first imported, from
# numba's config (numba.core.config, read from the environment when numba was
# imported, and re-read by reload_config()).
REAL_GPU = os.environ.get("STICKSLIP_TEST_REAL_GPU") == "1"
if "numba.cuda" not in sys.modules and not REAL_GPU:
    import numba.core.config as _numba_config

    _old = os.environ.get("NUMBA_ENABLE_CUDASIM")
    os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
    _numba_config.reload_config()
    try:
        pytest.importorskip("numba_cuda", reason="numba-cuda (the [cuda] extra) is not installed")
        from numba import cuda  # noqa: F401  (binds the simulator for this process)
    finally:
        if _old is None:
            del os.environ["NUMBA_ENABLE_CUDASIM"]
        else:
            os.environ["NUMBA_ENABLE_CUDASIM"] = _old
        _numba_config.reload_config()
else:
    pytest.importorskip("numba_cuda", reason="numba-cuda (the [cuda] extra) is not installed")

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.analysis.sweep import sweep  # noqa: E402
from stickslip_fast.backends import cuda as cuda_backend  # noqa: E402
from stickslip_fast.base.status import STATUS_NAMES  # noqa: E402
from stickslip_fast.io import ConfigMismatchError  # noqa: E402

if REAL_GPU:  # pragma: no cover - only on a machine with a GPU
    cuda_backend.check_available()
elif not cuda_backend.simulator_enabled():  # pragma: no cover - numba.cuda imported earlier
    pytest.skip("numba.cuda was imported without the simulator", allow_module_level=True)

POINT_TOL = 1e-9
# Crossing times: the root of dx1 on the dense output is flat in the state (dx1 = 0
# there) but not in t; FMA roundings move it by ~1e-9 relative (seen on an H200).
TIME_RTOL = 1e-8
FINAL_TOL = 1e-6
# t_converged is the end of the step at which the rule fired: step boundaries
# follow the roundings, so it moves by up to a step (0.24% seen on an H200)
TCONV_RTOL = 1e-2
ASYM = ssf.System.preset("asymmetric")


def _agree(gpu, cpu, ended_at_t_end=True):
    """Status and period identical; points within POINT_TOL, NaN in the same places.

    ``ended_at_t_end=False``: the runs went past t_end by design (stoprules.past_end), so
    their end time follows the step sequence and only NaN-ness of final_state is compared.
    """
    np.testing.assert_array_equal(gpu.status, cpu.status)
    np.testing.assert_array_equal(gpu.period, cpu.period)
    np.testing.assert_array_equal(gpu.count, cpu.count)
    np.testing.assert_array_equal(gpu.n_crossings, cpu.n_crossings)
    for f in ("points", "t_points", "t_converged"):
        a, b = getattr(gpu, f, None), getattr(cpu, f, None)
        if a is None and b is None:
            continue
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b), err_msg=f)
        if f.startswith("t_"):
            rtol = TCONV_RTOL if f == "t_converged" else TIME_RTOL
            np.testing.assert_allclose(a, b, rtol=rtol, atol=0, err_msg=f)
        else:
            np.testing.assert_allclose(a, b, rtol=0, atol=POINT_TOL, err_msg=f)
    # final_state is where the run ended, not a section point. At t_end it carries
    # the roundoff grown along the transient (2.4e-9 seen on an H200); where a stop
    # rule or max_steps ended the run, the end time itself follows the step sequence
    # (7.5e-5 seen after 1000 steps), so only NaN-ness is compared there.
    a, b = gpu.final_state, cpu.final_state
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b), err_msg="final_state")
    at_end = np.isin(cpu.status, ["ok", "equilibrium", "stalled", "no-crossings"])
    at_end &= ended_at_t_end
    t_conv = getattr(cpu, "t_converged", None)
    if t_conv is not None:
        at_end &= np.isnan(t_conv)
    np.testing.assert_allclose(a[at_end], b[at_end], rtol=0, atol=FINAL_TOL, err_msg="final_state")


def test_constant_belt_matches_cpu():
    # max_points=4 < the crossings of the window: the device unrolls its ring buffer
    kw = dict(t_end=120.0, t_transient=50.0, max_points=4, progress=False)
    eta = np.array([1.5, 2.0, 5.0, 9.99])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # values with no orbit
        gpu = sweep(ASYM, "eta", eta, backend="cuda", **kw)
        cpu = sweep(ASYM, "eta", eta, backend="local", **kw)
    _agree(gpu, cpu)
    # the comparison covers values with a period and a value without one yet
    assert np.any(cpu.period > 0) and np.any(cpu.period == 0)
    assert np.any(cpu.n_crossings > 4)


def test_a_decaying_oscillation_is_refused_as_on_the_cpu():
    # minima that repeat within the tolerance while they head for rest: period 0 on both
    # (poincare.orbit_period; tests/test_decaying_oscillation.py has the references)
    from test_decaying_oscillation import DECAYING, NEAR_REST

    kw = dict(t_end=300.0, t_transient=0.0, y0=NEAR_REST, max_points=32, progress=False)
    eta = np.array([DECAYING.eta])
    gpu = sweep(DECAYING, "eta", eta, backend="cuda", **kw)
    cpu = sweep(DECAYING, "eta", eta, backend="local", **kw)
    _agree(gpu, cpu)
    assert (cpu.status[0], cpu.period[0], cpu.count[0]) == ("ok", 0, 32)


def test_dc_motor_two_disks_matches_cpu():
    # N = 2 with the DC motor: the bordered (Schur complement) solve; eta > v_b0 / beta stalls
    two = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2)
    y0 = [0, 0, 0, 0, 0.01, 0.01, 0.01, 0.01, 0]
    kw = dict(t_end=60.0, t_transient=20.0, y0=y0, max_points=8, progress=False)
    eta = np.array([3.0, 9.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        gpu = sweep(two, "eta", eta, backend="cuda", **kw)
        cpu = sweep(two, "eta", eta, backend="local", **kw)
    _agree(gpu, cpu)
    assert gpu.points.shape[-1] == 9


def test_converged_stopping_matches_cpu():
    # an orbit that converges (period 1), one that comes to rest (dwell window),
    # and one that has not converged by t_end (t_converged NaN)
    kw = dict(t_end=320.0, max_points=16, stop="converged", progress=False)
    eta = np.array([2.0, 4.0, 9.99])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        gpu = sweep(ASYM, "eta", eta, backend="cuda", **kw)
        cpu = sweep(ASYM, "eta", eta, backend="local", **kw)
    _agree(gpu, cpu)
    assert list(cpu.status) == ["ok", "equilibrium", "ok"]
    assert cpu.period[0] == 1 and np.isfinite(cpu.t_converged[:2]).all()
    assert np.isnan(cpu.t_converged[2])
    # it stopped early: far fewer steps than the same value run to t_end
    assert gpu.n_steps[0] < 0.7 * sweep(ASYM, "eta", eta[:1], backend="local", t_end=320.0,
                                        max_points=16, progress=False).n_steps[0]  # fmt: skip


def test_converged_stopping_near_the_hopf_point_matches_cpu():
    # the small orbit whose x1 minima look at rest, and the slowly decaying oscillation
    # whose minima repeat long before it rests (tests/test_classification.py): the
    # kernel's copy of the stop rule gives the CPU's labels, ending where disk 1 moves
    from stickslip_fast.backends.local import compute_restart_chunk
    from stickslip_fast.core.settings import Settings

    settings = Settings.resolve("rodas5p", 3000.0, 0.0, max_points=16).replace(stop="converged")
    vals = np.array([[1.0360360360360461, 0.018918918918918948], [8.65765766, -0.10540541]])
    y0 = np.tile(ASYM.initial_state(None), (2, 1))
    gpu = cuda_backend.compute_restart_chunk_cuda(ASYM, ("eta", "k12"), vals, y0, settings)
    cpu = compute_restart_chunk(ASYM, ("eta", "k12"), vals, y0, settings)
    for key in ("status", "period", "count"):
        np.testing.assert_array_equal(gpu[key], cpu[key], err_msg=key)
    assert [STATUS_NAMES[c] for c in cpu["status"]] == ["ok", "equilibrium"]
    assert cpu["period"][0] == 1 and cpu["t_converged"][0] < 100.0
    # the time the decaying run comes to rest is a threshold crossing of its speeds: a
    # GPU's fused multiply-adds moved it by 6.4e-6 relative on an H200 (0 in the simulator)
    np.testing.assert_allclose(gpu["t_converged"], cpu["t_converged"], rtol=1e-4)


def test_a_window_that_ends_undecided_looks_past_its_end_as_on_the_cpu():
    # tests/test_classification.py: a fixed window that ends in a dip of a small orbit's
    # speeds (at t = 141.215-141.225; the code before said "unsettled"), one that ends
    # 50 time units after the run came to rest, and one that ends 5.67 after a crossing
    # with a dwell of 4 (before: "no-crossings"). The kernel's copy of stoprules.past_end
    # goes on until disk 1 moves or crosses (the orbit) or the rest has lasted dwell
    # (the equilibrium), as the CPU does.
    small = ASYM.replace(eta=1.0360360360360461, k12=0.018918918918918948)
    for system, kw, expected in (
        (small, dict(t_end=141.22, t_transient=50.0), ("ok", 1)),
        (ASYM.replace(eta=3.2), dict(t_end=157.48864927201203), ("equilibrium", 0)),
        (ASYM.replace(eta=2.0), dict(t_end=119.0, t_transient=50.0, dwell=4.0), ("ok", 1)),
    ):
        kw.update(max_points=16, progress=False)
        gpu = sweep(system, "eta", [system.eta], backend="cuda", **kw)
        cpu = sweep(system, "eta", [system.eta], backend="local", **kw)
        # Each run ends past t_end, where the step sequence puts it: on an H200 the first
        # one's final state differed by 6e-5 (FMA roundings), its points by <= 1e-9.
        _agree(gpu, cpu, ended_at_t_end=False)
        assert (cpu.status[0], cpu.period[0]) == expected


def test_census_on_the_gpu_matches_cpu(tmp_path):
    # one start per (value, start): continuation units of one-value chains on the device;
    # the period-1 orbit at eta = 2 and steady sliding at eta = 4
    kw = dict(n_starts=2, seed=1, t_end=200.0, max_points=16, stop="converged",
              progress=False, box=[(-0.2, 0.2), (-0.02, 0.02), (-0.2, 0.2), (-0.02, 0.02)])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        gpu = ssf.census(ASYM, "eta", [2.0, 4.0], backend="cuda", out=tmp_path / "c.h5", **kw)
        cpu = ssf.census(ASYM, "eta", [2.0, 4.0], backend="local", **kw)
    np.testing.assert_array_equal(gpu.labels, cpu.labels)
    np.testing.assert_array_equal(gpu.status, cpu.status)
    np.testing.assert_array_equal(gpu.period, cpu.period)
    for ga, ca in zip(gpu.attractors, cpu.attractors):
        assert [(a.kind, a.period, a.fraction) for a in ga] == [
            (a.kind, a.period, a.fraction) for a in ca
        ]
    assert [[(a.kind, a.period) for a in x] for x in cpu.attractors] == [
        [("orbit", 1)],
        [("equilibrium", 0)],
    ]
    # the file records the backend: resuming it on the CPU is refused
    with pytest.raises(ConfigMismatchError, match="backend"):
        ssf.census(ASYM, "eta", [2.0, 4.0], backend="local", out=tmp_path / "c.h5", **kw)


def test_failed_runs_match_cpu():
    # max_steps cuts the long value short: "max-steps", no points; the short one finishes
    kw = dict(t_end=40.0, t_transient=10.0, max_points=4, max_steps=1000, progress=False)
    eta = np.array([2.0, 5.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        gpu = sweep(ASYM, "eta", eta, backend="cuda", **kw)
        cpu = sweep(ASYM, "eta", eta, backend="local", **kw)
    _agree(gpu, cpu)
    assert list(cpu.status) == ["max-steps", "ok"]


def test_threads_take_runs_from_the_queue(monkeypatch):
    # Fewer threads than runs: each thread takes run after run from the launch's queue,
    # across runs that end differently (an orbit, rest, max-steps, a non-finite start:
    # "error"). Every output equals that of one thread per run, bit for bit, and the
    # CPU's status and period.
    from stickslip_fast.backends.local import compute_restart_chunk
    from stickslip_fast.core.settings import Settings

    settings = Settings(t_end=40.0, t_transient=10.0, max_points=4, max_steps=1000)
    eta = np.array([[2.0], [5.0], [9.99], [5.0], [4.0]])
    y0 = np.tile(ASYM.initial_state(None), (5, 1))
    y0[3, 1] = np.nan
    outs = []
    for threads in (2, 5):  # 2: a queue of 5 runs; 5: one run per thread
        monkeypatch.setattr(cuda_backend, "SIMULATOR_THREADS", threads)
        outs.append(cuda_backend.compute_restart_chunk_cuda(ASYM, ("eta",), eta, y0, settings))
    two, five = outs
    assert set(two) == set(five)
    for key in two:
        np.testing.assert_array_equal(two[key], five[key], err_msg=key)
    cpu = compute_restart_chunk(ASYM, ("eta",), eta, y0, settings)
    # The simulator runs the CPU's arithmetic; a GPU contracts multiply-adds, so a run's
    # step count may move by a step or two there (seen on an H200: 948 against 947).
    exact = ("status", "period", "count") + (
        () if REAL_GPU else ("n_steps", "n_rejected", "n_crossings")
    )
    for key in exact:
        np.testing.assert_array_equal(two[key], cpu[key], err_msg=key)
    if REAL_GPU:  # pragma: no cover - only on a machine with a GPU
        for key in ("n_steps", "n_rejected", "n_crossings"):
            np.testing.assert_allclose(two[key], cpu[key], rtol=0.01, atol=2, err_msg=key)
    np.testing.assert_allclose(two["points"], cpu["points"], rtol=0, atol=POINT_TOL)
    from stickslip_fast.base.status import STATUS_NAMES

    names = [STATUS_NAMES[c] for c in two["status"]]
    assert "error" in names and "max-steps" in names and "ok" in names


def test_2d_map_to_file_resumes_and_is_never_mixed_with_cpu(tmp_path):
    out = tmp_path / "map.h5"
    axes = (np.array([2.0, 6.0]), np.array([-0.3, 0.2]))
    kw = dict(t_end=40.0, t_transient=20.0, max_points=6, progress=False, chunk_size=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        gpu = sweep(ASYM, ("eta", "k12"), axes, backend="cuda", out=out, **kw)
        cpu = sweep(ASYM, ("eta", "k12"), axes, backend="local", **kw)
        _agree(gpu, cpu)
        assert gpu.shape == (2, 2)
        # resume: the finished file is recognised, nothing is recomputed
        again = sweep(ASYM, ("eta", "k12"), axes, backend="cuda", out=out, **kw)
        np.testing.assert_array_equal(again.points, gpu.points)
        # GPU and CPU points differ at ~1e-9, so a file is all-GPU or all-CPU
        with pytest.raises(ConfigMismatchError, match="backend"):
            sweep(ASYM, ("eta", "k12"), axes, backend="local", out=out, **kw)


def test_cli_backend_cuda(tmp_path, capsys):
    from stickslip_fast.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\n[integration]\nt_end = 30.0\nt_transient = 10.0\n'
        'max_points = 4\n[sweep]\nparam = "eta"\nvalues = [2.0, 5.0]\n'
    )
    out = tmp_path / "o.h5"
    assert main(["sweep", str(cfg), "-o", str(out), "--quiet", "--backend", "cuda"]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        cpu = sweep(ASYM, "eta", [2.0, 5.0], t_end=30.0, t_transient=10.0, max_points=4,
                    progress=False)  # fmt: skip
    _agree(ssf.load_sweep(out), cpu)
    # the same command with the CPU backend is a different configuration: refused
    assert main(["sweep", str(cfg), "-o", str(out), "--quiet"]) == 2
    assert "backend" in capsys.readouterr().err


def test_falls_back_to_cpu_with_a_warning():
    kw = dict(t_end=10.0, t_transient=5.0, max_points=4, progress=False)
    eta = np.array([2.0])
    cases = [
        (ASYM, dict(mode="continuation"), "continuation"),
        (ssf.System.preset("asymmetric", n_oscillators=5), {}, "N <= 4"),
        (ASYM, dict(method="dopri5"), "rodas5p"),
    ]
    for system, extra, why in cases:
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            gpu = sweep(system, "eta", eta, backend="cuda", **kw, **extra)
            cpu = sweep(system, "eta", eta, backend="local", **kw, **extra)
        msgs = [str(w.message) for w in rec]
        assert any(why in m and "runs on the CPU" in m for m in msgs), msgs
        np.testing.assert_array_equal(gpu.points, cpu.points)  # the CPU kernels themselves
        np.testing.assert_array_equal(gpu.status, cpu.status)


def test_nothing_else_imports_cuda():
    # the package, its sweep/census/CLI modules and the analyses never import
    # numba's CUDA target or the package's CUDA modules
    code = textwrap.dedent(
        """
        import sys
        import stickslip_fast, stickslip_fast.analysis.sweep, stickslip_fast.analysis.census
        import stickslip_fast.cli.commands, stickslip_fast.bifurcation.orbits
        import stickslip_fast.bifurcation.continuation, stickslip_fast.backends.dask
        cuda = ("numba.cuda", "numba_cuda", "stickslip_fast.backends.cuda")
        print(sorted(m for m in sys.modules if m.startswith(cuda)))
        """
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300
    )
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip() == "[]", res.stdout


def test_kernel_sizes_are_checked():
    with pytest.raises(ValueError, match="n_osc"):
        cuda_backend.get_kernel(5, False)


def test_without_a_gpu_the_error_says_so():
    # a fresh process without the simulator; on a machine with a GPU there is nothing to test
    code = textwrap.dedent(
        """
        import numpy as np, stickslip_fast as ssf
        from numba import cuda
        if cuda.is_available():
            print("HAS-GPU"); raise SystemExit
        try:
            ssf.sweep(ssf.System.preset("asymmetric"), "eta", np.array([2.0]), t_end=1.0,
                      backend="cuda", progress=False)
        except RuntimeError as exc:
            print("ERROR:", exc)
        """
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300
    )
    if "HAS-GPU" in res.stdout:
        pytest.skip("this machine has a GPU")
    assert "ERROR:" in res.stdout, res.stdout + res.stderr
    assert "needs an NVIDIA GPU" in res.stdout and "NUMBA_ENABLE_CUDASIM" in res.stdout


def test_kernels_compile_for_the_real_cuda_target():
    # The simulator runs the kernel as Python and cannot tell whether it compiles for
    # a GPU. compile_ptx compiles the N = 2 DC-motor kernel (the bordered solve) and
    # the model functions it calls to PTX, with NVVM but without a GPU. ~15 s.
    try:
        from cuda.pathfinder import load_nvidia_dynamic_lib

        for lib in ("nvvm", "nvrtc"):
            load_nvidia_dynamic_lib(lib)
    except Exception as exc:  # noqa: BLE001 - any failure means: not available here
        pytest.skip(f"no NVVM/NVRTC here (install the [cuda] extra): {type(exc).__name__}")
    code = textwrap.dedent(
        """
        from stickslip_fast.backends import cuda as cb
        try:
            ptx = cb.compile_ptx(2, True, (8, 0))
        except Exception as exc:  # no NVVM / NVRTC in this environment
            text = f"{type(exc).__name__}: {exc}"
            if any(s in text.lower() for s in ("nvvm", "nvrtc", "dynamiclibnotfound", "libdevice")):
                print("NO-NVVM", text[:300]); raise SystemExit
            raise
        print("ENTRY" if ".entry" in ptx else "NO-ENTRY", ".target sm_80" in ptx)
        """
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600
    )
    if "NO-NVVM" in res.stdout:
        pytest.skip("no NVVM here (install the [cuda] extra): " + res.stdout.strip())
    assert res.returncode == 0, res.stdout + res.stderr[-3000:]
    assert "ENTRY True" in res.stdout, res.stdout


def test_basins_on_the_gpu_match_cpu():
    # 2 x 2 starts of tests/test_basins.py's plane at eta = 3.2, three of them in the
    # period-1 orbit's basin and one in steady sliding's: the basins run on the
    # census's device path, so labels and attractors agree
    kw = dict(t_end=3000.0, progress=False)
    grid = (np.linspace(-0.3, 0.3, 8)[:2], np.linspace(-0.25, 0.3, 9)[1:3])
    s = ASYM.replace(eta=3.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        gpu = ssf.basins(s, grid, backend="cuda", **kw)
        cpu = ssf.basins(s, grid, backend="local", **kw)
    np.testing.assert_array_equal(gpu.labels, cpu.labels)
    assert [(a.kind, a.period, a.count) for a in gpu.attractors] == [
        (a.kind, a.period, a.count) for a in cpu.attractors
    ]
    assert gpu.fractions() == cpu.fractions()
    assert {a.kind for a in cpu.attractors} == {"orbit", "equilibrium"}
