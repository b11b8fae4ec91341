"""The ``[basins.manifold]`` table of a basins config: parsing (errors name the key) and the run."""

import numpy as np
import pytest

from stickslip_fast.cli.config import ConfigError, parse_config

#: The unstable period-1 orbit past Fig. 6's upper fold (tests/test_basins_manifold.py).
FOLD_ETA = 3.323654117482133
FOLD_SADDLE = [0.07259114445455046, 0.0, 0.12216932570735764, -0.006665729137139496]


def _cfg(manifold, refine=True):
    basins = {"plane": ["x1", "phi1"], "g1": [0.0, 0.1], "g2": [0.0, 0.1]}
    if refine:
        basins["refine"] = {"tol": 1e-6}
    if manifold is not None:
        basins["manifold"] = manifold
    return {"system": {"preset": "asymmetric", "eta": FOLD_ETA}, "basins": basins}


def test_good_tables_are_accepted_with_defaults_filled():
    c = parse_config(_cfg({"point": FOLD_SADDLE})).basins["manifold"]
    assert c == {"point": FOLD_SADDLE, "period": 1, "seeds": "boundary", "ds": 1e-3,
                 "ds_min": 1e-7, "tol": 1e-11, "r_local": 1e-4, "n_max": 30,
                 "max_points": 400, "max_angle": 0.3}  # fmt: skip
    t = {"point": [0, 0, 0.1, 0], "period": 2, "seeds": "scan", "ds": 2e-3, "r_local": 1e-6,
         "n_max": 40, "skip_radius": 1, "rtol": 1e-11, "scan": {"grid": 8, "n_max": 12}}  # fmt: skip
    c = parse_config(_cfg(t, refine=False)).basins["manifold"]
    assert c["point"] == [0.0, 0.0, 0.1, 0.0] and c["period"] == 2 and c["seeds"] == "scan"
    assert c["ds"] == 2e-3 and c["n_max"] == 40 and isinstance(c["skip_radius"], float)
    assert c["rtol"] == 1e-11 and c["scan"] == {"grid": 8, "n_max": 12, "r_scan": 1e-2}
    c = parse_config(_cfg({"point": FOLD_SADDLE, "seeds": "scan"})).basins["manifold"]
    assert c["scan"] == {"r_scan": 1e-2}
    assert "manifold" not in parse_config(_cfg(None)).basins


@pytest.mark.parametrize(
    "table,match",
    [
        ({"point": FOLD_SADDLE, "colour": 1}, r"\[basins\.manifold\]\.colour"),
        ({"period": 1}, r"\[basins\.manifold\] needs 'point'"),
        ({"point": [0.0, 0.0, 0.1]}, r"\[basins\.manifold\]\.point must have 4"),
        ({"point": "saddle"}, r"\[basins\.manifold\]\.point must be a list"),
        ({"point": [0, 0, True, 0]}, r"\[basins\.manifold\]\.point must be a list"),
        ({"point": FOLD_SADDLE, "period": 1.5}, r"\[basins\.manifold\]\.period must be int"),
        ({"point": FOLD_SADDLE, "period": 0}, r"\[basins\.manifold\]\.period must be > 0"),
        ({"point": FOLD_SADDLE, "seeds": "grid"}, r"\[basins\.manifold\]\.seeds must be"),
        ({"point": FOLD_SADDLE, "ds": "1e-3"}, r"\[basins\.manifold\]\.ds must be float"),
        ({"point": FOLD_SADDLE, "ds": -1e-3}, r"\[basins\.manifold\]\.ds must be > 0"),
        ({"point": FOLD_SADDLE, "r_local": float("nan")}, r"\[basins\.manifold\]\.r_local"),
        ({"point": FOLD_SADDLE, "n_max": 4.0}, r"\[basins\.manifold\]\.n_max must be int"),
        ({"point": FOLD_SADDLE, "max_points": True}, r"\[basins\.manifold\]\.max_points"),
        ({"point": FOLD_SADDLE, "scan": {"grid": 8}}, r"\[basins\.manifold\]\.scan is an option"),
        ({"point": FOLD_SADDLE, "seeds": "scan", "scan": 8}, r"\[basins\.manifold\]\.scan must"),
        ({"point": FOLD_SADDLE, "seeds": "scan", "scan": {"size": 8}},
         r"\[basins\.manifold\.scan\]\.size"),
        ({"point": FOLD_SADDLE, "seeds": "scan", "scan": {"grid": 1}},
         r"\[basins\.manifold\.scan\]\.grid must be >= 2"),
        ({"point": FOLD_SADDLE, "seeds": "scan", "scan": {"r_scan": "big"}},
         r"\[basins\.manifold\.scan\]\.r_scan must be float"),
        ("point", r"\[basins\.manifold\] must be a table"),
    ],
)  # fmt: skip
def test_bad_keys_and_types_are_named(table, match):
    with pytest.raises(ConfigError, match=match):
        parse_config(_cfg(table))


def test_boundary_seeds_need_refine():
    with pytest.raises(ConfigError, match=r'\[basins\.manifold\]\.seeds = "boundary" needs'):
        parse_config(_cfg({"point": FOLD_SADDLE}, refine=False))
    parse_config(_cfg({"point": FOLD_SADDLE, "seeds": "scan"}, refine=False))  # no refine: ok


