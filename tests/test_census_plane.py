"""The census over a plane of two parameters: rows and columns equal one-parameter censuses.

Also: tracks across neighbouring cells (constructed runs), the maps, bit-identical
results across threads, chunk sizes and a resumed file, and bad input.
"""

from __future__ import annotations

import os
import sys
import textwrap

import h5py
import numpy as np
import pytest
from test_census import HAVE_DASK, RAW, _raw, _set_orbit, _set_rest, kill_after

import stickslip_fast as ssf
from stickslip_fast.analysis.census import census, default_box, load_census, sample_starts
from stickslip_fast.analysis.census_classify import classify_census
from stickslip_fast.analysis.census_plane import classify_plane
from stickslip_fast.cli.config import ConfigError, load_config, parse_config
from stickslip_fast.io import ConfigMismatchError

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASYM = ssf.System.preset("asymmetric")
PARAMS = ("eta", "k12")
# the anchors: at (3.5, -0.7) the period-1 orbit and steady sliding share the
# starts; at (3.5, -0.8) only steady sliding is left (t_end as the Fig. 6 census's)
AXES = (np.array([2.0, 3.5]), np.array([-0.8, -0.7]))
KW = dict(t_end=3000.0, t_transient=2000.0, progress=False)
STARTS = sample_starts(ASYM, 8, default_box(ASYM, PARAMS, AXES), seed=1)


@pytest.fixture(scope="module")
def plane():
    return census(ASYM, PARAMS, AXES, starts=STARTS, **KW)


def _same_cell(plane_atts, plane_labels, one_atts, one_labels):
    """One cell of the plane and of a 1-D census: the same partition of the starts."""
    pairs = set(zip(plane_labels.tolist(), one_labels.tolist()))
    assert len(pairs) == len({p for p, _ in pairs}) == len({q for _, q in pairs})  # a bijection
    key = {q: p for p, q in pairs}
    mine = {a.id: (a.kind, a.period, a.fraction, a.count, a.first_start) for a in plane_atts}
    for a in one_atts:
        assert mine[key[a.id]] == (a.kind, a.period, a.fraction, a.count, a.first_start)
        np.testing.assert_array_equal(next(b for b in plane_atts if b.id == key[a.id]).points,
                                      a.points)  # fmt: skip
    assert len(plane_atts) == len(one_atts)


def test_the_anchors_and_the_maps(plane):
    assert plane.labels.shape == (2, 2, 8) and plane.status.shape == (2, 2, 8)
    sliding_only = plane.attractors[1][0]  # (3.5, -0.8)
    assert [(a.kind, a.fraction) for a in sliding_only] == [("equilibrium", 1.0)]
    shared = {a.kind: a for a in plane.attractors[1][1]}  # (3.5, -0.7)
    assert set(shared) == {"orbit", "equilibrium"} and shared["orbit"].period == 1
    assert 0.25 <= shared["orbit"].fraction <= 0.75
    assert shared["orbit"].fraction + shared["equilibrium"].fraction == 1.0
    np.testing.assert_array_equal(plane.n_attractors()[1], [1, 2])
    sl = plane.sliding_fraction()
    assert sl[1, 0] == 1.0 and sl[1, 1] == shared["equilibrium"].fraction
    dom = plane.dominant_period()
    assert dom[1, 0] == 0 and dom[1, 1] == (1 if shared["orbit"].fraction > 0.5 else 0)
    np.testing.assert_allclose(plane.fractions().sum(axis=2) + plane.failed_fraction, 1.0)
    assert plane.attractor_of(1, 0, 0).kind == "equilibrium"


