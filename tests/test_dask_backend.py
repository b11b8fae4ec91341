"""The Dask backend: bit-identical to the local one, survives a killed worker, clear without the extra."""

import importlib.util
import os
import re
import signal
import sys
import threading
import time
from collections import Counter

import h5py
import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.analysis.sweep import sweep
from stickslip_fast.io import SweepFile

HAVE_DASK = importlib.util.find_spec("distributed") is not None
needs_dask = pytest.mark.skipif(not HAVE_DASK, reason="dask[distributed] is not installed")

ASYM = ssf.System.preset("asymmetric")
KW = dict(t_end=800.0, t_transient=400.0, max_points=24)
FIELDS = ("points", "t_points", "count", "period", "status_code", "n_steps", "n_rejected",
          "n_crossings", "final_state")  # fmt: skip


def _same(a, b):
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)


def _same_files(a, b):
    with h5py.File(a, "r") as ha, h5py.File(b, "r") as hb:
        assert sorted(ha) == sorted(hb)
        for name in ha:
            np.testing.assert_array_equal(ha[name][...], hb[name][...], err_msg=name)
        assert ha.attrs["config"] == hb.attrs["config"]


# values without an orbit are expected here: silence sweep()'s summary warning
pytestmark = pytest.mark.filterwarnings("ignore:.*gave no orbit")


@pytest.fixture(scope="module")
def cluster():
    """Two single-threaded worker processes (one Numba thread each) for the whole module."""
    from distributed import Client

    from stickslip_fast.backends.dask import local_cluster

    # compile (or load) the kernels here first, so the workers load Numba's cache
    sweep(ASYM, "eta", [9.0], **KW)
    sweep(ASYM, "eta", [9.0], mode="continuation", **KW)
    with local_cluster(2) as cl, Client(cl, set_as_default=False) as client:
        client.wait_for_workers(2)
        yield cl.scheduler_address, client


@needs_dask
def test_restart_equals_local_bit_for_bit_in_memory_and_in_the_file(cluster, tmp_path):
    address, _ = cluster
    # repeated values: equal inputs in different places must each be written
    etas = np.array([5.5, 9.9, 7.0, 5.5, 8.2, 9.9, 6.1, 7.0, 9.5, 8.8])
    ref = sweep(ASYM, "eta", etas, out=tmp_path / "local.h5", **KW)
    res = sweep(ASYM, "eta", etas, backend="dask", scheduler=address, chunk_size=1, **KW)
    _same(ref, res)
    res = sweep(ASYM, "eta", etas, backend="dask", scheduler=address, chunk_size=3,
                out=tmp_path / "dask.h5", **KW)  # fmt: skip
    _same(ref, res)
    _same_files(tmp_path / "local.h5", tmp_path / "dask.h5")
    # a 2-D period map
    axes = (np.array([6.0, 9.0, 9.9]), np.array([-0.8, 0.0]))
    _same(
        sweep(ASYM, ("eta", "k12"), axes, **KW),
        sweep(ASYM, ("eta", "k12"), axes, backend="dask", scheduler=address, chunk_size=2, **KW),
    )


@needs_dask
@pytest.mark.parametrize("mode", ["continuation", "continuation-both"])
def test_continuation_equals_local_bit_for_bit(cluster, tmp_path, mode):
    address, _ = cluster
    etas = np.linspace(5.0, 9.9, 7)
    ref = sweep(ASYM, "eta", etas, mode=mode, out=tmp_path / "local.h5", **KW)
    res = sweep(ASYM, "eta", etas, mode=mode, backend="dask", scheduler=address, chunk_size=3,
                out=tmp_path / "dask.h5", **KW)  # fmt: skip
    _same(ref, res)
    _same_files(tmp_path / "local.h5", tmp_path / "dask.h5")
    # 2-D: one chain per k12 value, split across the workers within each round
    axes = (np.array([6.0, 8.0, 9.9]), np.array([-0.8, -0.2, 0.0]))
    _same(
        sweep(ASYM, ("eta", "k12"), axes, mode=mode, **KW),
        sweep(ASYM, ("eta", "k12"), axes, mode=mode, backend="dask", scheduler=address, **KW),
    )


