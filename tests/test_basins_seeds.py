"""Seeds for the stable-manifold tracer from a saddle alone (scan_seeds, manifold_seeds).

On the maps of tests/test_basins_manifold.py, conjugate to a linear saddle with the
known stable manifold x = A y^2 + B z^2: a coarse grid's sign changes of g_n give seeds
on the known curve (parabola, closed ellipse) to 1e-10, and tracing from them gives the
curve traced from a hand-given seed; a plane that misses the manifold gives no seed.
For the model: the P1 saddle past Fig. 6's upper fold, on a 4 x 4 grid around a piece of
its manifold, and seeds="scan" on a 3 x 3 basin map's own grid with the result stored in
its file. Cost on the shared 2-core VM: 1-8 s for each map test; 7 s and 4 s for the model
tests once the orbit and census kernels are compiled (the fixture of test_basins_manifold).
"""

import shutil

import h5py
import numpy as np
import pytest
from test_basins_manifold import SADDLE, A, B, E, fold_saddle, plane_crossings_of

import stickslip_fast as ssf
from stickslip_fast.analysis.basins_manifold import trace_manifold
from stickslip_fast.analysis.basins_seeds import scan_seeds

__all__ = ["fold_saddle"]  # the model fixture, shared with test_basins_manifold

G = np.linspace(-1.0, 1.0, 21)
BOX = [[-1, 1], [-1, 1]]


def test_scan_seeds_lie_on_the_parabola_and_trace_the_same_curve():
    cr = plane_crossings_of(np.array([0.0, 0.0, 0.3]), E[0], E[1])
    s = scan_seeds(cr, SADDLE, G, G, r_scan=1e-2, r_local=1e-4, tol=1e-13, n_max=30)
    u, v = s["uv"].T
    # the parabola x = A y^2 + B 0.09 crosses 37 edges of the 21 x 21 grid; each gives a seed
    assert s["edge_status"] == ["seed"] * 37 and len(u) == 37
    assert np.max(np.abs(u - (A * v**2 + B * 0.09))) < 1e-10
    assert np.all(s["distance"] <= 1e-4) and np.all(s["n"] <= 30)
    kw = dict(ds=0.02, tol=1e-13, r_local=1e-4)
    # skip_radius: a quarter of the grid's spacing, as stable_manifold(seeds="scan") sets it
    scanned = trace_manifold(cr, SADDLE, s["uv"], BOX, skip_radius=0.025, **kw)
    hand = trace_manifold(cr, SADDLE, [[0.2, 0.1]], BOX, **kw)
    # one seed traces the curve from edge to edge; the others lie on it and are skipped
    assert scanned["seed_status"] == ["traced"] + ["skipped"] * 36
    assert scanned["branch_status"] == hand["branch_status"] == ["box", "box"]
    for r in (scanned, hand):
        uu, vv = r["uv"].T
        assert np.max(np.abs(uu - (A * vv**2 + B * 0.09))) < 1e-10
        assert vv.max() > 1 - 1e-3 and vv.min() < -1 + 1e-3
    # the same curve: both are the parabola (above) over the same stretch, v from -1 to 1
    # without gaps wider than the largest step (ds_max = 20 ds)
    for r in (scanned, hand):
        assert np.max(np.diff(np.sort(r["uv"][:, 1]))) <= 0.4
    assert np.abs(scanned["uv"][:, 1].min() - hand["uv"][:, 1].min()) < 1e-3
    assert np.abs(scanned["uv"][:, 1].max() - hand["uv"][:, 1].max()) < 1e-3


def test_scan_seeds_on_the_closed_ellipse():
    cr = plane_crossings_of(np.array([0.2, 0.0, 0.0]), E[1], E[2])
    s = scan_seeds(cr, SADDLE, G, G, r_scan=1e-2, r_local=1e-4, tol=1e-13)
    y, z = s["uv"].T
    assert len(y) >= 40 and np.max(np.abs(A * y**2 + B * z**2 - 0.2)) < 1e-10
    # the 4 edges with an end on the ellipse's vertices (y = +-0.5, z = 0), where the
    # grid line touches the curve, give no root
    assert s["edge_status"].count("no-root") == 4
    ang = np.sort(np.arctan2(z / np.sqrt(0.2 / B), y / np.sqrt(0.2 / A)))
    assert np.max(np.diff(np.r_[ang, ang[0] + 2 * np.pi])) < 0.5  # all the way round
    r = trace_manifold(cr, SADDLE, s["uv"], BOX, ds=0.02, tol=1e-13, r_local=1e-4,
                       skip_radius=0.025)  # fmt: skip
    assert r["branch_status"] == ["closed"] and r["seed_status"].count("traced") == 1
    yy, zz = r["uv"].T
    assert np.max(np.abs(A * yy**2 + B * zz**2 - 0.2)) < 1e-10


