"""Sweeps: equality with simulate, determinism, resume after a kill, the file contract."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import h5py
import numpy as np
import pytest
from scipy.integrate import solve_ivp  # noqa: F401  (reference helpers below)

import stickslip_fast as ssf
from stickslip_fast.analysis.sweep import load_sweep, sweep
from stickslip_fast.io import ConfigMismatchError

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "reference"))
import scipy_model  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASYM = ssf.System.preset("asymmetric")
KW = dict(t_end=800.0, t_transient=400.0, max_points=24)
FIELDS = ("points", "t_points", "count", "period", "status_code", "n_steps", "n_rejected",
          "n_crossings", "final_state")  # fmt: skip


def _same(a, b):
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)


# values without an orbit are expected here: silence sweep()'s summary warning
pytestmark = pytest.mark.filterwarnings("ignore:.*gave no orbit")


@pytest.mark.parametrize("method", ["rodas5p", "rodas4p"])
def test_sweep_equals_simulate_bit_for_bit(method):
    etas = np.array([1.7, 5.2, 6.6, 9.99])
    res = sweep(ASYM, "eta", etas, method=method, **KW)
    for i, eta in enumerate(etas):
        one = ssf.simulate(ASYM.replace(eta=eta), method=method, **KW)
        assert res.status[i] == one.status and res.period[i] == one.period
        k = res.count[i]
        assert k == len(one.t_poincare)
        np.testing.assert_array_equal(res.points[i, :k], one.poincare)
        np.testing.assert_array_equal(res.t_points[i, :k], one.t_poincare)
        assert np.all(np.isnan(res.points[i, k:]))
        np.testing.assert_array_equal(res.final_state[i], one.final_state)
        assert res.n_steps[i] == one.n_steps


def test_results_identical_across_threads_and_chunk_sizes(tmp_path):
    etas = np.linspace(6.0, 10.0, 7)
    ref = sweep(ASYM, "eta", etas, threads=1, chunk_size=1, **KW)
    for threads, chunk in ((2, 3), (2, None), (1, 7)):
        _same(ref, sweep(ASYM, "eta", etas, threads=threads, chunk_size=chunk, **KW))
    _same(ref, sweep(ASYM, "eta", etas, out=tmp_path / "a.h5", chunk_size=2, **KW))
    for mode in ("continuation", "continuation-both"):
        a = sweep(ASYM, "eta", etas, mode=mode, threads=1, chunk_size=1, **KW)
        b = sweep(ASYM, "eta", etas, mode=mode, threads=2, chunk_size=4, **KW)
        _same(a, b)


def test_file_matches_memory_and_reads_with_h5py_and_xarray(tmp_path):
    xr = pytest.importorskip("xarray")
    etas = np.linspace(5.5, 9.5, 5)
    mem = sweep(ASYM, "eta", etas, **KW)
    path = tmp_path / "fig.h5"
    res = sweep(ASYM, "eta", etas, out=path, title="test", **KW)
    _same(mem, res)
    _same(mem, load_sweep(path))
    with h5py.File(path, "r") as h5:
        assert h5.attrs["schema_version"] == 1 and h5.attrs["title"] == "test"
        np.testing.assert_array_equal(h5["eta"][...], etas)
        np.testing.assert_array_equal(h5["period"][...], mem.period)
        assert h5["points"].shape == (5, 24, 4)
        assert list(h5["status"].attrs["flag_meanings"].split()) == list(ssf.STATUS_NAMES)
    ds = xr.open_dataset(path, engine="h5netcdf")
    assert ds["points"].dims == ("eta", "point", "state")
    assert list(ds["state"].values) == ["x1", "dx1", "phi1", "dphi1"]
    np.testing.assert_array_equal(ds["eta"].values, etas)
    x1 = ds["points"].sel(state="x1").isel(eta=2).values
    np.testing.assert_array_equal(x1, mem.points[2, :, 0])
    ds.close()


def test_mismatched_configuration_is_refused(tmp_path):
    path = tmp_path / "s.h5"
    etas = np.linspace(6, 9, 3)
    sweep(ASYM, "eta", etas, out=path, **KW)
    before = path.read_bytes()
    with pytest.raises(ConfigMismatchError, match="t_end"):
        sweep(ASYM, "eta", etas, out=path, **{**KW, "t_end": 900.0})
    with pytest.raises(ConfigMismatchError, match="values_sha256"):
        sweep(ASYM, "eta", etas + 0.1, out=path, **KW)
    with pytest.raises(ConfigMismatchError, match="system.k12"):
        sweep(ASYM.replace(k12=-0.5), "eta", etas, out=path, **KW)
    with pytest.raises(ConfigMismatchError, match="mode"):
        sweep(ASYM, "eta", etas, out=path, mode="continuation", **KW)
    assert path.read_bytes() == before  # untouched
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    with pytest.raises(ConfigMismatchError, match="not a readable HDF5"):
        sweep(ASYM, "eta", etas, out=junk, **KW)
    # the same configuration on the same file: nothing to do, same result
    again = sweep(ASYM, "eta", etas, out=path, **KW)
    assert again.count.shape == (3,)


def test_killed_sweep_resumes_to_the_same_file(tmp_path):
    etas = np.linspace(5.0, 10.0, 48)
    kw = dict(t_end=3000.0, t_transient=2000.0, max_points=16)
    full = tmp_path / "full.h5"
    ref = sweep(ASYM, "eta", etas, out=full, chunk_size=2, threads=1, **kw)
    part = tmp_path / "part.h5"
    script = textwrap.dedent(
        f"""
        import sys, numpy as np
        sys.path.insert(0, {ROOT!r})
        import stickslip_fast as ssf
        from stickslip_fast.analysis.sweep import sweep
        sweep(ssf.System.preset("asymmetric"), "eta", np.linspace(5.0, 10.0, 48),
              out={str(part)!r}, chunk_size=2, threads=1, progress=False, **{kw!r})
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.DEVNULL)
    n_done = 0
    deadline = time.time() + 600  # generous: the child may have to compile on a busy machine
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)
        try:
            with h5py.File(part, "r", libver="latest", swmr=True) as h5:
                n_done = int(h5["done"][...].sum())
        except (OSError, KeyError):
            continue
        if n_done >= 6:
            break
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with h5py.File(part, "r", libver="latest", swmr=True) as h5:
        n_done = int(h5["done"][...].sum())
    assert 0 < n_done < len(etas), "the sweep was not killed mid-run"
    resumed = sweep(ASYM, "eta", etas, out=part, chunk_size=5, threads=2, **kw)
    _same(ref, resumed)
    with h5py.File(full, "r") as a, h5py.File(part, "r") as b:
        for name in a:
            np.testing.assert_array_equal(a[name][...], b[name][...], err_msg=name)
        assert a.attrs["config"] == b.attrs["config"]


