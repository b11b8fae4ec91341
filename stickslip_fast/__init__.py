"""stickslip_fast: a Numba-accelerated bifurcation engine for stick-slip oscillators.

Models the coupled translational-rotational disks-on-belts system of Kudra et al.
(smooth Contensou-Pade friction with static > kinetic friction, constant belt or
a shared DC motor), integrates it with compiled stiff and explicit solvers, and
records Poincare points at the local minima of x_1.

Main entry points: :class:`System`, :func:`simulate`, :func:`sweep`, :func:`load_sweep`,
:func:`census`, :func:`basins` (and a saddle's :func:`stable_manifold` in its plane); periodic orbits and their multipliers: :func:`find_orbit`,
:func:`find_equilibrium`, :func:`continue_orbit`, :func:`continue_equilibrium` (docs/orbits.md).
"""

from __future__ import annotations

from .base import cache_guard as _cache_guard
from .base import cache_index as _cache_index
from .base import compile_gc as _compile_gc
from .base import compile_notice as _compile_notice

_cache_guard.check()  # before any kernel runs: drop kernels compiled from other sources
_cache_index.install()  # records from outside the package: no stale kernel, no failed index
_compile_gc.install()  # no full garbage collections during a Numba compile
_compile_notice.install()  # a line on the terminal while a kernel compiles for long

# ruff: noqa: E402
import importlib
from typing import TYPE_CHECKING

# What a first ``simulate`` needs is imported now; the rest on first use (PEP 562,
# ``__getattr__`` below): a process that only simulates starts ~0.2 s sooner.
from .analysis.simulate import DEFAULT_ATOL, DEFAULT_RTOL, SimulationResult, simulate
from .base.lazy import submodule_getattr
from .base.version import package_version
from .core.poincare import STATUS_NAMES
from .core.settings import CoarseToleranceWarning
from .core.trajectory import METHODS
from .model.system import PRESETS, SWEEPABLE, SynchronousStartWarning, System

#: The public names imported on first use, by the module they are imported from.
_LAZY_MODULES = {
    ".analysis": (
        "LyapunovResult",
        "LyapunovSpectrum",
        "SyncResult",
        "kaplan_yorke",
        "largest_lyapunov",
        "lyapunov_spectrum",
        "phases_from_events",
        "sync_error",
    ),
    ".analysis.basins": ("BasinsResult", "basins", "load_basins"),
    ".analysis.basins_manifold": ("StableManifold",),
    ".analysis.census": ("CensusResult", "census", "load_census"),
    ".analysis.census_plane": ("CensusPlaneResult",),
    ".analysis.sweep": ("MODES", "SweepResult", "load_sweep", "sweep"),
    ".base.journal": ("checkpoint",),
    ".bifurcation.continuation": (
        "Bifurcation",
        "Branch",
        "continue_equilibrium",
        "continue_orbit",
        "join_branches",
        "switch_branch",
    ),
    ".bifurcation.curve": ("Codim2Point", "Curve", "continue_bifurcation"),
    ".bifurcation.orbits": (
        "Equilibrium",
        "Orbit",
        "find_equilibrium",
        "find_orbit",
        "stick_phases",
    ),
    ".bifurcation.stable_manifold": ("manifold_seeds", "stable_manifold"),
    ".bifurcation.synchrony": ("SyncStability", "sync_stability"),
}
_LAZY = {name: module for module, names in _LAZY_MODULES.items() for name in names}

if TYPE_CHECKING:  # the same names, for type checkers and editors
    from .analysis import (
        LyapunovResult,
        LyapunovSpectrum,
        SyncResult,
        kaplan_yorke,
        largest_lyapunov,
        lyapunov_spectrum,
        phases_from_events,
        sync_error,
    )
    from .analysis.basins import BasinsResult, basins, load_basins
    from .analysis.basins_manifold import StableManifold
    from .analysis.census import CensusResult, census, load_census
    from .analysis.census_plane import CensusPlaneResult
    from .analysis.sweep import MODES, SweepResult, load_sweep, sweep
    from .base.journal import checkpoint
    from .bifurcation.continuation import (
        Bifurcation,
        Branch,
        continue_equilibrium,
        continue_orbit,
        join_branches,
        switch_branch,
    )
    from .bifurcation.curve import Codim2Point, Curve, continue_bifurcation
    from .bifurcation.orbits import Equilibrium, Orbit, find_equilibrium, find_orbit, stick_phases
    from .bifurcation.stable_manifold import manifold_seeds, stable_manifold
    from .bifurcation.synchrony import SyncStability, sync_stability


#: A layer not yet imported (``stickslip_fast.bifurcation``), imported on first use; each
#: layer does the same for its own submodules (base/lazy.py).
_submodule = submodule_getattr(__name__)


def __getattr__(name: str):
    """Import a public name of :data:`_LAZY`, or a layer, on first use and keep it (PEP 562)."""
    module = _LAZY.get(name)
    if module is None:
        return _submodule(name)
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__version__ = package_version()

__all__ = [
    "System",
    "simulate",
    "SimulationResult",
    "SynchronousStartWarning",
    "CoarseToleranceWarning",
    "sweep",
    "SweepResult",
    "load_sweep",
    "census",
    "CensusResult",
    "CensusPlaneResult",
    "load_census",
    "basins",
    "BasinsResult",
    "load_basins",
    "stable_manifold",
    "manifold_seeds",
    "StableManifold",
    "MODES",
    "largest_lyapunov",
    "LyapunovResult",
    "lyapunov_spectrum",
    "LyapunovSpectrum",
    "kaplan_yorke",
    "phases_from_events",
    "SyncResult",
    "sync_error",
    "sync_stability",
    "SyncStability",
    "find_orbit",
    "stick_phases",
    "Orbit",
    "find_equilibrium",
    "Equilibrium",
    "continue_orbit",
    "switch_branch",
    "continue_equilibrium",
    "join_branches",
    "Branch",
    "Bifurcation",
    "continue_bifurcation",
    "Curve",
    "Codim2Point",
    "checkpoint",
    "METHODS",
    "STATUS_NAMES",
    "PRESETS",
    "SWEEPABLE",
    "DEFAULT_RTOL",
    "DEFAULT_ATOL",
    "__version__",
]