def test_no_seed_where_the_plane_misses_the_manifold():
    # the plane x = -0.2 does not meet the paraboloid x = A y^2 + B z^2 >= 0
    cr = plane_crossings_of(np.array([-0.2, 0.0, 0.0]), E[1], E[2])
    s = scan_seeds(cr, SADDLE, G, G)
    assert s["uv"].shape == (0, 2) and s["edge_status"] == []
    assert s["n_evals"] == G.size**2 and np.all(s["closest"] > 0.19)


def test_scan_refuses_bad_arguments():
    cr = plane_crossings_of(np.zeros(3), E[0], E[1])
    with pytest.raises(ValueError, match="g1 must be"):
        scan_seeds(cr, SADDLE, [0.0, 0.0, 1.0], G)
    with pytest.raises(ValueError, match="g2 must be"):
        scan_seeds(cr, SADDLE, G, [0.5])
    for kw, name in (({"n_max": 0}, "n_max"), ({"period": 1.5}, "period"),
                     ({"r_scan": 0.0}, "r_scan"), ({"r_local": np.nan}, "r_local"),
                     ({"tol": -1.0}, "tol")):  # fmt: skip
        with pytest.raises(ValueError, match=name):
            scan_seeds(cr, SADDLE, G, G, **kw)


# ------------------------------------------------------------------ the model
SEED = np.array([0.0677029, -0.14516129])  # a refined boundary point of the fold's 32 x 32 map


def test_model_scan_finds_the_fold_saddles_manifold(fold_saddle):
    s = fold_saddle.system
    box = np.stack([SEED - 1e-3, SEED + 1e-3], axis=1)
    common = dict(plane=("x1", "phi1"), bounds=box)
    with pytest.raises(ValueError, match="grid must be"):
        ssf.manifold_seeds(s, fold_saddle, grid=1, **common)
    with pytest.raises(ValueError, match="seeds must be"):
        ssf.stable_manifold(s, fold_saddle, seeds="grid", **common)
    trace = dict(ds=4e-4, r_local=1e-6, n_max=12, max_points=3)
    m = ssf.stable_manifold(s, fold_saddle, seeds="scan", scan=dict(grid=4), **common, **trace)
    sc = m.settings["scan"]
    assert m.settings["seeds"] == "scan" and sc["seeds"] >= 1 and sc["grid"] == [4, 4]
    assert "traced" in m.settings["seed_status"] and len(m.u) >= 4
    assert np.all(m.distance <= 1e-6) and np.all(m.residual < 1e-9)
    hand = ssf.stable_manifold(s, fold_saddle, seeds=[SEED], **common, **trace)
    assert "seeds" not in hand.settings and "scan" not in hand.settings  # default: as before
    # the 9 sign-change edges of the 4 x 4 grid all give seeds; the traced points lie on
    # two pieces of W^s: the hand-seeded one (within 1e-7 of its curve) and the second
    # piece bounding the P1 tongue, ~8e-5 from it in this box
    assert sc["edges"] == 9 and sc["edge_status"] == {"seed": 9}
    d = hand.distance_to(m.uv)
    assert np.sum(d < 1e-7) >= 2 and np.sum((d > 2e-5) & (d < 2e-4)) >= 2


def test_model_scan_on_a_maps_own_grid_is_stored_in_its_file(fold_saddle, tmp_path):
    # seeds="scan" on a BasinsResult scans the map's own grid; the summary goes to the file
    s = fold_saddle.system
    g1 = np.linspace(SEED[0] - 1e-3, SEED[0] + 1e-3, 3)
    g2 = np.linspace(SEED[1] - 1e-3, SEED[1] + 1e-3, 3)
    res = ssf.basins(s, (g1, g2), out=tmp_path / "b.h5", progress=False, entropy_box=3)
    m = ssf.stable_manifold(res, fold_saddle, seeds="scan", ds=4e-4, r_local=1e-6, n_max=12,
                            max_points=2)  # fmt: skip
    sc = m.settings["scan"]
    assert sc["grid"] == [3, 3] and sc["seeds"] >= 1 and len(m.u) >= 2
    assert m.settings["skip_radius"] == pytest.approx(0.25 * 1e-3)
    back = ssf.load_basins(tmp_path / "b.h5").manifold
    assert back.settings == m.settings and back.settings["seeds"] == "scan"
    np.testing.assert_array_equal(back.uv, m.uv)


