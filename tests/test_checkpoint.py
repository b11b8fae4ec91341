"""Checkpoints of continuations (base/journal.py): a killed branch or curve resumes and
gives the bits of a run that was never interrupted; a wrong file is refused by name."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.base import journal as jmod
from stickslip_fast.base import threads as bthreads
from stickslip_fast.base.journal import Journal, call_journaled, describe, journal

# the stable period-1 orbit at eta = 3.3, k12 = -0.8 (tests/test_foldcurve_orbit.py)
Z33 = np.array([0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407])


# ------------------------------------------------------------------ the file, on a fake kernel
CALLS: list[tuple] = []


def pure_kernel(y, k, scale, flag, variant, abort):
    """A pure 'kernel': a code, an array, a matrix, a float, a bool and an empty array."""
    CALLS.append((y.copy(), k))
    return (3, y * scale, np.outer(y, y)[:k], float(np.sum(y)) + 0.1, bool(flag),
            np.empty((0, 2)))  # fmt: skip


def _call(y, k=2, scale=2.0, flag=True, variant=(0, 0.0)):
    return call_journaled(pure_kernel, y, k, scale, flag, variant, abort=np.zeros(1, np.int64))


def _same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert type(x) is type(y)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y)
            assert x.flags.writeable
        else:
            assert x == y


def test_calls_are_recorded_then_answered_from_the_file(tmp_path):
    path = tmp_path / "j.ckpt"
    y = np.array([1.0, -2.5, 3.25])
    CALLS.clear()
    with journal(path, "test", {"a": 1}) as j:
        first = _call(y)
        again = _call(y)  # the same inputs in the same run: from the record
        other = _call(y, scale=2)  # an int, not the float 2.0: another call
        assert (j.hits, j.misses) == (1, 2)
    assert len(CALLS) == 2
    _same(first, pure_kernel(y, 2, 2.0, True, (0, 0.0), None))
    _same(again, first)
    _same(other, first)  # the same numbers, computed again
    CALLS.clear()
    with journal(path, "test", {"a": 1.0}) as j:  # 1 and 1.0: the same setting
        assert j.recorded == 2
        _same(_call(y), first)
        _call(y, variant=(0, 0))  # a variant token of other types is another call
        assert (j.hits, j.misses) == (1, 1)
    assert len(CALLS) == 1
    # without a journal, nothing is recorded
    CALLS.clear()
    _call(y)
    _call(y)
    assert len(CALLS) == 2


def test_a_record_cut_short_is_dropped_and_the_file_goes_on(tmp_path):
    path = tmp_path / "j.ckpt"
    ys = [np.array([1.0, 2.0]), np.array([3.0, 4.0])]
    with journal(path, "test", {}):
        for y in ys:
            _call(y)
    size = path.stat().st_size
    # a kill in the middle of writing a third record: its frame promises more bytes
    with open(path, "ab") as f:
        f.write(jmod._FRAME.pack(500, 0) + b"\x01" * 37)
    CALLS.clear()
    with journal(path, "test", {}) as j:
        assert j.recorded == 2
        assert path.stat().st_size == size  # the tail is gone
        _call(ys[0])
        _call(np.array([5.0, 6.0]))
        assert (j.hits, j.misses) == (1, 1)
    # a damaged byte inside the last record: it (and only it) is dropped
    data = bytearray(path.read_bytes())
    data[-3] ^= 0xFF
    path.write_bytes(bytes(data))
    with journal(path, "test", {}) as j:
        assert j.recorded == 2


def test_another_configuration_is_refused_by_name(tmp_path, monkeypatch):
    path = tmp_path / "j.ckpt"
    with journal(path, "continue_orbit", {"ds": 0.01, "orbit": np.arange(3.0)}):
        _call(np.ones(2))
    with pytest.raises(ValueError, match=r"argument 'ds' was 0\.01, now 0\.02"):
        with journal(path, "continue_orbit", {"ds": 0.02, "orbit": np.arange(3.0)}):
            pass
    with pytest.raises(ValueError, match="argument 'orbit' was array"):
        with journal(
            path, "continue_orbit", {"ds": 0.01, "orbit": np.array([0.0, 1.0, 2.0 + 1e-15])}
        ):
            pass
    with pytest.raises(ValueError, match="argument 'tol' was \\(not given\\)"):
        with journal(path, "continue_orbit", {"ds": 0.01, "orbit": np.arange(3.0), "tol": 1.0}):
            pass
    with pytest.raises(ValueError, match="written by continue_orbit, not continue_bifurcation"):
        with journal(path, "continue_bifurcation", {}):
            pass
    monkeypatch.setattr("stickslip_fast.base.cache_guard.fingerprint", lambda: "f" * 64)
    with pytest.raises(ValueError, match="written by other code"):
        with journal(path, "continue_orbit", {"ds": 0.01, "orbit": np.arange(3.0)}):
            pass


def test_a_foreign_file_a_busy_file_and_a_bad_path(tmp_path):
    foreign = tmp_path / "out.h5"
    foreign.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100)
    with pytest.raises(ValueError, match="is not a stickslip_fast checkpoint file"):
        with journal(foreign, "test", {}):
            pass
    assert foreign.read_bytes()[:4] == b"\x89HDF"  # untouched
    path = tmp_path / "j.ckpt"
    with journal(path, "test", {}):
        _call(np.ones(2))
        with pytest.raises(RuntimeError, match="in use by another process"):
            Journal(path, {})
    with pytest.raises(ValueError, match="checkpoint must be a path"):
        with journal(3, "test", {}):
            pass


def test_a_file_with_nothing_recorded_is_not_left_behind(tmp_path):
    path = tmp_path / "sub" / "j.ckpt"
    with pytest.raises(KeyError):
        with journal(path, "test", {}):
            raise KeyError("failed before any integration")
    assert not path.exists()
    # a header cut short by a kill: the file starts again
    path.write_bytes(jmod.MAGIC + jmod._FRAME.pack(90, 1) + b"{")
    with journal(path, "test", {}) as j:
        assert j.recorded == 0
        _call(np.ones(2))
    with journal(path, "test", {}) as j:
        assert j.recorded == 1


def test_describe_is_exact_and_refuses_what_it_cannot_name():
    s = ssf.System.preset("asymmetric")
    assert describe(s) == describe(ssf.System.preset("asymmetric"))
    assert describe(s) != describe(s.replace(eta=s.eta + 1e-15))
    assert describe(np.zeros(3)) != describe(np.zeros(3, dtype=np.float32))
    assert describe([1, 2.0]) == describe((1.0, 2))
    assert describe(True) != describe(1)
    with pytest.raises(TypeError, match="function"):
        describe(lambda: 0)


# ------------------------------------------------------------------ continuations
@pytest.fixture(scope="module")
def fold_branch():
    s = ssf.System.preset("asymmetric", eta=3.30, k12=-0.8)
    orbit = ssf.find_orbit(s, Z33, 1)
    assert orbit.converged
    branch = ssf.continue_orbit(orbit, "eta", (3.30, 3.35), ds=2e-3, ds_max=5e-3,
                                max_points=100, stick_events=False, progress=False)  # fmt: skip
    return orbit, branch, next(b for b in branch.bifurcations if b.kind == "fold")


def _interrupted_after(monkeypatch, calls: int):
    """Make the journal's kernel calls raise KeyboardInterrupt after ``calls`` of them
    (what Ctrl-C does; a kill leaves the same file, less at most a record cut short)."""
    real, count = jmod.call_interruptible, [0]

    def flaky(kernel, *args, abort):
        count[0] += 1
        if count[0] > calls:
            raise KeyboardInterrupt
        return real(kernel, *args, abort=abort)

    monkeypatch.setattr(jmod, "call_interruptible", flaky)
    return lambda: monkeypatch.setattr(jmod, "call_interruptible", real)


def _same_branch(a, b):
    assert a.status == b.status
    for name in ("values", "points", "multipliers", "T", "stable"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert [(x.kind, x.value) for x in a.bifurcations] == [
        (x.kind, x.value) for x in b.bifurcations
    ]
    assert describe(a) == describe(b)  # every field, to the bit (segments, stick phases)


def _counts(caplog):
    """(from the file, in all, computed) of the last journal closed (its INFO line)."""
    record = [r for r in caplog.records if "calls from the file" in r.getMessage()][-1]
    return record.args[1:]


def test_a_branch_resumed_after_an_interruption_is_bit_identical(fold_branch, tmp_path,
                                                                 monkeypatch, caplog):  # fmt: skip
    orbit, _, _ = fold_branch
    kw = dict(ds=2e-3, ds_max=5e-3, max_points=40, progress=False)
    ref = ssf.continue_orbit(orbit, "eta", (3.30, 3.35), **kw)  # through the sharp fold
    path = tmp_path / "branch.ckpt"
    restore = _interrupted_after(monkeypatch, 25)
    with pytest.raises(KeyboardInterrupt):
        ssf.continue_orbit(orbit, "eta", (3.30, 3.35), checkpoint=path, **kw)
    restore()
    with open(path, "ab") as f:  # and a record cut short by the kill
        f.write(jmod._FRAME.pack(4000, 7) + b"\0" * 100)
    caplog.set_level("INFO", logger="stickslip_fast.checkpoint")
    resumed = ssf.continue_orbit(orbit, "eta", (3.30, 3.35), checkpoint=path, **kw)
    _same_branch(resumed, ref)
    assert "dropped 108 bytes of an unfinished record" in caplog.text
    assert "resuming from 25 recorded kernel calls" in caplog.text
    hits, total, misses = _counts(caplog)
    # the 25 recorded, and a few calls the walk repeats with the same inputs
    assert 25 <= hits < 35 and misses > 100 and total == hits + misses
    # done: the file answers the same call again without integrating
    again = ssf.continue_orbit(orbit, "eta", (3.30, 3.35), checkpoint=path, **kw)
    _same_branch(again, ref)
    assert _counts(caplog) == (total, total, 0)
    with pytest.raises(ValueError, match="argument 'max_points' was 40.0, now 41.0"):
        ssf.continue_orbit(orbit, "eta", (3.30, 3.35), checkpoint=path, **{**kw, "max_points": 41})  # fmt: skip


def _resumed_halfway(run, tmp_path, monkeypatch, caplog):
    """``run(checkpoint)`` with a checkpoint, interrupted halfway through its kernel
    calls, then resumed; returns (the resumed result, the calls in all)."""
    caplog.set_level("INFO", logger="stickslip_fast.checkpoint")
    run(tmp_path / "count.ckpt")
    total = _counts(caplog)[1]
    path = tmp_path / "half.ckpt"
    restore = _interrupted_after(monkeypatch, total // 2)
    with pytest.raises(KeyboardInterrupt):
        run(path)
    restore()
    return run(path), total


@pytest.mark.parametrize("threads", [1, 3])
def test_a_multiple_shooting_branch_resumes_bit_identically(fold_branch, tmp_path,
                                                            monkeypatch, caplog, threads):  # fmt: skip
    # on 3 threads the segments' calls reach the journal from the pool's workers, and the
    # interruption is raised in one of them
    monkeypatch.setattr(bthreads, "numba_threads", lambda: threads)
    orbit, _, _ = fold_branch
    kw = dict(ds=2e-3, ds_max=5e-3, max_points=6, shooting="multiple", segments=3,
              stick_events=False, progress=False)  # fmt: skip
    ref = ssf.continue_orbit(orbit, "eta", (3.30, 3.35), **kw)
    got, total = _resumed_halfway(
        lambda path: ssf.continue_orbit(orbit, "eta", (3.30, 3.35), checkpoint=path, **kw),
        tmp_path, monkeypatch, caplog,
    )  # fmt: skip
    assert total > 10
    _same_branch(got, ref)
    assert got.segments is not None


def test_a_fold_curve_resumed_after_an_interruption_is_bit_identical(fold_branch, tmp_path,
                                                                     monkeypatch, caplog):  # fmt: skip
    _, branch, fold = fold_branch
    kw = dict(direction=-1, ds=0.002, ds_max=0.01, max_points=10, progress=False)
    ref = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79), **kw)
    assert len(ref.values) == 10
    got, total = _resumed_halfway(
        lambda path: ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79),
                                              checkpoint=path, **kw),
        tmp_path, monkeypatch, caplog,
    )  # fmt: skip
    assert total > 50
    assert got.status == ref.status
    for name in ("values", "points", "T", "multipliers"):
        np.testing.assert_array_equal(getattr(got, name), getattr(ref, name), err_msg=name)
    assert [(c.kind, c.values.tolist()) for c in got.codim2] == [
        (c.kind, c.values.tolist()) for c in ref.codim2
    ]
    assert describe(got) == describe(ref)


def test_a_curve_of_equilibria_integrates_nothing_and_leaves_no_file(tmp_path):
    dc = ssf.System.preset("asymmetric", drive="dc-motor", eta=2.0)
    branch = ssf.continue_equilibrium(ssf.find_equilibrium(dc, "sliding"), "beta",
                                      (0.0005, 0.05), ds=0.001, ds_max=0.005, max_points=400,
                                      progress=False)  # fmt: skip
    hopf = next(b for b in branch.bifurcations if b.kind == "hopf")
    path = tmp_path / "hopf.ckpt"
    kw = dict(max_points=8, progress=False)
    got = ssf.continue_bifurcation(branch, hopf, "eta", (1.9, 2.1), checkpoint=path, **kw)
    ref = ssf.continue_bifurcation(branch, hopf, "eta", (1.9, 2.1), **kw)
    np.testing.assert_array_equal(got.values, ref.values)
    assert not path.exists()


def test_cli_continue_resumes_from_its_checkpoint_and_removes_it(tmp_path, monkeypatch, capsys):
    from stickslip_fast.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\neta = 2.0\n'
        '[integration]\nt_end = 20000.0\nstop = "converged"\n'
        '[continue]\nparam = "eta"\nbounds = [1.9, 2.1]\nds = 0.02\nds_max = 0.05\n'
        "max_points = 25\n"
    )
    ref_out, out = tmp_path / "ref.h5", tmp_path / "b.h5"
    assert main(["continue", str(cfg), "-o", str(ref_out), "--quiet"]) == 0
    assert not (tmp_path / "ref.h5.checkpoint").exists()
    restore = _interrupted_after(monkeypatch, 10)
    assert main(["continue", str(cfg), "-o", str(out), "--quiet"]) == 130
    restore()
    checkpoint = tmp_path / "b.h5.checkpoint"
    assert checkpoint.exists() and not out.exists()
    err = capsys.readouterr().err
    assert f"interrupted; the integrations so far are in {checkpoint}, run the same" in err
    assert main(["continue", str(cfg), "-o", str(out)]) == 0
    assert f"resuming from {checkpoint} (10 integrations recorded)" in capsys.readouterr().err
    assert not checkpoint.exists()
    _same_branch(ssf.Branch.from_hdf5(out), ssf.Branch.from_hdf5(ref_out))
    # a changed config does not resume another's checkpoint
    assert main(["continue", str(cfg), "-o", str(out), "--quiet"]) == 0  # a fresh run
    restore = _interrupted_after(monkeypatch, 5)
    assert main(["continue", str(cfg), "-o", str(out), "--quiet"]) != 0
    restore()
    cfg.write_text(cfg.read_text().replace("max_points = 25", "max_points = 26"))
    assert main(["continue", str(cfg), "-o", str(out)]) == 2
    assert "argument 'continuation' was" in capsys.readouterr().err


def test_a_curve_killed_by_sigkill_resumes_bit_identically(fold_branch, tmp_path):
    """A real SIGKILL of a process in the middle of a fold curve, then the same call."""
    _, branch, fold = fold_branch
    kw = dict(direction=-1, ds=0.002, ds_max=0.01, max_points=14, progress=False)
    ref = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79), **kw)
    branch.to_hdf5(tmp_path / "branch.h5")
    path = tmp_path / "curve.ckpt"
    root = str(Path(__file__).resolve().parents[1])
    script = textwrap.dedent(
        f"""
        import sys
        sys.path.insert(0, {root!r})
        import stickslip_fast as ssf
        branch = ssf.Branch.from_hdf5({str(tmp_path / "branch.h5")!r})
        fold = next(b for b in branch.bifurcations if b.kind == "fold")
        ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79),
                                 checkpoint={str(path)!r}, **{kw!r})
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.DEVNULL)
    deadline = time.time() + 600  # generous: the child may have to compile on a busy machine
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.02)
        if path.exists() and path.stat().st_size > 40_000:  # about 60 records
            break
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the curve ended before the kill"
    got = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79), checkpoint=path, **kw)
    assert describe(got) == describe(ref)