def test_two_dimensional_grid_is_a_period_map():
    etas = np.array([6.0, 9.0])
    k12s = np.array([-0.8, 0.0, 0.3])
    res = sweep(ASYM, ("eta", "k12"), (etas, k12s), **KW)
    assert res.points.shape == (2, 3, 24, 4) and res.period.shape == (2, 3)
    for i, eta in enumerate(etas):
        for j, k12 in enumerate(k12s):
            one = ssf.simulate(ASYM.replace(eta=eta, k12=k12), **KW)
            assert res.status[i, j] == one.status and res.period[i, j] == one.period
            np.testing.assert_array_equal(res.points[i, j, : res.count[i, j]], one.poincare)
    # k12 = 0 with phi = 0 initially: the symmetric disk never rotates
    assert np.all(np.nan_to_num(res.column("phi1")[:, 1]) == 0.0)


def test_continuation_both_finds_coexisting_attractors():
    # Asymmetric set, constant belt. Independent evidence of bistability:
    # (1) steady sliding q = K^-1 (mu, 0) is a linearly stable equilibrium of the
    #     independent SciPy model (finite-difference Jacobian) for every eta here;
    # (2) that model's trajectory from rest at eta = 9.99 is a stick-slip orbit
    #     (tests/reference, Radau rtol 1e-10).
    etas = np.array([5.0, 6.5, 8.0, 9.5])
    q = np.linalg.solve([[1.0, ASYM.k12], [ASYM.k12, 1.0]], [ASYM.mu, 0.0])
    y_eq = np.array([q[0], 0.0, q[1], 0.0])
    for eta in etas:
        p = ASYM.replace(eta=eta).to_dict()
        f0 = scipy_model.rhs(0.0, y_eq, p)
        assert np.abs(f0).max() < 1e-6  # it is an equilibrium
        jac = np.column_stack([
            (scipy_model.rhs(0, y_eq + d, p) - scipy_model.rhs(0, y_eq - d, p)) / 2e-7
            for d in np.eye(4) * 1e-7
        ])  # fmt: skip
        assert np.linalg.eigvals(jac).real.max() < 0
    res = sweep(ASYM, "eta", etas, mode="continuation-both", **{**KW, "t_end": 1500.0})
    up, down = res.status
    assert res.points.shape[:2] == (2, 4)
    assert list(up) == ["equilibrium"] * 4  # from rest at eta = 5: steady sliding throughout
    assert list(down[1:]) == ["ok"] * 3  # from the orbit at 9.5 down: stick-slip persists
    assert np.all(res.period[1, 1:] >= 1)


def test_failed_values_get_status_and_nan_and_the_sweep_goes_on():
    etas = np.array([6.0, 9.99])
    with pytest.warns(UserWarning, match="2 of 2 values gave no orbit: 2 max-steps"):
        res = sweep(ASYM, "eta", etas, max_steps=50, **KW)
    assert list(res.status) == ["max-steps", "max-steps"]
    assert np.all(np.isnan(res.points)) and np.all(res.count == 0)
    with pytest.warns(UserWarning, match="equilibrium"):
        sweep(ASYM, "eta", np.array([1.0, 9.99]), **KW)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(param="n_oscillators", values=[1, 2]), "n_oscillators"),
        (dict(param="eta", values=[5.0, 11.0]), "eta"),
        (dict(param="m", values=[1.0, -1.0]), "m"),
        (dict(param="eta", values=[]), "eta"),
        (dict(param="eta", values=[5.0], mode="sideways"), "mode"),
        (dict(param="eta", values=[5.0], chunk_size=0), "chunk_size"),
        (dict(param="eta", values=[5.0], threads=0), "threads"),
        (dict(param="eta", values=[5.0], backend="spark"), "backend"),
        (dict(param=("eta", "eta"), values=([5.0], [6.0])), "differ"),
    ],
)
def test_bad_sweep_arguments_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        sweep(ASYM, t_end=10.0, **kwargs)