def test_a_second_trace_uses_the_scan_stored_in_the_file(fold_saddle, tmp_path, monkeypatch):
    # the scan (82 s on the fold map of docs/basins.md) is kept in /basins/manifold_scan
    # and used again, bit for bit, by a later trace with the same saddle, plane, scan
    # arguments and tolerances; other scan arguments scan again (and replace it)
    from stickslip_fast.bifurcation import stable_manifold as sm
    from stickslip_fast.cli.basins import basins_report
    from stickslip_fast.io.basins_extras import read_manifold_scan

    s = fold_saddle.system
    g1 = np.linspace(SEED[0] - 1e-3, SEED[0] + 1e-3, 3)
    g2 = np.linspace(SEED[1] - 1e-3, SEED[1] + 1e-3, 3)
    res = ssf.basins(s, (g1, g2), out=tmp_path / "b.h5", progress=False, entropy_box=3)
    shutil.copy(tmp_path / "b.h5", tmp_path / "c.h5")  # a map with no scan stored
    scans = []
    real = sm.manifold_seeds
    monkeypatch.setattr(sm, "manifold_seeds", lambda *a, **k: scans.append(k) or real(*a, **k))
    kw = dict(seeds="scan", ds=4e-4, r_local=1e-6, n_max=12)
    first = ssf.stable_manifold(res, fold_saddle, max_points=2, **kw)
    assert len(scans) == 1
    with h5py.File(tmp_path / "b.h5", "r") as h5:
        key = h5["basins/manifold_scan"].attrs["key"]
    stored = read_manifold_scan(tmp_path / "b.h5", key)
    fresh = real(res, fold_saddle, r_local=1e-6, n_max=12)
    # `stickslip-fast info` says it is there
    line = [x for x in basins_report(tmp_path / "b.h5").splitlines() if x.startswith("seed scan:")]
    sc = first.settings["scan"]
    assert line == [f"seed scan: 3 x 3 nodes, {sc['seeds']} seeds from {sc['edges']} sign-change "
                    f"edges, {sc['n_evals']} evaluations; stored, so a trace of the same saddle "
                    "with the same scan settings reads it"]  # fmt: skip
    assert stored.keys() == fresh.keys()
    for name in fresh:
        np.testing.assert_array_equal(stored[name], fresh[name], err_msg=name)
    # the same scan, a longer trace: no scan, and the same curve as a fresh run
    again = ssf.stable_manifold(ssf.load_basins(tmp_path / "b.h5"), fold_saddle, max_points=3,
                                **kw)  # fmt: skip
    assert len(scans) == 1 and again.settings["scan"] == first.settings["scan"]
    other = ssf.load_basins(tmp_path / "c.h5")
    alone = ssf.stable_manifold(other, fold_saddle, max_points=3, store=False, **kw)
    assert len(scans) == 2  # no scan in that file, and store=False writes none
    np.testing.assert_array_equal(again.uv, alone.uv)
    assert again.settings == alone.settings
    with h5py.File(tmp_path / "c.h5", "r") as h5:
        assert "manifold_scan" not in h5["basins"] and "manifold" not in h5["basins"]
    # another r_scan is another scan, and it replaces the stored one
    ssf.stable_manifold(res, fold_saddle, max_points=2, scan={"r_scan": 2e-2}, **kw)
    assert len(scans) == 3 and read_manifold_scan(tmp_path / "b.h5", key) is None
    # a rewrite of the map's /basins group keeps the scan
    ssf.basins(s, (g1, g2), out=tmp_path / "b.h5", progress=False, entropy_box=3)
    with h5py.File(tmp_path / "b.h5", "r") as h5:
        assert "manifold_scan" in h5["basins"]
    # another version of the package may scan otherwise: it scans again
    again = dict(kw, scan={"r_scan": 2e-2})
    ssf.stable_manifold(res, fold_saddle, max_points=2, **again)
    assert len(scans) == 3
    monkeypatch.setattr(sm, "package_version", lambda: "99.0")
    ssf.stable_manifold(res, fold_saddle, max_points=2, **again)
    assert len(scans) == 4
