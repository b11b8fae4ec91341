"""TOML configs (errors name the key) and the command line."""

import glob
import json
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.cli import main
from stickslip_fast.cli.config import ConfigError, load_config, paper_order_to_state

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SMALL = """
title = "small"
[system]
preset = "asymmetric"
[integration]
t_end = 600.0
t_transient = 300.0
max_points = 8
[sweep]
param = "eta"
values = { start = 6.0, stop = 9.0, num = 4 }
"""


def _write(tmp_path, text, name="c.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    "text,match",
    [
        ("[sytem]\neta = 2.0", "sytem"),
        ("[system]\netta = 2.0", "etta"),
        ("[system]\neta = 12.0", "eta"),
        ("[system]\npreset = 'nope'", "preset"),
        ("[system]\ndrive = 'belt'", "drive"),
        ("[integration]\nt_end = 'long'", "t_end"),
        ("[integration]\nmax_points = 1.5", "max_points"),
        ("[integration]\nrtool = 1e-8", "rtool"),
        ("[initial]\ny0 = [0, 0, 0]", "y0"),
        ("[initial]\ny0_paper = [0, 0, 0]", "y0_paper"),
        ("[simulate]\nsample_dt = -1", "sample_dt"),
        ("[sweep]\nparam = 'eta'", "values"),
        ("[sweep]\nparam = 'eta'\nvalues = { start = 1, stop = 2 }", "values"),
        ("[sweep]\nparam = 'eta'\nvalues = [1, 2]\nchunk = 3", "chunk"),
        ("[sweep]\nparam = 'eta'\nvalues = [1, 2]\nchunk_size = 0", "chunk_size"),
        ("[system\neta = 2", "invalid TOML"),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nshooting = 'double'", "shooting"),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nsegments = 0", "segments"),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nmax_segments = 4", "max_segments.*>= 8"),
        (
            "[continue]\nparam = 'eta'\nbounds = [1, 2]\nsegments = 12\nmax_segments = 10",
            "max_segments.*>= 12",
        ),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nremesh = true", "remesh"),
        (
            "[continue]\nparam = 'eta'\nbounds = [1, 2]\nshooting = 'auto'\nremesh = 1",
            "remesh",
        ),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nparam2 = 'eta'\nbounds2 = [0, 1]", "param2"),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nparam2 = 'k12'\nbounds2 = [0]", "bounds2"),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nbounds2 = [0, 1]", "param2"),
        (
            "[continue]\nparam = 'eta'\nbounds = [1, 2]\nparam2 = 'k12'\nbounds2 = [-1, 0]\n"
            "direction2 = 2",
            "direction2",
        ),
        (
            "[continue]\nparam = 'eta'\nbounds = [1, 2]\nparam2 = 'k12'\nbounds2 = [-1, 0]\n"
            "kinds2 = ['hopf']",
            "kinds2",
        ),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nkinds2 = ['fold']", "kinds2 need param2"),
        ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nstick_events = 1", "stick_events"),
        (
            "[continue]\nparam = 'beta'\nbounds = [1, 2]\nstart = 'sliding'\nstick_events = false",
            "stick_events applies to start = 'orbit'",
        ),
    ],
)
def test_bad_config_names_the_key(tmp_path, text, match):
    with pytest.raises(ConfigError, match=match):
        load_config(_write(tmp_path, text))


def test_continue_table_takes_the_issue_28_keys(tmp_path):
    text = ("[continue]\nparam = 'eta'\nbounds = [1, 2]\nshooting = 'auto'\nsegments = 12\n"
            "param2 = 'k12'\nbounds2 = [-0.9, -0.7]\ndirection2 = -1")  # fmt: skip
    c = load_config(_write(tmp_path, text)).continuation
    assert (c["shooting"], c["segments"], c["param2"]) == ("auto", 12, "k12")
    assert c["bounds2"] == (-0.9, -0.7) and c["direction2"] == -1.0 and "kinds2" not in c
    c = load_config(_write(tmp_path, text + "\nkinds2 = ['neimark-sacker', 'stick-phase']"))
    assert c.continuation["kinds2"] == ("neimark-sacker", "stick-phase")
    c = load_config(_write(tmp_path, text + "\nremesh = true\nmax_segments = 128")).continuation
    assert (c["remesh"], c["max_segments"]) == (True, 128)


def test_param2_for_an_equilibrium_continuation(tmp_path):
    # the curves of an equilibrium branch's folds and Hopf points (tests/test_eqcurve.py)
    text = ("[continue]\nparam = 'beta'\nbounds = [0.001, 0.02]\nstart = 'sliding'\n"
            "param2 = 'eta'\nbounds2 = [1.5, 2.5]")  # fmt: skip
    c = load_config(_write(tmp_path, text)).continuation
    assert (c["start"], c["param2"], c["bounds2"]) == ("sliding", "eta", (1.5, 2.5))
    with pytest.raises(ConfigError, match="param2"):
        load_config(_write(tmp_path, text.replace("'eta'", "'n_oscillators'")))


