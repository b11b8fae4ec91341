"""The small-N kernel (problems.StickSlipSmall) against the generic bordered kernel.

For N <= SMALL_N_MAX the Rosenbrock runs integrate the model with its sizes known
at compile time. It must be the same computation: same steps, same points, same
final state, bit for bit (the arithmetic is the model's and linalg's own functions,
only inlined with literal sizes). The generic kernel itself is checked against
SciPy and the analytic Jacobian elsewhere (test_scipy_crosscheck.py, test_model.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.base.status import ST_ERROR, ST_OK
from stickslip_fast.core.problems import SMALL_N_MAX
from stickslip_fast.core.trajectory import (
    I_CROSSINGS,
    I_REJECTED,
    I_STEPS,
    M_RODAS5P,
    N_STAT_F,
    N_STAT_I,
    integrate,
    kernel_variant,
    run_settings,
)


def _integrate(system, y0, variant, n_osc=None):
    n = system.n_state
    rs = run_settings(300.0, 200.0, 1e-8, 1e-10)
    ring = np.full((64, n), np.nan)
    tring = np.full(64, np.nan)
    samples = np.empty((11, n))
    y_end = np.empty(n)
    stat_i = np.zeros(N_STAT_I, dtype=np.int64)
    stat_f = np.zeros(N_STAT_F)
    code = integrate(
        M_RODAS5P, y0, system.to_array(), system.n_oscillators if n_osc is None else n_osc,
        system.is_dc_motor, variant, rs, ring, tring, samples, 10.0, y_end, stat_i, stat_f,
    )  # fmt: skip
    return code, ring, tring, samples, y_end, stat_i, stat_f


def test_kernel_variant_tokens():
    # only the types matter: N int64 zeros, then a float64 zero for the DC motor
    assert kernel_variant(1, False) == (0,)
    assert kernel_variant(1, True) == (0, 0.0)
    assert isinstance(kernel_variant(1, True)[1], float)
    assert SMALL_N_MAX == 1
    assert kernel_variant(2, True) == ()
    assert kernel_variant(3, False) == ()
    assert kernel_variant(64, True) == ()


@pytest.mark.parametrize(("n_osc", "drive"), [(1, "constant"), (1, "dc-motor")])
def test_small_kernel_is_bit_identical_to_bordered(n_osc, drive):
    system = ssf.System.preset("asymmetric", eta=2.0, n_oscillators=n_osc, drive=drive)
    rng = np.random.default_rng(7)
    y0 = system.initial_state(None) + rng.uniform(-1e-3, 1e-3, system.n_state)
    if system.is_dc_motor:
        y0[-1] = system.vb0
    variant = kernel_variant(n_osc, system.is_dc_motor)
    assert variant != ()
    small = _integrate(system, y0, variant)
    generic = _integrate(system, y0, ())
    assert small[0] == generic[0] == ST_OK
    assert small[5][I_CROSSINGS] >= 5  # a real orbit, not a trivial run
    assert small[5][I_STEPS] > 1000 and small[5][I_REJECTED] > 0
    for a, b in zip(small[1:], generic[1:], strict=True):
        np.testing.assert_array_equal(a, b)


def test_mismatched_variant_is_an_error_not_a_wrong_result():
    # a variant compiled for one disk must not integrate two (same compiled signature)
    system = ssf.System.preset("asymmetric", eta=2.0, n_oscillators=1)
    code, ring, *_ = _integrate(system, system.initial_state(None), (0,), n_osc=2)
    assert code == ST_ERROR
    assert np.isnan(ring).all()
