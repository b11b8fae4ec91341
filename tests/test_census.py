"""The attractor census: attractors and basin fractions per value, tracks, the file contract.

References: plain :func:`simulate` from the zero state (the fixed-start
diagram), the analytic steady-sliding state, and constructed point sets for
the grouping and tracking. Cost: about 20-30 s on a busy 2-core VM (the Dask
test adds ~10 s when dask[distributed] is installed).
"""

import importlib.util
import os
import signal
import subprocess
import sys
import textwrap
import time

import h5py
import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.analysis.census import (
    census,
    classify_census,
    default_box,
    load_census,
    sample_starts,
)
from stickslip_fast.core.poincare import STATUS_NAMES
from stickslip_fast.io import ConfigMismatchError

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASYM = ssf.System.preset("asymmetric")
# short runs: from the census box the period-1 orbit at eta = 2 and steady sliding
# are reached well within 300 time units (the same labels with t_end = 3000)
KW = dict(t_end=600.0, t_transient=300.0)
RAW = ("points", "count", "period", "status", "final_state", "n_steps", "n_rejected",
       "n_crossings", "done")  # fmt: skip
HAVE_DASK = importlib.util.find_spec("distributed") is not None


def _same(a, b):
    for name in RAW:
        np.testing.assert_array_equal(a.raw[name], b.raw[name], err_msg=name)
    np.testing.assert_array_equal(a.labels, b.labels)
    np.testing.assert_array_equal(a.starts, b.starts)


@pytest.fixture(scope="module")
def eta2_4():
    return census(ASYM, "eta", [2.0, 4.0], n_starts=16, progress=False, **KW)


def test_eta2_has_the_period1_orbit_and_steady_sliding(eta2_4):
    res = eta2_4
    atts = res.attractors[0]
    kinds = {(a.kind, a.period) for a in atts}
    assert kinds == {("orbit", 1), ("equilibrium", 0)}
    assert res.failed_fraction[0] == 0.0
    assert sum(a.fraction for a in atts) == pytest.approx(1.0, abs=1e-15)
    for a in atts:
        assert a.count == np.sum(res.labels[0] == a.id)
        assert a.fraction == a.count / 16
    # both basins hold several starts (the issue measured 20 : 4 of 24 in a smaller box)
    assert all(a.count >= 2 for a in atts)
    # steady sliding is the analytic state: friction -mu balances the springs
    eq = next(a for a in atts if a.kind == "equilibrium")
    xs = ASYM.mu / (1.0 - ASYM.k12**2)
    np.testing.assert_allclose(eq.points[0], [xs, 0.0, -ASYM.k12 * xs, 0.0], atol=2e-5)
    # at eta = 4 the period-1 orbit no longer exists (it ends near 3.32): sliding only
    assert [(a.kind, a.fraction) for a in res.attractors[1]] == [("equilibrium", 1.0)]
    assert res.attractors[1][0].id == eq.id  # the same track
    assert res.deaths == [(next(a.id for a in atts if a.kind == "orbit"), 2.0)]


def test_zero_start_agrees_with_the_fixed_start_simulation(eta2_4):
    res = eta2_4
    np.testing.assert_array_equal(res.starts[0], 0.0)
    for i, eta in enumerate(res.values):
        ref = ssf.simulate(ASYM.replace(eta=eta), t_end=3000.0, t_transient=2000.0)
        att = res.attractor_of(i, 0)
        if ref.status == "ok":
            assert (att.kind, att.period) == ("orbit", ref.period)
            # the same orbit: ref's last point is one of the census points
            d = np.max(np.abs(att.points - ref.poincare[-1]), axis=1).min()
            assert d < 1e-5
        else:
            assert att.kind == ref.status == "equilibrium"
            np.testing.assert_allclose(att.points[0], ref.final_state, atol=1e-6)
    assert res.attractor_of(0, 0).kind == "orbit" and res.attractor_of(0, 0).period == 1
    assert res.attractor_of(1, 0).kind == "equilibrium"


