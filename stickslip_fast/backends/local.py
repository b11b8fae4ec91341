"""Units of sweep work and the pure functions that compute them.

The work of a sweep is cut into *units*. A restart unit is a chunk of
independent values; a continuation unit is one segment of every unfinished
chain (each chain follows the values in order, starting from the previous
value's final state). A unit is computed by a pure function of (system,
values, settings) -- :func:`compute_restart_chunk` or
:func:`compute_continuation_chunk` -- so a backend (:func:`run_local` here,
:mod:`stickslip_fast.backends` for Dask) can run it anywhere; the sweep driver
alone writes the results, with :func:`write_unit`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numba
import numpy as np

from ..base.interrupt import call_interruptible, new_abort_flag
from ..base.status import ST_NOT_COMPUTED
from ..core.settings import Settings
from ..core.sweep_kernels import continuation_chunk, sweep_chunk
from ..core.trajectory import (
    AUTO_TOKEN,
    M_AUTO,
    METHODS,
    SWEEP_INT_FIELDS,
    kernel_variant,
    method_variant,
)
from ..model.system import PARAM_INDEX, System

__all__ = [
    "WorkUnit",
    "compute_restart_chunk",
    "compute_continuation_chunk",
    "restart_units",
    "continuation_units",
    "run_local",
    "unit_starts",
    "write_unit",
]


# ----------------------------------------------------------------- pure chunks
def _param_rows(system: System, names: Sequence[str], values: np.ndarray) -> np.ndarray:
    """Packed parameter rows: ``values`` (..., len(names)) replace the named slots."""
    base = system.to_array()
    rows = np.broadcast_to(base, values.shape[:-1] + base.shape).copy()
    for k, name in enumerate(names):
        rows[..., PARAM_INDEX[name]] = values[..., k]
    return rows


def _kernel_args(system: System, s: Settings) -> tuple:
    """(n_osc, dc, variant, run settings, max_points): the kernels' arguments after the parameters."""
    rs = s.run_settings()
    n_osc, dc = system.n_oscillators, system.is_dc_motor
    # trajectory.method_variant, through this module's kernel_variant (which
    # benchmarks/converged.py swaps for the generic kernel)
    m = METHODS.index(s.method)
    variant = None if method_variant(m, n_osc, dc) is None else kernel_variant(n_osc, dc)
    if m == M_AUTO:
        variant = variant + AUTO_TOKEN
    return n_osc, dc, variant, rs, s.max_points


def _checked(res: tuple) -> tuple:
    """Refuse kernel output with a value that was never computed (never stored as a result)."""
    status = res[2][..., SWEEP_INT_FIELDS.index("status")]
    if np.any(status == ST_NOT_COMPUTED):
        missing = int(np.count_nonzero(status == ST_NOT_COMPUTED))
        raise RuntimeError(
            f"internal error: {missing} value(s) of a chunk were not computed; nothing was stored"
        )
    return res


def _pack(res: tuple, settings: Settings) -> dict[str, np.ndarray]:
    points, t_points, ints, t_converged, final_state = _checked(res)
    out = {"points": points, "t_points": t_points, "final_state": final_state}
    if settings.stop == "converged":
        out["t_converged"] = t_converged
    for k, name in enumerate(SWEEP_INT_FIELDS):
        out[name] = ints[..., k]
    return out


def compute_restart_chunk(
    system: System, names: Sequence[str], values: np.ndarray, y0: np.ndarray, settings: Settings
) -> dict[str, np.ndarray]:
    """Restart mode: trajectories from ``y0`` for each row of ``values`` (L, len(names)).

    A pure function: the same inputs give bit-identical outputs on any machine
    with the same compiled kernels, whatever the thread count.
    """
    rows = _param_rows(system, names, np.asarray(values, dtype=float))
    res = call_interruptible(
        sweep_chunk, METHODS.index(settings.method), y0, rows,
        *_kernel_args(system, settings), numba.get_num_threads(), abort=new_abort_flag(),
    )  # fmt: skip
    return _pack(res, settings)


def compute_continuation_chunk(
    system: System,
    names: Sequence[str],
    values: np.ndarray,
    y_starts: np.ndarray,
    y0: np.ndarray,
    settings: Settings,
) -> dict[str, np.ndarray]:
    """Continuation mode: ``values`` (C, L, len(names)) are C chains run in parallel.

    Chain c starts from ``y_starts[c]``; each later value starts from the final
    state of the last value before it that did not fail (nonfinite,
    step-underflow, max-steps, error), ``y_starts[c]`` if none.
    """
    rows = _param_rows(system, names, np.asarray(values, dtype=float))
    res = call_interruptible(
        continuation_chunk, METHODS.index(settings.method), y0,
        np.ascontiguousarray(y_starts), rows, *_kernel_args(system, settings),
        abort=new_abort_flag(),
    )  # fmt: skip
    return _pack(res, settings)


# ----------------------------------------------------------------- work units
@dataclass
class WorkUnit:
    """One unit of sweep work.

    Attributes
    ----------
    kind : {"restart", "continuation"}
    values : ndarray
        (L, k) for restart, (C, L, k) for continuation (k swept parameters).
    targets : list
        Restart: (grid index, slice of the unit) pairs; continuation: one
        segment (list of grid indices) per chain.
    y_starts : ndarray or None
        Continuation: the start state of each chain.
    axis : int
        Continuation: the grid axis the chains follow (1 when there is a branch axis).
    """

    kind: str
    values: np.ndarray
    targets: list
    y_starts: np.ndarray | None = None
    axis: int = 0