def test_rows_and_columns_equal_one_parameter_censuses(plane):
    for i, eta in enumerate(AXES[0]):  # a row: k12 varies at fixed eta
        row = census(ASYM.replace(eta=eta), "k12", AXES[1], starts=STARTS, **KW)
        for name in RAW:
            np.testing.assert_array_equal(plane.raw[name][i], row.raw[name], err_msg=name)
        for j in range(2):
            _same_cell(plane.attractors[i][j], plane.labels[i, j], row.attractors[j], row.labels[j])
        # a plane of one row is classified exactly as the one-parameter census, ids included
        runs = {k: row.raw[k] for k in ("points", "count", "period", "status", "final_state")}
        labels, atts, _ = classify_plane((1, 2), runs, period_tol=row.settings["period_tol"])
        np.testing.assert_array_equal(labels[0], row.labels)
    for j, k12 in enumerate(AXES[1]):  # a column: eta varies at fixed k12
        col = census(ASYM.replace(k12=k12), "eta", AXES[0], starts=STARTS, **KW)
        for name in RAW:
            np.testing.assert_array_equal(plane.raw[name][:, j], col.raw[name], err_msg=name)
        for i in range(2):
            _same_cell(plane.attractors[i][j], plane.labels[i, j], col.attractors[i], col.labels[i])


def test_tracks_join_neighbouring_cells_never_two_attractors_of_one_cell():
    """Constructed 2 x 2 plane: A everywhere, sliding E everywhere, and a loop that must not close."""
    raw = _raw(4, 3)
    for c in range(4):  # cells (0,0) (0,1) (1,0) (1,1)
        _set_orbit(raw, c, 0, np.array([[0.1 + 0.001 * c, 0.0, 0.2, 0.01]]))
        _set_rest(raw, c, 1, np.array([0.136 + 0.001 * c, 0.0, 0.109, 0.0]))
    labels, atts, tracks = classify_plane((2, 2), raw, period_tol=1e-5)
    assert np.all(labels[..., 0] == labels[0, 0, 0]) and np.all(labels[..., 1] == labels[0, 0, 1])
    assert [(t.kind, t.n_cells, t.extent) for t in tracks] == [
        ("orbit", 4, (0, 1, 0, 1)), ("equilibrium", 4, (0, 1, 0, 1))]  # fmt: skip
    assert np.all(labels[..., 2] == -1) and atts[1][1][0].fraction == 1 / 3
    # x1 alone varies (spread 1): X = 0, Y = 1 in cell (0,0); Z = 0.1 in (0,1);
    # W = 0.55 in (1,0); V = 0.2 in (1,1). Closest first: X-Z, Z-V (0.1), V-W (0.35)
    # join X, Z, V, W; W-Y (0.45) would put X and Y of cell (0,0) in one track: refused
    raw = _raw(4, 2)
    for c, j, x in ((0, 0, 0.0), (0, 1, 1.0), (1, 0, 0.1), (2, 0, 0.55), (3, 0, 0.2)):
        _set_orbit(raw, c, j, np.array([[x, 0.0, 0.2, 0.01]]))
    labels, _, tracks = classify_plane((2, 2), raw, period_tol=1e-5, track_threshold=0.5)
    x_id, y_id = labels[0, 0]
    assert x_id != y_id
    assert labels[0, 1, 0] == labels[1, 0, 0] == labels[1, 1, 0] == x_id
    assert tracks[x_id].n_cells == 4 and tracks[y_id].n_cells == 1
    # on one row the plane's matching is the one-parameter census's, ids included
    row = {k: v[:2] for k, v in raw.items()}
    lab1, _, _ = classify_census(np.arange(2.0), row, period_tol=1e-5, track_threshold=0.5)
    lab2, _, _ = classify_plane((1, 2), row, period_tol=1e-5, track_threshold=0.5)
    np.testing.assert_array_equal(lab2[0], lab1)