def test_a_census_run_is_the_simulate_run_from_its_start(eta2_4):
    res = eta2_4
    j = 5
    stop = res.settings["stop"]  # the census's default stop rule: "converged"
    assert stop == "converged"
    one = ssf.simulate(ASYM.replace(eta=2.0), y0=res.starts[j], max_points=128, stop=stop, **KW)
    assert STATUS_NAMES[res.raw["status"][0, j]] == one.status
    assert res.period[0, j] == one.period
    k = res.raw["count"][0, j]
    np.testing.assert_array_equal(res.raw["points"][0, j, :k], one.poincare)
    np.testing.assert_array_equal(res.raw["final_state"][0, j], one.final_state)


def test_starts_are_seeded_in_the_default_box():
    box = default_box(ASYM, "eta", [2.0, 4.0])
    xs = ASYM.mu / (1 - ASYM.k12**2)
    d = 3.0 * ASYM.mu  # (eta_max - 1) mu
    np.testing.assert_allclose(box[0], [xs - d, xs + d])
    np.testing.assert_allclose(box[1], [-d, d])
    a = sample_starts(ASYM, 10, box, seed=3)
    b = sample_starts(ASYM, 10, box, seed=3)
    c = sample_starts(ASYM, 10, box, seed=4)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a[1:], c[1:])
    np.testing.assert_array_equal(a[0], 0.0)
    assert np.all((a[1:] >= box[:, 0]) & (a[1:] <= box[:, 1]))
    dc = default_box(ASYM.replace(drive="dc-motor"))
    assert dc.shape == (5, 2) and tuple(dc[4]) == (0.0, ASYM.vb0)


def _raw(n_values, n_starts, max_points=8, n_state=4):
    return {
        "points": np.full((n_values, n_starts, max_points, n_state), np.nan),
        "count": np.zeros((n_values, n_starts), dtype="i4"),
        "period": np.zeros((n_values, n_starts), dtype="i4"),
        "status": np.full((n_values, n_starts), STATUS_NAMES.index("nonfinite"), dtype="i1"),
        "final_state": np.full((n_values, n_starts, n_state), np.nan),
    }


def _set_orbit(raw, i, j, cycle, phase=0, repeats=3):
    """Store an orbit run: ``cycle`` (p, n) repeated, starting at ``phase`` of the cycle."""
    p = len(cycle)
    pts = np.array([cycle[(phase + k) % p] for k in range(repeats * p)])
    raw["points"][i, j, : len(pts)] = pts
    raw["count"][i, j] = len(pts)
    raw["period"][i, j] = p
    raw["status"][i, j] = STATUS_NAMES.index("ok")
    raw["final_state"][i, j] = pts[-1]


def _set_rest(raw, i, j, state, status="equilibrium"):
    raw["status"][i, j] = STATUS_NAMES.index(status)
    raw["final_state"][i, j] = state


