"""Analyses built on the core: one run, sweeps, the attractor census, Lyapunov exponents, sync.

One run is :mod:`.simulate`, a bifurcation sweep :mod:`.sweep` (its result
:mod:`.sweep_result`), the census :mod:`.census` (with :mod:`.census_classify`).
Re-exported here: the Lyapunov exponents of :mod:`.lyapunov` (the tangent
problem on the one driver, :mod:`.lyapunov_kernel`), synchronization from :mod:`.sync`, and the
variational pieces of the model from :mod:`stickslip_fast.model.equations`.
"""

from __future__ import annotations

from ..model.equations import second_derivative_form, tangent_rhs
from .lyapunov import LyapunovResult, largest_lyapunov, lyapunov_kernel
from .lyapunov_spectrum import LyapunovSpectrum, kaplan_yorke, lyapunov_spectrum
from .sync import SyncResult, event_times, phases_from_events, sync_error, wrap_phase

__all__ = [
    "LyapunovResult",
    "largest_lyapunov",
    "LyapunovSpectrum",
    "lyapunov_spectrum",
    "kaplan_yorke",
    "lyapunov_kernel",
    "tangent_rhs",
    "second_derivative_form",
    "SyncResult",
    "event_times",
    "phases_from_events",
    "sync_error",
    "wrap_phase",
]

from ..base.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use
