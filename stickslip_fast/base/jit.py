"""Compilation options shared by every compiled module, the record-type test, and borrowing.

``error_model="numpy"`` makes a division by zero give inf/NaN instead of
raising: no kernel can raise (see docs/developing.md, "The kernel rules").

Two option sets: :data:`JIT` for the functions that compiled code calls, built
without Numba's CPython and C wrappers, and :data:`ENTRY` for the functions
Python calls alone. Compile them with this module's :func:`njit`: a Python call of
a :data:`JIT` function then goes to its entry twin, where Numba's own ``njit``
would crash the interpreter.
"""

from __future__ import annotations

import functools
import inspect
import types as pytypes

from numba import njit as _numba_njit
from numba import types
from numba.core import cgutils, ir_utils
from numba.core.caching import NullCache
from numba.core.registry import CPUDispatcher
from numba.extending import intrinsic, overload

__all__ = [
    "JIT",
    "ENTRY",
    "njit",
    "python_callable",
    "OVERLOAD",
    "LLVM_INLINED",
    "overload_call",
    "is_record",
    "borrow",
    "poll_flag",
]

#: Options of every ``@njit`` of the package that compiled code calls. Numba builds
#: no CPython wrapper (the code that unboxes Python arguments: for a record, every
#: field) and no C wrapper for them. Only a call from Python needs those, but every
#: caller links them in and LLVM optimised them again at each level: about a sixth
#: of a first ``simulate``'s compile (docs/performance.md, "The first run").
JIT = dict(
    cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True, no_cfunc_wrapper=True
)
#: Options of the compiled functions that Python calls and compiled code does not
#: (``integrate``, ``run_lane``, the variational and Lyapunov kernels, ...):
#: :data:`JIT` with Numba's wrappers.
ENTRY = dict(JIT, no_cpython_wrapper=False, no_cfunc_wrapper=False)
#: Options of the small ``@overload`` implementations (the problem's right-hand
#: side, Jacobian, factorisation, solve, norms). Inlined into the caller at
#: Numba IR level: records (namedtuples of arrays) passed across a call boundary
#: cost an atomic incref/decref per array field, which made a step of the generic
#: driver ~1.5x slower than the hand-written loop it replaced; inlined, the
#: reference counts are pruned and the step costs what it did. The large ones
#: use :func:`overload_call` instead.
OVERLOAD = dict(jit_options=JIT, inline="always")
#: Options of a function compiled once and inlined by LLVM into each caller
#: (``forceinline``: LLVM's ``alwaysinline``), as :func:`overload_call`'s are. Not
#: cached on its own: its callers are cached with its code linked in, and Numba's
#: cache index names a function by its source, so a cached copy of another
#: function's ``py_func`` would share that function's entries whatever the options.
LLVM_INLINED = dict(JIT, cache=False, forceinline=True)


class CompiledOnlyDispatcher(CPUDispatcher):
    """Numba's dispatcher for a function compiled without its CPython wrapper.

    Compiled callers call the native function and never go through
    ``__call__``. Numba would call the missing wrapper's null address from
    Python and crash the interpreter; here a Python call goes to an entry twin
    instead: the same function compiled with the wrappers (:data:`ENTRY`),
    built at the first such call. The twin has its own name in Numba's cache
    (``<name>__entry``): the cache index does not know the options.
    """

    def __call__(self, *args, **kwargs):
        return self.entry_twin()(*args, **kwargs)

    def entry_twin(self) -> CPUDispatcher:
        """The twin that Python calls go to (built at the first call)."""
        twin = self.__dict__.get("_entry_twin")
        if twin is None:
            func = self.py_func
            copy = pytypes.FunctionType(
                func.__code__, func.__globals__, func.__name__, func.__defaults__,
                func.__closure__,
            )  # fmt: skip
            copy.__kwdefaults__ = func.__kwdefaults__
            copy.__module__ = func.__module__
            copy.__qualname__ = f"{func.__qualname__}__entry"
            copy.__doc__ = func.__doc__
            # the dispatcher's own options (also after pickle rebuilt it), with the wrappers
            options = {k: v for k, v in self.targetoptions.items() if k != "nopython"}
            options.update(cache=not isinstance(self._cache, NullCache))
            options.update(no_cpython_wrapper=False, no_cfunc_wrapper=False)
            twin = _numba_njit(**options)(copy)
            self.__dict__["_entry_twin"] = twin
        return twin


def python_callable(dispatcher):
    """The dispatcher to call from Python in a loop: a compiled-only one's entry twin.

    Skips the forwarding call of :meth:`CompiledOnlyDispatcher.__call__` (for peers
    that call the model's right-hand side from Python at every evaluation).
    """
    if isinstance(dispatcher, CompiledOnlyDispatcher):
        return dispatcher.entry_twin()
    return dispatcher


def njit(*args, **options):
    """:func:`numba.njit`; without the CPython wrapper, Python calls go to an entry twin.

    With ``no_cpython_wrapper=True`` (as in :data:`JIT`) the dispatcher is a
    :class:`CompiledOnlyDispatcher`; otherwise this is :func:`numba.njit` itself.
    """
    if not options.get("no_cpython_wrapper"):
        return _numba_njit(*args, **options)

    def decorate(func):
        dispatcher = _numba_njit(**options)(func)
        dispatcher.__class__ = CompiledOnlyDispatcher  # same layout: a subclass, no slots
        return dispatcher

    return decorate(args[0]) if args else decorate


def is_record(typ, cls) -> bool:
    """At compile time: is the Numba type ``typ`` the namedtuple record class ``cls``?"""
    return isinstance(typ, types.BaseNamedTuple) and typ.instance_class is cls