def test_tracks_follow_a_smooth_branch_and_report_birth_and_death():
    """Constructed: orbit A (P1) and sliding E everywhere, orbit B (P2) on values 2..4."""
    n_v, n_s = 7, 5
    vals = np.linspace(1.0, 4.0, n_v)
    raw = _raw(n_v, n_s)
    for i in range(n_v):
        a = np.array([[0.1 + 0.01 * i, 0.0, 0.2, 0.01]])
        b = np.array([[-0.3, 0.0, -0.1 - 0.01 * i, 0.02], [0.4, 0.0, 0.05, -0.02]])
        e = np.array([0.136 + 0.001 * i, 0.0, 0.109, 0.0])
        _set_orbit(raw, i, 0, a)
        _set_rest(raw, i, 1, e)
        if 2 <= i <= 4:
            _set_orbit(raw, i, 2, b, phase=1)
            # same orbit, other phase and a difference below the identity tolerance
            _set_orbit(raw, i, 3, b + 1e-9, phase=0)
        else:
            _set_orbit(raw, i, 2, a + 1e-9)
            _set_rest(raw, i, 3, e + 1e-9)
        if i != 0:
            _set_orbit(raw, i, 4, a)  # start 4 failed at value 0
    labels, atts, tracks = classify_census(vals, raw, period_tol=1e-5)
    ida, ide = labels[0, 0], labels[0, 1]
    assert np.all(labels[:, 0] == ida) and np.all(labels[:, 1] == ide) and ida != ide
    idb = labels[2, 2]
    assert idb not in (ida, ide)
    np.testing.assert_array_equal(labels[2:5, 2], idb)
    np.testing.assert_array_equal(labels[2:5, 3], idb)
    assert labels[0, 4] == -1 and np.all(labels[1:, 4] == ida)
    tb = tracks[idb]
    assert (tb.kind, tb.birth, tb.death, tb.born, tb.dies) == ("orbit", 2, 4, True, True)
    assert tb.periods == (2,)
    for t in (tracks[ida], tracks[ide]):
        assert (t.birth, t.death, t.born, t.dies) == (0, n_v - 1, False, False)
    assert len(tracks) == 3
    # fractions: value 0 has A 2/5, E 2/5 and one failed start
    f0 = {a.id: a.fraction for a in atts[0]}
    assert f0 == {ida: 0.4, ide: 0.4}
    # B's points begin at its smallest x1, whatever the phase the run ended in
    b_att = next(a for a in atts[3] if a.id == idb)
    assert b_att.points[0, 0] == -0.3 and b_att.period == 2 and b_att.fraction == 0.4
    # a distinct orbit of the same period, further away than the identity tolerance
    raw2 = _raw(1, 2)
    _set_orbit(raw2, 0, 0, np.array([[0.1, 0.0, 0.2, 0.0]]))
    _set_orbit(raw2, 0, 1, np.array([[0.1 + 1e-2, 0.0, 0.2, 0.0]]))
    lab2, _, _ = classify_census(np.array([1.0]), raw2, period_tol=1e-5)
    assert lab2[0, 0] != lab2[0, 1]


def test_identical_across_threads_chunks_file_and_resume(tmp_path):
    vals = np.array([2.0, 3.0, 7.0])
    kw = dict(n_starts=5, seed=7, t_end=300.0, t_transient=150.0, max_points=32, progress=False)
    ref = census(ASYM, "eta", vals, threads=1, chunk_size=1, **kw)
    a = census(ASYM, "eta", vals, threads=2, chunk_size=4, out=tmp_path / "a.h5", **kw)
    _same(ref, a)
    b = census(ASYM, "eta", vals, threads=2, out=tmp_path / "b.h5", **kw)
    _same(ref, b)
    # a partly written file (runs lost in flight) resumes to the same result
    with h5py.File(tmp_path / "b.h5", "r+") as h5:
        h5["done"][1:, 2:] = 0
        h5["points"][1:, 2:] = 123.0
        h5["label"][...] = -2
    mid = load_census(tmp_path / "b.h5")
    assert np.all(mid.labels[1:, 2:] == -1) and np.all(mid.status[1:, 2:] == "missing")
    c = census(ASYM, "eta", vals, threads=1, chunk_size=3, out=tmp_path / "b.h5", **kw)
    _same(ref, c)
    with h5py.File(tmp_path / "b.h5", "r") as h5:
        np.testing.assert_array_equal(h5["label"][...], ref.labels)
        assert h5.attrs["classified"] == 1
        assert h5["attractors/fraction"].shape == (sum(len(x) for x in ref.attractors),)