@needs_dask
@pytest.mark.parametrize("mode", ["restart", "continuation-both"])
def test_dask_resumes_a_partial_local_sweep(cluster, tmp_path, monkeypatch, mode):
    address, _ = cluster
    etas = np.linspace(5.5, 9.9, 10)
    sweep(ASYM, "eta", etas, mode=mode, out=tmp_path / "full.h5", **KW)
    original = SweepFile.write
    calls = []

    def failing_write(self, index, data):
        if len(calls) == 3:
            raise RuntimeError("stop here")
        calls.append(index)
        original(self, index, data)

    part = tmp_path / "part.h5"
    monkeypatch.setattr(SweepFile, "write", failing_write)
    with pytest.raises(RuntimeError, match="stop here"):
        sweep(ASYM, "eta", etas, mode=mode, out=part, chunk_size=2, **KW)
    monkeypatch.setattr(SweepFile, "write", original)
    with h5py.File(part, "r") as h5:
        assert h5["done"][...].sum() == 6
    sweep(ASYM, "eta", etas, mode=mode, out=part, backend="dask", scheduler=address, **KW)
    _same_files(tmp_path / "full.h5", part)


@needs_dask
def test_tasks_do_not_compile_and_use_one_numba_thread(cluster):
    address, client = cluster
    from stickslip_fast.backends import dask as backends

    info = backends.prepare_client(client)  # already registered: returns what each warm-up did
    pids = client.run(os.getpid)
    assert set(info) == set(pids)
    for addr, warm in info.items():
        assert warm["pid"] == pids[addr] and warm["numba_threads"] == 1
        assert warm["fingerprint"] == backends.fingerprint()
    sweep(ASYM, "eta", np.linspace(5, 9.9, 6), backend="dask", scheduler=address, chunk_size=1,
          mode="continuation-both", **KW)  # fmt: skip

    def overloads():
        from stickslip_fast.core.sweep_kernels import run_lane

        return {"run_lane": len(run_lane.overloads)}

    # no task compiled a new specialisation after the warm-up
    assert client.run(overloads) == {a: w["overloads"] for a, w in info.items()}
    threads = [client.submit(backends._set_task_threads, pure=False) for _ in range(4)]
    assert set(client.gather(threads)) == {1}


@needs_dask
def test_killed_worker_loses_nothing_and_writes_nothing_twice(cluster, tmp_path, monkeypatch):
    address, client = cluster
    etas = np.linspace(5.0, 10.0, 40)
    kw = dict(t_end=2000.0, t_transient=1000.0, max_points=16)
    ref_path = tmp_path / "local.h5"
    sweep(ASYM, "eta", etas, out=ref_path, **kw)

    written = []
    original = SweepFile.write

    def counting_write(self, index, data):
        written.append(index)
        original(self, index, data)

    monkeypatch.setattr(SweepFile, "write", counting_write)
    path = tmp_path / "dask.h5"
    errors = []

    def run():
        try:
            sweep(ASYM, "eta", etas, out=path, backend="dask", scheduler=address, chunk_size=2,
                  progress=False, **kw)  # fmt: skip
        except BaseException as exc:  # pragma: no cover - reported below
            errors.append(exc)

    thread = threading.Thread(target=run)
    thread.start()
    deadline = time.time() + 60
    while len(written) < 3 and time.time() < deadline:
        time.sleep(0.02)
    busy = {w: keys for w, keys in client.processing().items() if keys}
    assert busy, "no worker was computing"
    victim = sorted(busy)[0]
    pid = client.run(os.getpid, workers=[victim])[victim]
    os.kill(pid, signal.SIGKILL)
    n_at_kill = len(written)
    thread.join(120)
    assert not thread.is_alive() and not errors, errors
    assert 3 <= n_at_kill < len(etas) // 2, "the worker was not killed mid-sweep"
    counts = Counter(i for (sl,) in written for i in range(sl.start, sl.stop))
    assert sorted(counts) == list(range(len(etas))) and set(counts.values()) == {1}
    _same_files(ref_path, path)
    client.wait_for_workers(2, timeout=60)  # the nanny restarted the killed worker
    assert pid not in client.run(os.getpid).values()


@needs_dask
def test_own_local_cluster_is_started_and_closed(tmp_path):
    psutil = pytest.importorskip("psutil")
    etas = np.linspace(6.0, 9.9, 5)
    ref = sweep(ASYM, "eta", etas, **KW)
    before = {p.pid for p in psutil.Process().children(recursive=True)}
    res = sweep(ASYM, "eta", etas, backend="dask", n_workers=2, out=tmp_path / "d.h5", **KW)
    _same(ref, res)
    time.sleep(0.5)
    left = [
        p for p in psutil.Process().children(recursive=True)
        if p.pid not in before and p.is_running() and p.status() != psutil.STATUS_ZOMBIE
        and "spawn_main" in " ".join(p.cmdline())
    ]  # fmt: skip
    assert not left, "the sweep's LocalCluster left worker processes behind"


