"""Poincare points against an independent SciPy solution (Radau, rtol 1e-10, event location).

The reference model (tests/reference/scipy_model.py) was written from the paper
without reading the engine; tests/reference/README.md says how it was made and
how accurate it is (self-consistency 2.6e-12 to 6.2e-10 in the states).
"""

import json
import os

import numpy as np
import pytest

import stickslip_fast as ssf

HERE = os.path.join(os.path.dirname(__file__), "reference")
CASES = json.load(open(os.path.join(HERE, "cases.json")))
REF = np.load(os.path.join(HERE, "scipy_reference.npz"))


def _run(case, **kw):
    system = ssf.System.from_dict(case["params"])
    return ssf.simulate(system, case["t_end"], case["t_transient"], y0=case["y0"], **kw)


def test_cases_cover_presets_drives_and_two_disks():
    kinds = {
        (c["params"]["drive"], c["params"]["n_oscillators"], c["params"]["k12"]) for c in CASES
    }
    assert ("constant", 1, -0.8) in kinds and ("constant", 1, 0.0) in kinds
    assert ("dc-motor", 1, -0.8) in kinds and ("dc-motor", 2, -0.8) in kinds
    assert any(c["params"]["m"] == 90.0 for c in CASES)  # the literature set


@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in CASES])
def test_poincare_points_match_scipy_at_default_tolerances(case):
    res = _run(case)
    t_ref = REF[case["name"] + "__t"]
    y_ref = REF[case["name"] + "__y"]
    assert res.status == "ok"
    assert len(res.t_poincare) == len(t_ref)
    # the bound is 1e-6; the defaults are chosen for ~1e-7 (worst seen 1.8e-7)
    assert np.abs(res.poincare - y_ref).max() < 5e-7
    # crossing times: dx1 crosses zero at a minimum, so times are ~sqrt less precise
    assert np.abs(res.t_poincare - t_ref).max() < 1e-3


@pytest.mark.parametrize("method", ["rodas5p", "dopri5", "rodas4p", "rodas4p2"])
def test_tight_tolerances_converge_to_the_reference(method):
    # a non-stiff enough case that the explicit method finishes quickly
    case = next(c for c in CASES if c["name"] == "sym_const_eta5")
    res = _run(case, method=method, rtol=1e-11, atol=1e-13)
    y_ref = REF[case["name"] + "__y"]
    assert np.abs(res.poincare - y_ref).max() < 2e-8


@pytest.mark.parametrize("method", ["rodas4p", "rodas4p2"])
def test_fourth_order_rosenbrock_on_two_disks_and_a_motor(method):
    """The 4th-order tableaus run the generic (bordered) kernel too: N = 2 on a DC motor."""
    case = next(c for c in CASES if c["params"]["n_oscillators"] == 2)
    res = _run(case, method=method, rtol=1e-11, atol=1e-13)
    y_ref = REF[case["name"] + "__y"]
    assert res.status == "ok"
    assert len(res.t_poincare) == len(y_ref)
    assert np.abs(res.poincare - y_ref).max() < 1e-8  # measured 1.1e-9 (rodas5p: 1.2e-8)
