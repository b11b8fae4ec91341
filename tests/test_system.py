"""System: presets, physical conversion, validation naming the bad field."""

import math

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast import System


def test_from_physical_reproduces_the_papers_numbers():
    s = System.from_physical(5.0, 0.1, 0.1, 9000.0, 1000.0, 0.0, 0.0, vb_hat=0.05, mu=1.0, g=9.81)
    assert s.m == pytest.approx(2.0, rel=1e-12)
    assert s.k12 == pytest.approx(-0.8, rel=1e-12)
    assert s.c == 0.0 and s.c12 == 0.0
    assert round(s.mu, 4) == 0.0491  # paper: 0.0491
    assert round(s.vb0, 4) == 0.0112  # paper: 0.0112
    assert s.mu == pytest.approx(5 * 9.81 / (0.1 * 10000))
    assert s.vb == pytest.approx(0.05 / (math.sqrt(10000 / 5) * 0.1))
    # symmetric springs k1 = k2 = 5000 -> k12 = 0 (Figs. 4, 5)
    assert System.from_physical(5.0, 0.1, 0.1, 5000.0, 5000.0).k12 == 0.0
    # damping formulas
    d = System.from_physical(5.0, 0.1, 0.1, 9000.0, 1000.0, c1_hat=3.0, c2_hat=1.0)
    assert d.c == pytest.approx(4.0 / math.sqrt(5 * 10000))
    assert d.c12 == pytest.approx(-2.0 / math.sqrt(5 * 10000))


def test_presets_match_the_paper():
    lit = System.preset("literature")
    assert (lit.m, lit.k12, lit.c, lit.c12, lit.mu, lit.vb, lit.eps) == (
        90.0, 0.85, 1e-4, 0.0, 5.0, 0.15, 1e-5,
    )  # fmt: skip
    asym = System.preset("asymmetric")
    assert (asym.m, asym.k12, asym.mu, asym.eta, asym.Tb, asym.vb0, asym.beta) == (
        2.0, -0.8, 0.0491, 1.5, 0.5, 0.0112, 0.0014,
    )  # fmt: skip
    assert System.preset("symmetric").k12 == 0.0
    two = System.preset("asymmetric", drive="dc-motor", n_oscillators=2, eta=8.0)
    assert two.n_state == 9 and two.eta == 8.0
    assert two.state_names == [
        "x1", "dx1", "phi1", "dphi1", "x2", "dx2", "phi2", "dphi2", "vb",
    ]  # fmt: skip
    assert System.preset("literature").state_names == ["x1", "dx1", "phi1", "dphi1"]


@pytest.mark.parametrize(
    "field,value",
    [
        ("m", 0.0), ("m", -1.0), ("eps", 0.0), ("eps", -1e-5), ("Tb", 0.0),
        ("eta", 0.5), ("eta", 10.5), ("k12", math.nan), ("mu", math.inf), ("vb", "fast"),
        ("n_oscillators", 0), ("n_oscillators", 1.5), ("drive", "belt"), ("beta", None),
    ],
)  # fmt: skip
def test_invalid_field_is_named(field, value):
    with pytest.raises(ValueError, match=field):
        System.preset("asymmetric", **{field: value})


def test_unknown_preset_and_field_and_y0():
    with pytest.raises(ValueError, match="preset"):
        System.preset("nonexistent")
    with pytest.raises(ValueError, match="bogus"):
        System.preset("asymmetric", bogus=1.0)
    s = System.preset("asymmetric", drive="dc-motor")
    with pytest.raises(ValueError, match="y0"):
        ssf.simulate(s, 10.0, y0=np.zeros(4))
    with pytest.raises(ValueError, match="y0"):
        ssf.simulate(s, 10.0, y0=[0, 0, np.nan, 0, 0])


@pytest.mark.parametrize(
    "kwargs,name",
    [
        (dict(t_end=-1.0), "t_end"),
        (dict(t_end=10.0, t_transient=20.0), "t_transient"),
        (dict(t_end=10.0, rtol=0.0), "rtol"),
        (dict(t_end=10.0, atol=math.nan), "atol"),
        (dict(t_end=10.0, method="euler"), "method"),
        (dict(t_end=10.0, method="dopri5-fixed"), "h"),
        (dict(t_end=10.0, max_points=-1), "max_points"),
        (dict(t_end=10.0, sample_dt=0.0), "sample_dt"),
    ],
)
def test_invalid_settings_are_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        ssf.simulate(System(), **kwargs)


def test_to_array_roundtrip_and_replace():
    s = System.preset("asymmetric", eta=4.0)
    p = s.to_array()
    from stickslip_fast.model.system import PARAM_INDEX

    for name, idx in PARAM_INDEX.items():
        assert p[idx] == getattr(s, name)
    assert s.replace(eta=5.0).eta == 5.0
    assert System.from_dict(s.to_dict()) == s