def test_killed_census_resumes_to_the_same_file(tmp_path):
    vals = np.linspace(5.0, 10.0, 8)
    kw = dict(n_starts=4, t_end=3000.0, t_transient=2000.0, max_points=16)
    full = tmp_path / "full.h5"
    census(ASYM, "eta", vals, out=full, chunk_size=2, threads=1, progress=False, **kw)
    part = tmp_path / "part.h5"
    script = textwrap.dedent(
        f"""
        import sys, numpy as np
        sys.path.insert(0, {ROOT!r})
        import stickslip_fast as ssf
        ssf.census(ssf.System.preset("asymmetric"), "eta", np.linspace(5.0, 10.0, 8),
                   out={str(part)!r}, chunk_size=2, threads=1, progress=False, **{kw!r})
        """
    )
    n_done = kill_after(script, part, 6)
    assert 0 < n_done < 32, "the census was not killed mid-run"
    census(ASYM, "eta", vals, out=part, chunk_size=5, threads=2, progress=False, **kw)
    with h5py.File(full, "r") as a, h5py.File(part, "r") as b:
        for name in ("label", *RAW):
            np.testing.assert_array_equal(a[name][...], b[name][...], err_msg=name)
        for name in ("track", "value_index", "fraction", "points"):
            np.testing.assert_array_equal(a["attractors"][name][...], b["attractors"][name][...])
        assert a.attrs["config"] == b.attrs["config"]
    with pytest.raises(ConfigMismatchError, match="n_starts"):
        census(ASYM, "eta", vals, out=part, progress=False, **{**kw, "n_starts": 5})


def kill_after(script: str, path, n_runs: int) -> int:
    """Run ``script`` in a subprocess, SIGKILL it once ``path`` has ``n_runs`` runs done.

    Returns the runs done in the file after the kill.
    """
    proc = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)
        try:
            with h5py.File(path, "r", libver="latest", swmr=True) as h5:
                if int(h5["done"][...].sum()) >= n_runs:
                    break
        except (OSError, KeyError):
            continue
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        return int(h5["done"][...].sum())


@pytest.mark.skipif(not HAVE_DASK, reason="dask[distributed] is not installed")
def test_dask_backend_is_bit_identical(tmp_path):
    vals = np.array([2.0, 7.0])
    kw = dict(n_starts=4, t_end=300.0, t_transient=150.0, max_points=32, progress=False)
    ref = census(ASYM, "eta", vals, **kw)
    res = census(ASYM, "eta", vals, backend="dask", n_workers=2, chunk_size=3,
                 out=tmp_path / "d.h5", **kw)  # fmt: skip
    _same(ref, res)


def test_file_reads_with_xarray(tmp_path, eta2_4):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    path = tmp_path / "c.h5"
    res = census(ASYM, "eta", [2.0, 4.0], n_starts=16, out=path, progress=False, **KW)
    _same(eta2_4, res)
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        assert ds.label.dims == ("eta", "start")
        np.testing.assert_array_equal(ds.label.values, res.labels)
    with xr.open_dataset(path, engine="h5netcdf", group="attractors") as ds:
        np.testing.assert_allclose(
            ds.fraction.values, [a.fraction for atts in res.attractors for a in atts]
        )
    with xr.open_dataset(path, engine="h5netcdf", group="tracks") as ds:
        assert list(ds.dies.values) == [t.dies for t in res.tracks]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(box=np.zeros((3, 2))), "box"),
        (dict(box=np.zeros(4)), "box"),
        (dict(n_starts=0), "n_starts"),
        (dict(n_starts=2.5), "n_starts"),
        (dict(starts=np.array([[0.0, np.nan, 0.0, 0.0]])), "starts"),
        (dict(starts=np.zeros((2, 5))), "starts"),
        (dict(seed=-1), "seed"),
        (dict(stop="sometimes"), "stop"),
        (dict(track_threshold=0.0), "track_threshold"),
        (dict(chunk_size=0), "chunk_size"),
    ],
)
def test_bad_input_is_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        census(ASYM, "eta", [2.0], t_end=10.0, progress=False, **kwargs)


