"""Trajectory files, sweep analyses and the plotting scripts (images from small HDF5 files)."""

import json
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.analysis import largest_lyapunov, sync_error
from stickslip_fast.cli.config import load_config
from stickslip_fast.io import (
    ConfigMismatchError,
    read_trajectory,
    read_trajectory_header,
    write_trajectory,
)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(ROOT, "scripts")
sys.path.insert(0, SCRIPTS)

import make_figures  # noqa: E402
import plot_bifurcation  # noqa: E402
import plot_timeseries  # noqa: E402

ASYM = ssf.System.preset("asymmetric")
TWO = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2)
Y0_TWO = [0, 0, 0, 0, 0.01, 0.01, 0.01, 0.01, 0]
KW = dict(t_end=400.0, t_transient=200.0, max_points=16)


# values without an orbit are expected here: silence sweep()'s summary warning
pytestmark = pytest.mark.filterwarnings("ignore:.*gave no orbit")


def _check_png(path):
    """A real, non-trivial image: PNG signature, > 5 kB, pixels that vary."""
    import matplotlib.image as mpimg

    with open(path, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    assert os.path.getsize(path) > 5000
    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[0] > 100 and img.shape[1] > 100
    assert float(img[..., :3].std()) > 0.02
    assert len(np.unique(img[..., :3].reshape(-1, 3), axis=0)) > 20


# ------------------------------------------------------------- trajectory files
def test_trajectory_roundtrip_and_xarray(tmp_path):
    res = ssf.simulate(ASYM.replace(eta=9.99), 600.0, 300.0, sample_dt=0.5)
    path = write_trajectory(tmp_path / "run.h5", res, {"title": "t"})
    back = read_trajectory(path)
    np.testing.assert_array_equal(back["t"], res.t)
    np.testing.assert_array_equal(back["y"], res.y)
    np.testing.assert_array_equal(back["poincare"], res.poincare)
    np.testing.assert_array_equal(back["t_poincare"], res.t_poincare)
    assert back["status"] == res.status and back["period"] == res.period
    assert back["system"] == res.system and back["title"] == "t"
    assert back["result"].n_steps == res.n_steps
    head = read_trajectory_header(path)  # the report's reader: no arrays
    assert (head["n_samples"], head["n_points"]) == (len(res.t), len(res.t_poincare))
    assert head["state_names"] == res.state_names and head["config"] == back["config"]
    with h5py.File(path, "r") as h5:
        assert h5.attrs["schema_version"] == 1 and h5.attrs["kind"] == "trajectory"
        assert json.loads(h5.attrs["config"])["settings"]["t_end"] == 600.0
        assert h5.attrs["package_version"]
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        assert ds["y"].dims == ("t", "state")
        assert list(ds["state"].values) == res.state_names
        np.testing.assert_array_equal(ds["t"].values, res.t)
        assert ds["poincare"].dims == ("crossing", "state")


def test_trajectory_without_samples_and_stalled(tmp_path):
    sym = ssf.System.preset("symmetric", drive="dc-motor", eta=9.99)
    # the motor comes to rest at t = 167.7: with t_end = 600 it has rested dwell by t_end
    res = ssf.simulate(sym, 600.0, 300.0)
    assert res.status == "stalled"
    back = read_trajectory(write_trajectory(tmp_path / "s.h5", res))
    assert back["t"].shape == (0,) and back["y"].shape == (0, 5)
    assert back["poincare"].shape == (0, 5) and back["status"] == res.status


def test_cli_simulate_writes_trajectory(tmp_path):
    cfg = tmp_path / "run.toml"
    cfg.write_text(
        'title = "cli run"\n[system]\npreset = "asymmetric"\neta = 9.99\n'
        "[integration]\nt_end = 400.0\nt_transient = 200.0\n[simulate]\nsample_dt = 0.25\n"
    )
    out = tmp_path / "run.h5"
    r = subprocess.run(
        [sys.executable, "-m", "stickslip_fast.cli", "simulate", str(cfg), "-o", str(out)],
        cwd=ROOT, capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    back = read_trajectory(out)
    assert back["title"] == "cli run"
    assert back["t"][1] - back["t"][0] == pytest.approx(0.25)
    assert back["config"]["source"]["system"]["eta"] == 9.99
    direct = ssf.simulate(ASYM.replace(eta=9.99), 400.0, 200.0, sample_dt=0.25)
    np.testing.assert_array_equal(back["poincare"], direct.poincare)


# ------------------------------------------------------------------ analyses
def test_sweep_sync_analysis_matches_direct_calls_and_changes_nothing(tmp_path):
    etas = np.array([1.5, 6.0, 8.0])
    plain = ssf.sweep(TWO, "eta", etas, y0=Y0_TWO, **KW)
    path = tmp_path / "sync.h5"
    res = ssf.sweep(TWO, "eta", etas, y0=Y0_TWO, analyses=("sync",), out=path, **KW)
    for f in ("points", "t_points", "period", "status_code", "final_state", "n_steps"):
        np.testing.assert_array_equal(getattr(plain, f), getattr(res, f))
    want = [sync_error(plain.points[i], 2) for i in range(len(etas))]
    np.testing.assert_array_equal(res.sync_error, want)
    np.testing.assert_array_equal(ssf.load_sweep(path).sync_error, want)
    with h5py.File(path, "r") as h5:
        assert h5["sync_error"].dims[0][0].name == "/eta"
        assert json.loads(h5.attrs["config"])["analyses"] == ["sync"]
    with pytest.raises(AttributeError):
        _ = plain.sync_error
    # the analyses list is part of the configuration: no silent mix on resume
    with pytest.raises(ConfigMismatchError, match="analyses"):
        ssf.sweep(TWO, "eta", etas, y0=Y0_TWO, out=path, **KW)
    with pytest.raises(ValueError, match="unknown analyses"):
        ssf.sweep(TWO, "eta", etas, analyses=("chaos",), **KW)


def test_sweep_lyapunov_analysis_matches_direct_calls():
    kw = dict(t_end=300.0, t_transient=150.0, max_points=8)
    etas = np.array([5.0, 9.99])
    res = ssf.sweep(ASYM, "eta", etas, analyses=("lyapunov",), **kw)
    for i, eta in enumerate(etas):
        ly = largest_lyapunov(ASYM.replace(eta=eta), 300.0, 150.0, rtol=1e-9, atol=1e-11)
        assert res.lyapunov[i] == ly.exponent
        assert res.lyapunov_fit[i] == ly.exponent_fit
    # continuation: each value's exponent is of its own trajectory (previous final state)
    cont = ssf.sweep(ASYM, "eta", etas, mode="continuation", analyses=("lyapunov",), **kw)
    ly = largest_lyapunov(ASYM.replace(eta=9.99), 300.0, 150.0, y0=cont.final_state[0],
                          rtol=1e-9, atol=1e-11)  # fmt: skip
    assert cont.lyapunov[1] == ly.exponent


# ------------------------------------------------------------------- plots
def test_plot_scripts_make_images_from_small_files(tmp_path):
    files = {}
    files["one"] = tmp_path / "one.h5"
    ssf.sweep(ASYM, "eta", np.linspace(1.0, 10.0, 6), out=files["one"], **KW)
    files["both"] = tmp_path / "both.h5"
    ssf.sweep(ASYM, "eta", np.linspace(5.0, 10.0, 4), mode="continuation-both",
              out=files["both"], **KW)  # fmt: skip
    files["map"] = tmp_path / "map.h5"
    ssf.sweep(ASYM, ("eta", "k12"), (np.linspace(1, 10, 4), np.linspace(-0.8, 0.0, 3)),
              out=files["map"], **KW)  # fmt: skip
    files["two"] = tmp_path / "two.h5"
    ssf.sweep(TWO, "eta", np.array([1.5, 8.0, 9.99]), y0=Y0_TWO, analyses=("sync",),
              out=files["two"], **KW)  # fmt: skip
    for name, path in files.items():
        png = tmp_path / f"{name}.png"
        assert plot_bifurcation.main([str(path), "-o", str(png), "--period"]) == 0
        _check_png(png)
    png = tmp_path / "vars.png"
    plot_bifurcation.plot_sweep(files["two"], png, ["x1", "x2"])
    _check_png(png)
    pdf = tmp_path / "one.pdf"
    plot_bifurcation.plot_sweep(files["one"], pdf, ["x1", "phi1"])
    assert pdf.read_bytes()[:4] == b"%PDF"
    with pytest.raises(ValueError, match="unknown variable"):
        plot_bifurcation.plot_sweep(files["one"], tmp_path / "x.png", ["x2"])

    run = tmp_path / "run.h5"
    write_trajectory(run, ssf.simulate(TWO.replace(eta=8.0), 400.0, 200.0, y0=Y0_TWO,
                                       sample_dt=0.05))  # fmt: skip
    png = tmp_path / "run.png"
    assert plot_timeseries.main([str(run), "-o", str(png)]) == 0
    _check_png(png)


def test_make_figures_quick_makes_one_file_per_figure(tmp_path):
    figures = {f.number for f in make_figures.FIGURES}  # the planes: the test below
    made = make_figures.make_figures(tmp_path, quick=True, only=figures, verbose=False)
    want = {f"{n:02d}" for n in (*range(2, 8), *range(9, 19))}
    assert set(made) == want
    assert sorted(p.name for p in tmp_path.glob("fig*.png")) == sorted(f"fig{n}.png" for n in want)
    for path in made.values():
        assert path.stat().st_size > 5000
    # every config in data/ is used
    used = {c for f in make_figures.FIGURES for c in f.configs}
    assert used == {p for p in os.listdir(os.path.join(ROOT, "data")) if p.startswith("fig")}
    load_config(os.path.join(ROOT, "data", sorted(used)[0]))


def test_make_figures_draws_the_census_planes_with_their_curves(tmp_path):
    from stickslip_fast.analysis.census import load_census

    made = make_figures.make_figures(tmp_path, quick=True, only={"eta_k12_folds"}, verbose=False)
    assert set(made) == {"eta_k12_folds"}
    _check_png(made["eta_k12_folds"])
    res = load_census(tmp_path / "data" / "census_plane_eta_k12_quick.h5")
    assert res.params == ("eta", "k12") and res.shape == (4, 4) and len(res.starts) == 4
    np.testing.assert_allclose(res.values[1], np.linspace(-0.95, -0.55, 4))
    # every census plane in data/maps/ is drawn, and every curve file laid over one exists
    used = {p.config for p in make_figures.PLANES}
    assert used == {p for p in os.listdir(os.path.join(ROOT, "data", "maps"))
                    if p.startswith("census_plane")}  # fmt: skip
    for plane in make_figures.PLANES:
        for name in plane.curves:
            assert os.path.exists(os.path.join(ROOT, "data", "curves", name)), name


def _fake_branch(system, period, values, stable, bifurcations=()):
    from stickslip_fast.bifurcation.continuation import Bifurcation, Branch

    n = system.n_state
    pts = np.zeros((values.size, n))
    pts[:, 0] = 0.05 + 0.01 * values  # x1 on the branch
    m = n if period == 0 else n - 1
    mult = np.full((values.size, m), 0.5 + 0j)
    mult[~stable, 0] = 1.5
    bifs = [Bifurcation(k, v, int(np.searchsorted(values, v)) - 1, np.r_[0.05 + 0.01 * v,
                                                                      np.zeros(n - 1)])
            for k, v in bifurcations]  # fmt: skip
    return Branch(system, "eta", period, values, pts, np.full(values.size, 6.0), mult, stable,
                  bifs, "bounds")  # fmt: skip


def test_branches_overlay_sweeps_and_censuses(tmp_path):
    from stickslip_fast.bifurcation.continuation import Branch

    sweep_file = tmp_path / "one.h5"
    ssf.sweep(ASYM, "eta", np.linspace(1.0, 10.0, 6), out=sweep_file, **KW)
    values = np.linspace(2.0, 3.0, 5)
    stable = np.array([True, True, True, False, False])
    orbit = _fake_branch(ASYM, 1, values, stable, [("fold", 2.6)])
    orbit_file = orbit.to_hdf5(tmp_path / "orbit.h5")
    eq_file = _fake_branch(ASYM, 0, values, np.ones(5, bool)).to_hdf5(tmp_path / "eq.h5")
    back = Branch.from_hdf5(orbit_file)
    assert back.bifurcations[0].kind == "fold" and back.bifurcations[0].value == 2.6
    png = tmp_path / "over.png"
    args = [str(sweep_file), "-o", str(png), "--branch", str(orbit_file), "--branch",
            str(eq_file), "--multipliers", "--period"]  # fmt: skip
    assert plot_bifurcation.main(args) == 0
    _check_png(png)
    # what is drawn: the stable run solid, the unstable run (from the last stable point) dashed
    data = plot_bifurcation.read_sweep(sweep_file)
    fig = plot_bifurcation.plot_bifurcation(data, ["x1"])
    plot_bifurcation.overlay_branches(fig, [orbit], "eta", data["state_names"], ["x1"],
                                      multiplier_panel=True)  # fmt: skip
    lines = [ln for ln in fig.axes[0].lines if ln.get_zorder() == 5]
    assert [ln.get_linestyle() for ln in lines] == ["-", "--"]
    np.testing.assert_array_equal(lines[0].get_xdata(), values[:4])
    np.testing.assert_array_equal(lines[1].get_xdata(), values[3:])
    assert [t.get_text() for t in fig.axes[0].texts] == ["F"]
    assert len(fig.axes) == 2  # the variable panel and the multiplier panel
    np.testing.assert_allclose(fig.axes[1].lines[0].get_ydata(), [0.5, 0.5, 0.5, 1.5, 1.5])
    plot_bifurcation.plt.close(fig)
    # on a census file too
    census_file = tmp_path / "census.h5"
    ssf.census(ASYM, "eta", [2.0, 4.0], n_starts=2, t_end=60.0, max_points=16, out=census_file,
               progress=False)  # fmt: skip
    png = tmp_path / "census.png"
    assert plot_bifurcation.main([str(census_file), "-o", str(png), "--branch",
                                  str(orbit_file)]) == 0  # fmt: skip
    _check_png(png)
    # refused: another parameter, another system, a 2-D map
    other = _fake_branch(ASYM, 1, values, stable)
    other.param = "k12"
    with pytest.raises(ValueError, match="continued in 'k12'"):
        plot_bifurcation.plot_sweep(sweep_file, tmp_path / "x.png",
                                    branches=[other.to_hdf5(tmp_path / "k.h5")])  # fmt: skip
    two = _fake_branch(TWO, 1, values, stable).to_hdf5(tmp_path / "two.h5")
    with pytest.raises(ValueError, match="state variables"):
        plot_bifurcation.plot_sweep(sweep_file, tmp_path / "x.png", branches=[two])
    map_file = tmp_path / "map.h5"
    ssf.sweep(ASYM, ("eta", "k12"), (np.linspace(1, 10, 2), np.linspace(-0.8, 0.0, 2)),
              out=map_file, **KW)  # fmt: skip
    with pytest.raises(ValueError, match="2-D"):
        plot_bifurcation.plot_sweep(map_file, tmp_path / "x.png", branches=[orbit_file])