def restart_units(axes, done: np.ndarray, chunk: int) -> Iterator[WorkUnit]:
    """Chunks of ``chunk`` values not yet ``done``, in grid order."""
    grid = tuple(len(a) for a in axes)
    todo = np.flatnonzero(~done.reshape(-1))
    for a in range(0, todo.size, chunk):
        flat = todo[a : a + chunk]
        idx = np.unravel_index(flat, grid)
        vals = np.stack([axes[k][idx[k]] for k in range(len(axes))], axis=-1)
        # group into contiguous runs along the last axis, for efficient HDF5 writes
        targets = []
        start = 0
        for j in range(1, flat.size + 1):
            if j == flat.size or flat[j] != flat[j - 1] + 1 or (flat[j] % grid[-1]) == 0:
                lead = tuple(int(i[start]) for i in idx[:-1])
                last = slice(int(idx[-1][start]), int(idx[-1][j - 1]) + 1)
                targets.append((lead + (last,), slice(start, j)))
                start = j
        yield WorkUnit("restart", vals, targets)


def _chains(axes, branches: bool) -> list[list[tuple]]:
    """Every chain: a list of grid indices in the order the values are followed."""
    n1 = len(axes[0])
    others = [()] if len(axes) == 1 else [(j,) for j in range(len(axes[1]))]
    chains = []
    for b in (0, 1) if branches else (None,):
        for rest in others:
            order = range(n1) if b in (None, 0) else range(n1 - 1, -1, -1)
            lead = () if b is None else (b,)
            chains.append([lead + (i,) + rest for i in order])
    return chains


def continuation_units(
    axes, branches: bool, done: np.ndarray, chunk: int, y0: np.ndarray,
    final_state_at: Callable[[tuple], np.ndarray],
) -> Iterator[WorkUnit]:  # fmt: skip
    """Rounds of chain segments; each round holds the next segment of every open chain.

    A round's start states are read (``final_state_at``) only when the round is
    pulled, so the previous round must have been written by then.
    """
    chains = _chains(axes, branches)
    # resume: each chain continues after its last written value
    pos = []
    for chain in chains:
        k = 0
        while k < len(chain) and done[chain[k]]:
            k += 1
        pos.append(k)
    while True:
        open_ = [c for c, chain in enumerate(chains) if pos[c] < len(chain)]
        if not open_:
            return
        length = min(chunk, min(len(chains[c]) - pos[c] for c in open_))
        vals = []
        starts = []
        targets = []
        for c in open_:
            seg = chains[c][pos[c] : pos[c] + length]
            vals.append(
                [
                    [axes[k][idx[k + (len(idx) - len(axes))]] for k in range(len(axes))]
                    for idx in seg
                ]
            )
            starts.append(y0 if pos[c] == 0 else final_state_at(chains[c][pos[c] - 1]))
            targets.append(seg)
            pos[c] += length
        yield WorkUnit(
            "continuation", np.asarray(vals, dtype=float), targets, np.asarray(starts, dtype=float),
            axis=1 if branches else 0,
        )  # fmt: skip


def run_local(
    units: Iterator[WorkUnit], system: System, names, y0: np.ndarray, settings: Settings
) -> Iterator[tuple[WorkUnit, dict]]:
    """The local backend: compute each unit in this process, in order."""
    for unit in units:
        if unit.kind == "restart":
            res = compute_restart_chunk(system, names, unit.values, y0, settings)
        else:
            res = compute_continuation_chunk(
                system, names, unit.values, unit.y_starts, y0, settings
            )
        yield unit, res


def unit_starts(unit: WorkUnit, res: dict, y0: np.ndarray) -> np.ndarray:
    """The initial state of every trajectory of a unit (shape of the value axes + state)."""
    if unit.kind == "restart":
        return np.broadcast_to(y0, (len(unit.values), y0.size))
    final = res["final_state"]
    starts = np.empty_like(final)
    starts[:, 0] = unit.y_starts
    starts[:, 1:] = final[:, :-1]
    bad = ~np.all(np.isfinite(starts), axis=-1)
    starts[bad] = y0  # as the continuation kernel: restart from y0 after a failure
    return starts


def write_unit(unit: WorkUnit, res: dict, write: Callable[[tuple, dict], None]) -> int:
    """Hand a computed unit to ``write(grid index, block)`` block by block; returns its size."""
    if unit.kind == "restart":
        for index, sl in unit.targets:
            write(index, {k: v[sl] for k, v in res.items()})
        return len(unit.values)
    n = 0
    for c, seg in enumerate(unit.targets):
        # the segment runs along the first parameter axis, downwards on the "down" branch
        ax = unit.axis
        lo = min(idx[ax] for idx in seg)
        hi = max(idx[ax] for idx in seg)
        order = slice(None) if seg[0][ax] <= seg[-1][ax] else slice(None, None, -1)
        index = list(seg[0])
        index[ax] = slice(lo, hi + 1)
        write(tuple(index), {k: v[c][order] for k, v in res.items()})
        n += len(seg)
    return n