def test_identical_across_threads_chunks_and_a_resumed_file(tmp_path):
    axes = (np.array([2.0, 3.0]), np.array([-0.8, -0.75, -0.7]))
    kw = dict(n_starts=4, seed=5, t_end=300.0, t_transient=150.0, max_points=32, progress=False)
    ref = census(ASYM, PARAMS, axes, threads=1, chunk_size=1, **kw)
    a = census(ASYM, PARAMS, axes, threads=2, chunk_size=5, out=tmp_path / "a.h5", **kw)
    for name in RAW:
        np.testing.assert_array_equal(a.raw[name], ref.raw[name], err_msg=name)
    np.testing.assert_array_equal(a.labels, ref.labels)
    # an interrupted writer: runs lost in flight (done not set), the classification not written
    with h5py.File(tmp_path / "a.h5", "r+") as h5:
        assert h5["points"].shape == (2, 3, 4, 32, 4) and h5.attrs["param2"] == "k12"
        h5["done"][1, 1:, 2:] = 0
        h5["points"][1, 1:, 2:] = 123.0
        h5["label"][...] = -2
        h5.attrs["classified"] = 0
    mid = load_census(tmp_path / "a.h5")
    assert np.all(mid.labels[1, 1:, 2:] == -1) and np.all(mid.status[1, 1:, 2:] == "missing")
    b = census(ASYM, PARAMS, axes, threads=2, chunk_size=3, out=tmp_path / "a.h5", **kw)
    for name in RAW:
        np.testing.assert_array_equal(b.raw[name], ref.raw[name], err_msg=name)
    np.testing.assert_array_equal(b.labels, ref.labels)
    with h5py.File(tmp_path / "a.h5", "r") as h5:
        np.testing.assert_array_equal(h5["label"][...], ref.labels)
        assert h5.attrs["classified"] == 1
        n_att = sum(len(c) for row in ref.attractors for c in row)
        assert h5["attractors/value_index2"].shape == (n_att,)
        assert h5["tracks/n_cells"][...].tolist() == [t.n_cells for t in ref.tracks]
    with pytest.raises(ConfigMismatchError, match="values_sha256"):
        census(ASYM, PARAMS, (axes[0], axes[1][:2]), out=tmp_path / "a.h5", **kw)


@pytest.mark.skipif(not HAVE_DASK, reason="dask[distributed] is not installed")
def test_dask_backend_is_bit_identical():
    axes = (np.array([2.0, 7.0]), np.array([-0.8, -0.7]))
    kw = dict(n_starts=3, t_end=300.0, t_transient=150.0, max_points=32, progress=False)
    ref = census(ASYM, PARAMS, axes, **kw)
    res = census(ASYM, PARAMS, axes, backend="dask", n_workers=2, chunk_size=5, **kw)
    for name in RAW:
        np.testing.assert_array_equal(res.raw[name], ref.raw[name], err_msg=name)
    np.testing.assert_array_equal(res.labels, ref.labels)


def test_bad_input_names_the_field():
    kw = dict(t_end=10.0, progress=False)
    with pytest.raises(ValueError, match="'etaa' cannot be swept"):
        census(ASYM, ("etaa", "k12"), ([2.0], [-0.8]), **kw)
    with pytest.raises(ValueError, match="values of a census over two params must be a pair"):
        census(ASYM, PARAMS, [2.0, 3.0], **kw)
    with pytest.raises(ValueError, match="values for 'k12' must be a non-empty 1-D"):
        census(ASYM, PARAMS, ([2.0], [[-0.8, -0.7]]), **kw)
    with pytest.raises(ValueError, match="must differ"):
        census(ASYM, ("eta", "eta"), ([2.0], [3.0]), **kw)
    with pytest.raises(ValueError, match="swept param 'eta' is invalid"):
        census(ASYM, PARAMS, ([0.5], [-0.8]), **kw)
    with pytest.raises(ValueError, match="starts must have shape"):
        census(ASYM, PARAMS, ([2.0], [-0.8]), starts=np.zeros((3, 5)), **kw)
    cfg = parse_config({"census": {"param": ["eta", "k12"], "values": [[1.0, 2.0], [-0.8]]}})
    assert cfg.census["param"] == PARAMS and len(cfg.census["values"][0]) == 2
    cfg = load_config(os.path.join(ROOT, "data", "maps", "census_plane_eta_k12.toml"))
    v1, v2 = cfg.census["values"]
    assert cfg.census["param"] == PARAMS and (v1.size, v2.size) == (41, 33)
    assert 3.5 in v1 and np.min(np.abs(v2 + 0.7)) < 1e-15 and np.min(np.abs(v2 + 0.8)) < 1e-15
    assert os.path.exists(os.path.join(ROOT, "docs", "figures", "census_plane_eta_k12.png"))
    with pytest.raises(ConfigError, match=r"\[census\].values must be a list of two"):
        parse_config({"census": {"param": ["eta", "k12"], "values": [1.0, 2.0, 3.0]}})
    with pytest.raises(ConfigError, match=r"\[census\].param"):
        parse_config({"census": {"param": ["eta", "k12", "mu"], "values": [[1.0], [2.0]]}})


