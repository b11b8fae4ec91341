"""Issue 14, compiled side: no value is stored wrong, no kernel raises, every loop ends, Ctrl-C works.

Each case here failed before the driver rewrite: a value raising inside the
parallel kernel left its lane's later values stored as "ok" with 0 steps;
eps = 1e103 looped forever; mu = 1e300 and friends raised ZeroDivisionError; a
failure in a continuation chain spread to every later value; Ctrl-C waited for
the compiled run to end.
"""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.base.status import FAILURE_STATUSES

ASYM = ssf.System.preset("asymmetric", eta=2.0)
KW = dict(t_end=300.0, t_transient=200.0, progress=False)


def test_a_failing_value_never_corrupts_its_neighbours():
    mus = [0.05, 1e300, 0.051, 0.052, 0.053, 0.054, 0.055, 0.056]
    for threads in (1, 2):
        r = ssf.sweep(ASYM, "mu", mus, threads=threads, **KW)
        for k, mu in enumerate(mus):
            if k == 1:
                continue
            # every other value equals its own single run, bit for bit
            ref = ssf.simulate(
                ssf.System.preset("asymmetric", eta=2.0, mu=mu), 300.0, 200.0, max_points=256
            )
            assert r.status[k] == ref.status == "ok" and r.n_steps[k] == ref.n_steps > 0
            assert r.period[k] == ref.period
        # the absurd value is computed and classified, whatever its outcome
        assert r.n_steps[1] > 0 or r.status[1] in FAILURE_STATUSES
        assert np.all((r.n_steps > 0) | np.isin(r.status, FAILURE_STATUSES))


@pytest.mark.parametrize(
    "fields,y0",
    [
        (dict(mu=1e300), None),
        (dict(c=1e200), None),
        (dict(c=1e300), None),
        (dict(Tb=1e-300, drive="dc-motor"), None),
        ({}, [1e155, 0.0, 0.0, 0.0]),
    ],
)
def test_extreme_but_valid_inputs_are_classified_not_raised(fields, y0):
    s = ssf.System.preset("asymmetric", eta=2.0, **fields)
    r = ssf.simulate(s, 300.0, 200.0, y0=y0, max_steps=100_000)
    assert r.status in ssf.STATUS_NAMES
    if r.status == "ok":
        assert r.n_steps > 0 and np.all(np.isfinite(r.poincare))


def test_eps_1e103_ends_within_max_steps():
    # eps^3 overflows: every stage is NaN, the step size becomes NaN. Before, the
    # rejected-step loop never ended (max_steps counted accepted steps only).
    s = ssf.System.preset("asymmetric", eta=2.0, eps=1e103)
    r = ssf.simulate(s, 300.0, 200.0, y0=[0.01, 0, 0, 0], max_steps=1000)
    assert r.status in ("nonfinite", "step-underflow", "max-steps")
    assert r.n_steps + r.n_rejected <= 2000
    r = ssf.sweep(ASYM, "eps", [1e-5, 1e103], max_steps=100_000, **KW)
    assert r.status[0] == "ok" and r.status[1] in FAILURE_STATUSES


def test_continuation_continues_from_the_last_good_state():
    cs = [-5.0, 0.0, 0.01, 0.02]
    cont = ssf.sweep(ASYM, "c", cs, mode="continuation", **KW)
    rest = ssf.sweep(ASYM, "c", cs, mode="restart", **KW)
    assert cont.status[0] in FAILURE_STATUSES  # negative damping blows up
    # the classification of the later values is the restart one (c = 0.02 damps to rest)
    assert list(cont.status[1:]) == list(rest.status[1:]) == ["ok", "ok", "equilibrium"]
    # the first good value started from y0 again, like restart mode
    assert cont.n_steps[1] == rest.n_steps[1]
    np.testing.assert_array_equal(cont.points[1], rest.points[1])
    assert np.all(cont.n_steps[1:] > 0)


_LONG_RUN = """
import stickslip_fast as ssf, numpy as np, sys
print("ready", flush=True)
if sys.argv[1] == "simulate":
    ssf.simulate(ssf.System.preset("literature", eta=2.7), 1e8, max_points=10,
                 max_steps=10**10)
else:
    ssf.sweep(ssf.System.preset("literature"), "eta", np.linspace(2, 3, 4), t_end=1e8,
              max_steps=10**10, progress=False, out=sys.argv[2])
"""