class _Result:
    """A stand-in BasinsResult (no file): what run_manifold reads of one."""

    path = None
    manifold = None

    def __init__(self, system):
        self.system = system


def test_runner_passes_the_table_to_stable_manifold(monkeypatch):
    import stickslip_fast.bifurcation.orbits as orbits
    import stickslip_fast.bifurcation.stable_manifold as sm
    from stickslip_fast.cli.basins_manifold import run_manifold

    class Orb:
        converged, status, message = True, "ok", ""
        multipliers = np.array([4.7, 1e-8, 1e-13])

    calls = {}

    def fake_find(system, start, period, **kw):
        calls["find"] = (system, list(start), period, kw)
        return Orb()

    class M:
        def __init__(self):
            self.settings = {}

    def fake_manifold(result, orbit, **kw):
        calls["manifold"] = (result, orbit, kw)
        return M()

    monkeypatch.setattr(orbits, "find_orbit", fake_find)
    monkeypatch.setattr(sm, "stable_manifold", fake_manifold)
    monkeypatch.setattr(sm, "store_manifold", lambda r, m: calls.setdefault("stored", m))
    cfg = parse_config(_cfg({"point": FOLD_SADDLE, "seeds": "scan", "period": 2, "ds": 2e-3,
                             "rtol": 1e-11, "scan": {"grid": 6}}, refine=False))  # fmt: skip
    res = _Result(cfg.system)
    m, computed = run_manifold(res, cfg.basins["manifold"])
    assert computed and calls["stored"] is m
    assert calls["find"] == (cfg.system, FOLD_SADDLE, 2, {"rtol": 1e-11})
    r, orb, kw = calls["manifold"]
    assert r is res and isinstance(orb, Orb)
    assert kw == {"store": False, "checkpoint": None, "seeds": "scan", "scan": {"grid": 6, "r_scan": 1e-2},
                  "ds": 2e-3, "ds_min": 1e-7, "tol": 1e-11, "r_local": 1e-4, "n_max": 30,
                  "max_points": 400, "max_angle": 0.3, "rtol": 1e-11}  # fmt: skip
    assert m.settings["config"]["manifold"]["period"] == 2
    # boundary seeds: the library's default (the refined boundary); refine in the fingerprint
    cfg = parse_config(_cfg({"point": FOLD_SADDLE}))
    m, _ = run_manifold(res, cfg.basins["manifold"], {"tol": 1e-6})
    assert "seeds" not in calls["manifold"][2] and "scan" not in calls["manifold"][2]
    assert m.settings["config"]["refine"] == {"tol": 1e-6}
    # a stable orbit, or one that does not converge, is refused naming the point
    Orb.multipliers = np.array([0.5, 1e-8, 1e-13])
    with pytest.raises(ConfigError, match=r"\[basins\.manifold\]\.point: .*stable orbit"):
        run_manifold(res, cfg.basins["manifold"])
    Orb.converged, Orb.status = False, "max-iter"
    with pytest.raises(ConfigError, match=r"\[basins\.manifold\]\.point: .*did not converge"):
        run_manifold(res, cfg.basins["manifold"])


def test_cli_traces_the_fold_saddles_manifold_and_keeps_it_on_a_rerun(tmp_path, capsys):
    # a 3 x 3 map around a piece of the fold saddle's manifold (tests/test_basins_seeds.py),
    # seeds from the scan of the map's own grid
    import stickslip_fast as ssf
    from stickslip_fast.cli import main

    seed = [0.0677029, -0.14516129]
    g = [{"start": c - 1e-3, "stop": c + 1e-3, "num": 3} for c in seed]
    cfg = tmp_path / "m.toml"
    cfg.write_text(
        f'[system]\npreset = "asymmetric"\neta = {FOLD_ETA!r}\n'
        f'[basins]\nplane = ["x1", "phi1"]\nentropy_box = 3\n'
        f"g1 = {{ start = {g[0]['start']!r}, stop = {g[0]['stop']!r}, num = 3 }}\n"
        f"g2 = {{ start = {g[1]['start']!r}, stop = {g[1]['stop']!r}, num = 3 }}\n"
        f'[basins.manifold]\npoint = {FOLD_SADDLE!r}\nseeds = "scan"\n'
        "ds = 4e-4\nr_local = 1e-6\nn_max = 12\nmax_points = 2\n"
    )
    out = tmp_path / "m.h5"
    assert main(["basins", str(cfg), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "manifold:" in text and "period-1 saddle (|mu| 4.713" in text and "seeds: scan" in text
    m = ssf.load_basins(out).manifold
    assert len(m.u) >= 2 and np.all(m.distance <= 1e-6)
    assert m.settings["seeds"] == "scan" and m.settings["config"]["manifold"]["n_max"] == 12
    assert not (tmp_path / "m.h5.checkpoint").exists()  # removed once the curve is stored
    # the same config again: the stored curve is kept
    assert main(["basins", str(cfg), "-o", str(out)]) == 0
    assert "stored for the same settings; not recomputed" in capsys.readouterr().out
    np.testing.assert_array_equal(ssf.load_basins(out).manifold.uv, m.uv)