def test_without_the_extra_the_error_says_what_to_install(monkeypatch, tmp_path, capsys):
    from stickslip_fast.cli import main

    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` now fails
    path = tmp_path / "never.h5"
    hint = re.escape('pip install "stickslip_fast[dask]"')
    with pytest.raises(ImportError, match=hint):
        sweep(ASYM, "eta", [5.0], backend="dask", out=path, **KW)
    with pytest.raises(ImportError, match=hint):
        sweep(ASYM, "eta", [5.0], backend="dask", scheduler="tcp://127.0.0.1:8786", **KW)
    assert not path.exists()  # failed before touching the output
    cfg = tmp_path / "s.toml"
    cfg.write_text('[integration]\nt_end = 10.0\n[sweep]\nparam = "eta"\nvalues = [5.0]\n')
    assert main(["sweep", str(cfg), "-o", str(path), "--workers", "2", "--quiet"]) == 2
    assert 'pip install "stickslip_fast[dask]"' in capsys.readouterr().err
    assert not path.exists()


@needs_dask
def test_bad_dask_arguments_are_named():
    with pytest.raises(ValueError, match="n_workers"):
        sweep(ASYM, "eta", [5.0], backend="dask", scheduler="tcp://h:8786", n_workers=2, **KW)
    with pytest.raises(ValueError, match="n_workers"):
        sweep(ASYM, "eta", [5.0], backend="dask", n_workers=0, **KW)
    with pytest.raises(ValueError, match="scheduler"):
        sweep(ASYM, "eta", [5.0], backend="dask", scheduler=8786, **KW)
    with pytest.raises(ValueError, match="backend='dask'"):
        sweep(ASYM, "eta", [5.0], n_workers=2, **KW)


@needs_dask
def test_cli_scheduler_flag_writes_the_same_file(cluster, tmp_path):
    from stickslip_fast.cli import main

    address, _ = cluster
    cfg = tmp_path / "s.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\n[integration]\nt_end = 600.0\nt_transient = 300.0\n'
        'max_points = 8\n[sweep]\nparam = "eta"\nvalues = { start = 6.0, stop = 9.9, num = 5 }\n'
    )
    assert main(["sweep", str(cfg), "-o", str(tmp_path / "l.h5"), "--quiet"]) == 0
    assert main(["sweep", str(cfg), "-o", str(tmp_path / "d.h5"), "--quiet",
                 "--scheduler", address]) == 0  # fmt: skip
    _same_files(tmp_path / "l.h5", tmp_path / "d.h5")


_TWO_STARTS = """
import sys, warnings
import numpy as np
warnings.simplefilter("ignore")
import stickslip_fast as ssf

def main():
    asym = ssf.System.preset("asymmetric")
    kw = dict(t_end=200.0, t_transient=100.0, max_points=8, progress=False)
    ref = ssf.sweep(asym, "eta", [6.0, 9.0], **kw)
    for _ in range(2):
        res = ssf.sweep(asym, "eta", [6.0, 9.0], backend="dask", n_workers=2, **kw)
        assert np.array_equal(res.status_code, ref.status_code)
        assert np.array_equal(res.points, ref.points, equal_nan=True)
    print("two-starts-ok")

if __name__ == "__main__":
    main()
"""


@needs_dask
def test_local_cluster_leaves_numba_num_threads_alone():
    # Numba raises "Cannot set NUMBA_NUM_THREADS to a different value once the
    # threads have been launched" when that variable changes between two
    # compilations of one process; a cluster's env was applied after a spawned
    # worker had imported Numba, which raced with the warm-up (issue 26).
    from stickslip_fast.backends.dask import local_cluster

    with local_cluster(2) as cl:
        for nanny in cl.workers.values():
            assert "NUMBA_NUM_THREADS" not in nanny.env


@needs_dask
def test_cluster_starts_repeated_in_one_process_and_in_two_at_once(tmp_path):
    """Own clusters started again and again, by two processes at the same time."""
    import subprocess

    script = tmp_path / "two_starts.py"
    script.write_text(_TWO_STARTS)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    procs = [
        subprocess.Popen(
            [sys.executable, str(script)],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=tmp_path,
        )  # fmt: skip
        for _ in range(2)
    ]
    # and in this process meanwhile
    etas = [6.0, 9.0]
    ref = sweep(ASYM, "eta", etas, **KW)
    for _ in range(2):
        _same(ref, sweep(ASYM, "eta", etas, backend="dask", n_workers=2, **KW))
    for p in procs:
        out, err = p.communicate(timeout=600)
        assert p.returncode == 0 and "two-starts-ok" in out, err[-3000:]
        assert "Cannot set NUMBA_NUM_THREADS" not in err