def _sigint_state(pid: str = "self") -> str:
    """SIGINT's bit in the blocked and ignored signal sets of a process (Linux), for messages."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            fields = dict(line.split(":", 1) for line in fh if ":" in line)
    except OSError:
        return "unknown"
    bit = 1 << (signal.SIGINT - 1)
    return ", ".join(
        f"{k} {'SIGINT' if int(fields[k], 16) & bit else '-'}"
        for k in ("SigBlk", "SigIgn")
        if k in fields
    )


def _default_sigint() -> None:
    # A terminal's Ctrl-C reaches a process with SIGINT handled by default. The test
    # runner's process may have it ignored or blocked (inherited across exec), so the
    # child starts from the terminal's state.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT])


@pytest.mark.skipif(os.name != "posix", reason="SIGINT delivery")
@pytest.mark.parametrize("what", ["simulate", "sweep"])
def test_ctrl_c_stops_compiled_work_promptly(what, tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-c", _LONG_RUN, what, str(tmp_path / "s.h5")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint,
    )  # fmt: skip
    runner = _sigint_state()
    assert proc.stdout.readline().strip() == "ready"
    time.sleep(8.0)  # compile (cached) and get into the long run
    assert proc.poll() is None
    sent = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        child = _sigint_state(str(proc.pid))
        proc.kill()
        pytest.fail(f"no exit 60 s after SIGINT; child {child}, runner {runner}")
    waited = time.perf_counter() - sent
    assert "KeyboardInterrupt" in err and "SystemError" not in err, (err, runner)
    assert waited < 10.0, waited  # within about a second on a quiet machine


_LONG_ORBIT = """
import stickslip_fast as ssf
s = ssf.System.preset("asymmetric", eta=2.0)
o = ssf.find_orbit(s, ssf.simulate(s, 3000, 2000))  # compiled and warm
print("running", flush=True)
ssf.find_orbit(s, o.points[0], period=10**7)  # one kernel call of 10**7 crossings
"""


@pytest.mark.skipif(os.name != "posix", reason="SIGINT delivery")
def test_ctrl_c_stops_an_orbit_kernel_with_keyboard_interrupt():
    # the orbit kernels return arrays: SIGINT's handler then runs inside Numba's boxing of
    # the result, which surfaced as SystemError until 2026-12-01 (base/interrupt.py)
    proc = subprocess.Popen(
        [sys.executable, "-c", _LONG_ORBIT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, preexec_fn=_default_sigint,
    )  # fmt: skip
    assert proc.stdout.readline().strip() == "running"
    time.sleep(1.0)
    assert proc.poll() is None
    sent = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert "KeyboardInterrupt" in err and "SystemError" not in err, err[-2000:]
    assert time.perf_counter() - sent < 10.0


@pytest.mark.skipif(os.name != "posix", reason="SIGINT delivery")
def test_ctrl_c_on_cli_simulate_says_interrupted_and_exits_130():
    cmd = [sys.executable, "-m", "stickslip_fast.cli", "simulate", "--preset", "literature",
           "--eta", "2.7", "--n-oscillators", "3", "--drive", "dc-motor", "--max-points", "10"]  # fmt: skip
    # compiled first: on an empty cache the kernel's compile can outlast the 10 s below,
    # and a SIGINT inside Numba's compiler is not what this test is about
    subprocess.run([*cmd, "--t-end", "1"], capture_output=True, check=True, timeout=600)
    proc = subprocess.Popen(
        # three disks on a DC motor: long enough per step that max_steps (2e7) takes
        # well over the 10 s below
        [*cmd, "--t-end", "1e8"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint,
    )  # fmt: skip
    runner = _sigint_state()
    time.sleep(10.0)
    assert proc.poll() is None
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, (err, runner)
    assert err.strip().splitlines()[-1] == "stickslip-fast: interrupted", err


@pytest.mark.skipif(os.name != "posix", reason="SIGINT delivery")
def test_a_sigint_lost_during_a_chunk_leaves_it_missing_not_interrupted(tmp_path, monkeypatch):
    # Ctrl-C during a cold compile can raise its KeyboardInterrupt inside a finaliser,
    # where Python prints it and goes on; the kernel then stops on the flag with its runs
    # "interrupted". Before 2026-12-02 the sweep stored those four values as finished
    # ("interrupted") and went on; the resumed sweep never ran them again
    import threading

    from stickslip_fast.backends import local

    real, calls = local.sweep_chunk, []

    def chunk_with_a_lost_sigint(*args):
        calls.append(1)
        if len(calls) == 2:
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(5.0)
            except KeyboardInterrupt:
                pass  # as in a __del__: printed, not raised
            while not args[-1][0]:  # the watcher thread sets the flag
                time.sleep(0.001)
        return real(*args)

    assert threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    s = ssf.System.preset("asymmetric")
    values, kw = np.linspace(2, 3, 8), dict(t_end=200, t_transient=100, chunk_size=4)
    out = tmp_path / "s.h5"
    try:
        monkeypatch.setattr(local, "sweep_chunk", chunk_with_a_lost_sigint)
        with pytest.raises(KeyboardInterrupt):
            ssf.sweep(s, "eta", values, out=out, progress=False, **kw)
    finally:
        signal.signal(signal.SIGINT, old)
    part = ssf.load_sweep(out)
    assert list(part.status[4:]) == ["missing"] * 4
    monkeypatch.setattr(local, "sweep_chunk", real)
    resumed = ssf.sweep(s, "eta", values, out=out, progress=False, **kw)
    whole = ssf.sweep(s, "eta", values, progress=False, **kw)
    assert "interrupted" not in list(whole.status)
    assert list(resumed.status) == list(whole.status)
    np.testing.assert_array_equal(resumed.points, whole.points)