def test_paper_order_initial_condition_for_two_disks():
    # paper: (x1, x2, dx1, dx2, phi1, phi2, dphi1, dphi2)
    y = paper_order_to_state([1, 2, 3, 4, 5, 6, 7, 8], 2, vb=0.5)
    np.testing.assert_array_equal(y, [1, 3, 5, 7, 2, 4, 6, 8, 0.5])


def test_every_data_config_loads_and_matches_the_paper():
    files = sorted(glob.glob(os.path.join(ROOT, "data", "*.toml")))
    figs = {os.path.basename(f)[3:5] for f in files}
    assert figs >= {"02", "03", "04", "05", "06", "07", "09", "10", "11", "12", "13", "14",
                    "15", "16", "17", "18"}  # fmt: skip
    for f in files:
        cfg = load_config(f)
        assert cfg.title.startswith("Fig.")
        if cfg.sweep:
            assert cfg.sweep["param"] == "eta" and len(cfg.sweep["values"]) >= 1000
            assert cfg.sweep["values"].min() == 1.0 and cfg.sweep["values"].max() == 10.0
    fig16 = load_config(os.path.join(ROOT, "data", "fig16_asymmetric_dcmotor_N2.toml"))
    np.testing.assert_array_equal(fig16.y0, [0, 0, 0, 0, 0.01, 0.01, 0.01, 0.01, 0])
    fig14 = load_config(os.path.join(ROOT, "data", "fig14_symmetric_dcmotor_N2.toml"))
    np.testing.assert_array_equal(fig14.y0, [0, 0, 0, 0, 0.05, 0.05, 0, 0, 0])


def test_census_and_continuation_configs_load():
    census = sorted(glob.glob(os.path.join(ROOT, "data", "census", "*.toml")))
    assert {os.path.basename(f)[:5] for f in census} == {"fig02", "fig06", "fig12", "fig16"}
    for f in census:
        cfg = load_config(f)
        assert cfg.census["param"] == "eta" and cfg.census["n_starts"] == 64
        assert cfg.census["values"].min() >= 1.0 and cfg.census["values"].max() <= 10.0
    conts = sorted(glob.glob(os.path.join(ROOT, "data", "continuation", "*.toml")))
    assert len(conts) >= 2
    for f in conts:
        cont = load_config(f)
        c = cont.continuation
        assert c["bounds"][0] <= getattr(cont.system, c["param"]) <= c["bounds"][1]


def test_cli_sweep_info_and_resume(tmp_path, capsys):
    cfg = _write(tmp_path, SMALL)
    out = tmp_path / "o.h5"
    assert main(["sweep", str(cfg), "-o", str(out), "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    res = ssf.sweep(ssf.System.preset("asymmetric"), "eta", np.linspace(6, 9, 4),
                    t_end=600.0, t_transient=300.0, max_points=8)  # fmt: skip
    with h5py.File(out, "r") as h5:
        np.testing.assert_array_equal(h5["points"][...], res.points)
        assert json.loads(h5.attrs["config"])["settings"]["t_end"] == 600.0
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "4 of 4 values done" in text and "eta in [6, 9] (4 values)" in text
    # same command again: resumes (nothing to do) and reports
    assert main(["sweep", str(cfg), "-o", str(out)]) == 0
    assert "4 of 4 values done" in capsys.readouterr().out
    # a changed config on the same file is refused, naming what changed
    assert main(["sweep", str(cfg), "-o", str(out), "--t-end", "700"]) == 2
    assert "settings.t_end" in capsys.readouterr().err


def test_cli_simulate_prints_points_and_period(capsys):
    assert main(["simulate", "--preset", "asymmetric", "--eta", "9.99", "--show", "4"]) == 0
    text = capsys.readouterr().out
    assert "status: ok" in text and "period: 2" in text
    assert main(["simulate", "--eta", "11"]) == 2
    assert "eta" in capsys.readouterr().err
    assert (
        main(["simulate", "--set", "k12=-0.5", "--json", "--t-end", "500", "--t-transient", "0"])
        == 0
    )
    data = json.loads(capsys.readouterr().out)
    assert data["system"]["k12"] == -0.5 and len(data["poincare"]) == len(data["t_poincare"])


def test_console_script_runs_in_a_subprocess(tmp_path):
    # what the README runs; the CLI must work as a separate process (Numba cache)
    cfg = _write(tmp_path, SMALL)
    proc = subprocess.run(
        [sys.executable, "-m", "stickslip_fast.cli", "sweep", str(cfg), "-o", str(tmp_path / "x.h5")],
        capture_output=True, text=True, cwd=ROOT, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "periods:" in proc.stdout and proc.stderr.count("\r") == 0  # no progress bar off a tty