def test_a_killed_plane_census_resumes_to_the_same_file(tmp_path):
    axes = (np.linspace(5.0, 8.0, 4), np.array([-0.8, -0.7]))
    kw = dict(n_starts=4, t_end=3000.0, t_transient=2000.0, max_points=16, progress=False)
    full, part = tmp_path / "full.h5", tmp_path / "part.h5"
    census(ASYM, PARAMS, axes, out=full, chunk_size=2, threads=1, **kw)
    script = textwrap.dedent(
        f"""
        import sys, numpy as np
        sys.path.insert(0, {ROOT!r})
        import stickslip_fast as ssf
        ssf.census(ssf.System.preset("asymmetric"), ("eta", "k12"),
                   (np.linspace(5.0, 8.0, 4), np.array([-0.8, -0.7])),
                   out={str(part)!r}, chunk_size=2, threads=1, **{kw!r})
        """
    )
    n_done = kill_after(script, part, 8)
    assert 0 < n_done < 32, "the census was not killed mid-run"
    census(ASYM, PARAMS, axes, out=part, chunk_size=5, threads=2, **kw)
    with h5py.File(full, "r") as a, h5py.File(part, "r") as b:
        for name in ("label", *RAW):
            np.testing.assert_array_equal(a[name][...], b[name][...], err_msg=name)
        for name in ("track", "value_index", "value_index2", "fraction", "points"):
            np.testing.assert_array_equal(a["attractors"][name][...], b["attractors"][name][...])
        assert a.attrs["config"] == b.attrs["config"]


def test_the_command_line_the_summary_and_the_maps_script(plane, tmp_path, capsys):
    from stickslip_fast.cli import main

    cfg = tmp_path / "p.toml"
    starts = ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]" for row in STARTS)
    cfg.write_text(
        "[system]\npreset = 'asymmetric'\n[integration]\nt_end = 3000.0\nt_transient = 2000.0\n"
        "[census]\nparam = ['eta', 'k12']\nvalues = [[2.0, 3.5], [-0.8, -0.7]]\n"
        f"starts = [{starts}]\n"
    )
    out = tmp_path / "p.h5"
    for argv in (["census", str(cfg), "-o", str(out), "--quiet"], ["info", str(out)]):
        capsys.readouterr()
        assert main(argv) == 0
    text = capsys.readouterr().out
    np.testing.assert_array_equal(load_census(out).labels, plane.labels)
    n_mixed = int(np.sum((plane.sliding_fraction() > 0) & (plane.sliding_fraction() < 1)))
    assert "eta in [2, 3.5] (2) x k12 in [-0.8, -0.7] (2) cells x 8 starts" in text
    assert f"{n_mixed} depending on the start" in text and "orbit P1" in text
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import plot_census_plane

    png = tmp_path / "p.png"
    assert plot_census_plane.main([str(out), "-o", str(png)]) == 0
    assert png.stat().st_size > 10_000
