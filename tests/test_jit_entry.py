"""Compiled functions without Numba's wrappers, and their entry twins (base.jit).

Functions compiled with ``base.jit.JIT`` carry no CPython or C wrapper: compiled
callers call them directly, and a call from Python goes to an entry twin (the
same function compiled with ``ENTRY``). Numba on its own would call the missing
wrapper's null address and crash. The first-run test (test_first_compile.py)
checks that a first ``simulate`` compiles no wrapper beyond its entries.
"""

import math

import numpy as np
import pytest
from numba import njit as numba_njit

from stickslip_fast.base.jit import ENTRY, JIT, CompiledOnlyDispatcher, njit, python_callable
from stickslip_fast.core import poincare, stoprules, trajectory
from stickslip_fast.model import equations
from stickslip_fast.model.params import eta_prime


def _functions(cres) -> list[str]:
    return [f.name for f in cres.library._final_module.functions if not f.is_declaration]


def _hypot3(a, b, c):
    return math.sqrt(a * a + b * b + c * c)


def test_a_jit_function_has_no_wrapper_and_python_calls_reach_its_entry_twin():
    inner = njit(**dict(JIT, cache=False))(_hypot3)
    assert isinstance(inner, CompiledOnlyDispatcher)

    @numba_njit(cache=False)
    def outer(a):
        return inner(a, 4.0, 12.0)

    assert outer(3.0) == 13.0  # compiled caller: the native function
    (cres,) = inner.overloads.values()
    names = _functions(cres)
    assert names and not any("cpython" in n or "cfunc" in n for n in names), names
    # from Python: the twin, with Numba's wrapper, its own cache name, the same result
    assert inner(3.0, 4.0, 12.0) == 13.0
    twin = inner.__dict__["_entry_twin"]
    assert twin.py_func.__qualname__ == "_hypot3__entry"
    assert twin.targetoptions["no_cpython_wrapper"] is False
    assert twin.targetoptions["error_model"] == "numpy" and twin.targetoptions["nogil"]
    (tres,) = twin.overloads.values()
    assert any("cpython" in n for n in _functions(tres))
    assert not isinstance(twin, CompiledOnlyDispatcher)
    assert python_callable(inner) is twin and python_callable(outer) is outer
    # keyword and default arguments pass through
    assert inner(c=12.0, b=4.0, a=3.0) == 13.0


def test_the_twin_takes_the_dispatchers_options_and_caching():
    # from the dispatcher itself (so also after pickle rebuilt it without its decorator)
    plain = njit(**dict(JIT, cache=False, inline="always"))(_hypot3)
    twin = plain.entry_twin()
    assert twin.targetoptions["inline"] == "always" and twin.targetoptions["nogil"]
    assert type(twin._cache).__name__ == "NullCache"
    cached = njit(**JIT)(poincare.ring_period.py_func)
    assert type(cached.entry_twin()._cache).__name__ == "FunctionCache"
    assert cached.entry_twin() is cached.entry_twin()  # built once


def test_options_and_the_package_functions_python_calls():
    assert JIT["no_cpython_wrapper"] and JIT["no_cfunc_wrapper"]
    assert not ENTRY["no_cpython_wrapper"] and not ENTRY["no_cfunc_wrapper"]
    assert {k: v for k, v in ENTRY.items() if "wrapper" not in k} == {
        k: v for k, v in JIT.items() if "wrapper" not in k
    }
    # the kernels' internals: no wrapper; the entries Python calls: Numba's dispatcher
    for internal in (stoprules.converged_now, poincare.ring_period, trajectory._run, eta_prime):
        assert isinstance(internal, CompiledOnlyDispatcher), internal
    for entry in (trajectory.integrate, equations.dense_jacobian):
        assert not isinstance(entry, CompiledOnlyDispatcher), entry
        assert entry.targetoptions["no_cpython_wrapper"] is False


def test_python_calls_of_internal_kernels_give_the_compiled_values():
    # eta_prime (the paper's cubic fit) through its twin, against its Python source
    etas = np.linspace(1.0, 10.0, 901)
    assert [eta_prime(e) for e in etas] == [eta_prime.py_func(e) for e in etas]
    # a ring of points repeating with period 3: ring_period finds it from Python
    pts = np.array([[1.0, 0.0], [2.0, 0.5], [3.0, 1.0]] * 8)
    assert poincare.ring_period(pts, len(pts), 1e-9, 10, 2, 4) == 3
    with pytest.raises(TypeError):
        poincare.ring_period(pts)  # a wrong call is Numba's TypeError, not a crash