def test_a_stable_manifold_resumes_bit_identically(tmp_path, monkeypatch, caplog):
    # the model case of tests/test_basins_manifold.py: the P1 saddle past Fig. 6's upper
    # fold, traced from one refined boundary point
    s = ssf.System.preset("asymmetric", eta=3.323654117482133)
    saddle = [0.07259114445455046, 0.0, 0.12216932570735764, -0.006665729137139496]
    orbit = ssf.find_orbit(s, saddle, period=1)
    seed = np.array([0.0677029, -0.14516129])
    box = np.stack([seed - 1e-3, seed + 1e-3], axis=1)
    kw = dict(plane=("x1", "phi1"), bounds=box, seeds=[seed], ds=4e-4, r_local=1e-6,
              n_max=12, max_points=3)  # fmt: skip
    ref = ssf.stable_manifold(s, orbit, **kw)
    assert len(ref.u) >= 4
    got, total = _resumed_halfway(
        lambda path: ssf.stable_manifold(s, orbit, checkpoint=path, **kw),
        tmp_path, monkeypatch, caplog,
    )  # fmt: skip
    assert total > 100
    assert describe(got) == describe(ref)
    with pytest.raises(ValueError, match="argument 'trace' was"):
        ssf.stable_manifold(s, orbit, checkpoint=tmp_path / "half.ckpt", **{**kw, "n_max": 13})