# ------------------------------------------------------------------ borrowing
def _borrowable(typ) -> bool:
    if isinstance(typ, types.Array):
        return True
    if isinstance(typ, types.BaseTuple):
        return all(_borrowable(t) for t in typ.types)
    return isinstance(typ, (types.Number, types.Boolean, types.NoneType))


def _borrow_value(context, builder, typ, value):
    """The value with every array in it re-made without its reference count (recursive)."""
    if isinstance(typ, types.Array):
        src = context.make_array(typ)(context, builder, value=value)
        dst = context.make_array(typ)(context, builder)
        for field in ("nitems", "itemsize", "data", "shape", "strides"):
            setattr(dst, field, getattr(src, field))
        dst.meminfo = cgutils.get_null_value(dst.meminfo.type)
        dst.parent = cgutils.get_null_value(dst.parent.type)
        return dst._getvalue()
    if isinstance(typ, types.BaseTuple):
        items = cgutils.unpack_tuple(builder, value, len(typ))
        fields = [_borrow_value(context, builder, t, v) for t, v in zip(typ.types, items)]
        return context.make_tuple(builder, typ, fields)
    return value


@intrinsic
def borrow(typingctx, value):  # noqa: ARG001 - the intrinsic's typing signature
    """In compiled code: ``value`` (an array, or a record of arrays and scalars) borrowed.

    The result has the same type and sees the same memory, but its arrays carry
    no reference count (a null ``meminfo``), so copying, passing or taking a
    field of it costs nothing. Numba counts references with an atomic
    instruction at every copy of an array, and inlined records copy all their
    arrays at every call: in the driver's step loop that was ~100 atomics per
    Rodas5P attempt and half its time (benchmarks/results/profile.md, section 5).

    A borrowed value is valid only while the caller's original is alive: use it
    inside the function that borrowed it, and never return or store it. Numba's
    dead-code elimination is told that the result aliases ``value``
    (:func:`_borrow_aliases`); without that, writes into a borrowed record made
    by an IR-inlined overload were removed as dead.
    """
    if not _borrowable(value):
        return None
    sig = value(value)

    def codegen(context, builder, signature, args):
        return _borrow_value(context, builder, signature.args[0], args[0])

    return sig, codegen


def _borrow_aliases(lhs: str, args, alias_map: dict, arg_aliases: set) -> None:
    """Numba alias analysis: ``lhs = borrow(x)`` aliases x.

    Numba removes a write into an array that it believes nothing else can see
    (one reached from a call's result, not from an argument). Without this
    rule every store an IR-inlined overload made into a borrowed record was
    dropped (measured: lost Poincare times, a wrong Lyapunov exponent).
    """
    rhs = args[0].name
    if rhs in arg_aliases:
        arg_aliases.add(lhs)
        return
    alias_map.setdefault(rhs, set()).add(lhs)
    alias_map.setdefault(lhs, set()).add(rhs)


ir_utils.alias_func_extensions[("borrow", __name__)] = _borrow_aliases


@intrinsic
def poll_flag(typingctx, flag):  # noqa: ARG001 - the intrinsic's typing signature
    """In compiled code: ``flag[0]`` of an integer array, read with an atomic (relaxed) load.

    For flags set from another thread (the abort flag of Ctrl-C): a plain load
    in a loop with no opaque calls left may legally be hoisted out of the loop
    by LLVM, and then the loop never sees the flag change.
    """
    if not (isinstance(flag, types.Array) and flag.ndim == 1
            and isinstance(flag.dtype, types.Integer)):  # fmt: skip
        return None
    sig = flag.dtype(flag)

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, value=args[0])
        return builder.load_atomic(ary.data, "monotonic", signature.return_type.bitwidth // 8)

    return sig, codegen


# ---------------------------------------------------------- overloads behind a call
def _borrowing_call(name: str, impl, arg_types):
    """``impl`` (an overload implementation) inside a function that borrows its arguments.

    The function is named ``name`` (so that compile events and profiles say what
    it is) and calls ``impl``, inlined at the Numba IR level, with every argument
    whose type :func:`borrow` takes replaced by its borrowed value.
    """
    inner = njit(inline="always", **JIT)(impl)
    names = list(inspect.signature(impl).parameters)
    passed = [f"borrow({a})" if _borrowable(t) else a for a, t in zip(names, arg_types)]
    source = f"def {name}({', '.join(names)}):\n    return inner({', '.join(passed)})\n"
    scope = {"inner": inner, "borrow": borrow}
    exec(source, scope)  # noqa: S102 - a fixed template over the implementation's own arguments
    called = scope[name]
    called.__module__ = impl.__module__
    return called


def overload_call(func):
    """``@overload(func)`` compiled once per type as a function of its own, then inlined by LLVM.

    For the large generic operations the driver calls at every step: a method's
    step, its initialisation, acceptance and dense output, an observer, a stop
    rule. Inlined at the Numba IR level (``inline="always"``), Numba deep-copies
    and re-types their IR into every caller, and that was most of a first run's
    compile (the driver alone: 48 of 78 s of CPU). Here Numba types and lowers
    each implementation once; the compiled function carries LLVM's
    ``alwaysinline`` (Numba's ``forceinline``), so LLVM inlines it into the step
    loop and the step costs what it did inlined. Its arguments are borrowed on
    entry (:func:`borrow`): after LLVM's inlining their arrays' reference counts
    are null constants and the count calls go away.

    The implementation must not return or store its record arguments (borrowed
    values do not outlive the call).
    """

    def decorate(generator):
        @functools.wraps(generator)
        def typed(*args, **kws):
            impl = generator(*args, **kws)
            if impl is None:
                return None
            return _borrowing_call(func.__name__, impl, args)

        # uncached (LLVM_INLINED): the generated function has no source file either
        overload(func, jit_options=LLVM_INLINED, inline="never")(typed)
        return generator

    return decorate