def test_converged_stopping_gives_the_same_attractors(eta2_4):
    conv = eta2_4  # converged stopping is the census's default
    fixed = census(ASYM, "eta", [2.0, 4.0], n_starts=16, stop="fixed", progress=False, **KW)
    np.testing.assert_array_equal(conv.labels, fixed.labels)
    for a_list, b_list in zip(conv.attractors, fixed.attractors):
        assert [(a.id, a.kind, a.period, a.count) for a in a_list] == [
            (b.id, b.kind, b.period, b.count) for b in b_list
        ]
        for a, b in zip(a_list, b_list):
            np.testing.assert_allclose(a.points, b.points, atol=1e-5)
    t_conv = conv.raw["t_converged"]
    assert np.all(np.isfinite(t_conv)) and np.all(t_conv < KW["t_end"])
    assert conv.raw["n_steps"].sum() < fixed.raw["n_steps"].sum()


def test_a_lone_equilibrium_branch_is_one_track():
    """Steady sliding moving by round-off-sized steps stays one track (no spread to divide by)."""
    raw = _raw(5, 2)
    for i in range(5):
        for j in range(2):
            _set_rest(raw, i, j, [0.136 + 1e-9 * i, 0.0, 0.109, 0.0])
    labels, _, tracks = classify_census(np.arange(5.0), raw, period_tol=1e-5)
    assert np.all(labels == 0) and len(tracks) == 1


def test_cli_census_and_info(tmp_path, capsys, eta2_4):
    from stickslip_fast.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text(
        textwrap.dedent(
            """
            title = "census test"
            [system]
            preset = "asymmetric"
            [integration]
            t_end = 600.0
            t_transient = 300.0
            [census]
            param = "eta"
            values = [2.0, 4.0]
            n_starts = 16
            """
        )
    )
    out = tmp_path / "c.h5"
    assert main(["census", str(cfg), "-o", str(out), "--quiet"]) == 0
    np.testing.assert_array_equal(load_census(out).labels, eta2_4.labels)
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "(census)" in text and "32 of 32 runs done" in text and "orbit P1" in text
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import plot_bifurcation

    png = tmp_path / "c.png"
    assert plot_bifurcation.main([str(out), "-o", str(png)]) == 0
    assert png.stat().st_size > 10_000
    fig = plot_bifurcation.plot_census(load_census(out))
    assert len(fig.axes) == 3 and fig.axes[-1].get_ylim() == (0.0, 1.0)
    cfg.write_text(cfg.read_text().replace("n_starts = 16", "n_starts = 16\nstarts_box = 1"))
    assert main(["census", str(cfg), "-o", str(tmp_path / "d.h5")]) == 2
    assert "starts_box" in capsys.readouterr().err


def test_transitions_of_the_zero_start_are_classified():
    """Constructed: sliding E everywhere, orbit A on values 2..4; start 0 on A at 2..3 only."""
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import census_transitions

    from stickslip_fast.analysis.census import CensusResult

    n_v, n_s = 6, 3
    vals = np.arange(float(n_v))
    raw = _raw(n_v, n_s)
    e = [0.136, 0.0, 0.109, 0.0]
    a = np.array([[0.1, 0.0, 0.12, 0.0]])
    for i in range(n_v):
        _set_rest(raw, i, 1, e)
        for j, on_a in ((2, 2 <= i <= 4), (0, i in (2, 3))):
            if on_a:
                _set_orbit(raw, i, j, a)
            else:
                _set_rest(raw, i, j, e)
    labels, atts, tracks = classify_census(vals, raw, period_tol=1e-5)
    res = CensusResult("eta", vals, np.zeros((n_s, 4)), labels, raw["status"], raw["period"],
                       atts, tracks, ["x1", "dx1", "phi1", "dphi1"], ASYM, {})  # fmt: skip
    rows = census_transitions.transitions(res)
    assert [(r["from_value"], r["to_value"]) for r in rows] == [(1.0, 2.0), (3.0, 4.0)]
    assert rows[0]["new_born"] and not rows[0]["old_dies"]
    assert rows[0]["verdict"].startswith("bifurcation")
    assert not rows[1]["old_dies"] and not rows[1]["new_born"]
    assert rows[1]["verdict"].startswith("basin-boundary crossing")
    assert rows[1]["old_track"] == "goes on to 4"