def test_a_script_under_one_checkpoint_resumes_bit_identically(fold_branch, tmp_path,
                                                               monkeypatch, caplog):  # fmt: skip
    orbit, _, _ = fold_branch
    curve_kw = dict(direction=-1, ds=0.002, ds_max=0.01, max_points=4, progress=False)

    def script(path):
        """A branch through the sharp fold, then the fold's curve in k12."""
        with ssf.checkpoint(path, preset="asymmetric") if path else contextlib.nullcontext():
            br = ssf.continue_orbit(orbit, "eta", (3.30, 3.35), ds=2e-3, ds_max=5e-3,
                                    max_points=20, stick_events=False, progress=False)  # fmt: skip
            fold = next(b for b in br.bifurcations if b.kind == "fold")
            return br, ssf.continue_bifurcation(br, fold, "k12", (-0.806, -0.79), **curve_kw)

    ref = script(None)
    got, total = _resumed_halfway(script, tmp_path, monkeypatch, caplog)
    assert total > 100
    assert describe(got) == describe(ref)
    with pytest.raises(ValueError, match="argument 'preset' was 'asymmetric', now 'literature'"):
        with ssf.checkpoint(tmp_path / "half.ckpt", preset="literature"):
            pass
    # a call with its own file records there, not in the script's
    with ssf.checkpoint(tmp_path / "outer.ckpt") as outer:
        ssf.continue_bifurcation(ref[0], ref[0].bifurcations[0], "k12", (-0.806, -0.79),
                                 checkpoint=tmp_path / "inner.ckpt", **curve_kw)  # fmt: skip
        assert outer.misses == 0
    assert (tmp_path / "inner.ckpt").exists() and not (tmp_path / "outer.ckpt").exists()
    with pytest.raises(ValueError, match="needs a path"):
        with ssf.checkpoint(None):
            pass
