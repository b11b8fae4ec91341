"""Analyses of trajectories: Lyapunov exponents and synchronization (re-exported).

The Lyapunov exponent lives in :mod:`stickslip_fast.lyapunov` (the tangent
problem on the one driver), synchronization in :mod:`stickslip_fast.sync`; the
variational pieces of the model in :mod:`stickslip_fast.model`.
"""

from __future__ import annotations

from .lyapunov import LyapunovResult, largest_lyapunov, lyapunov_kernel
from .model import second_derivative_form, tangent_rhs
from .sync import SyncResult, event_times, phases_from_events, sync_error, wrap_phase

__all__ = [
    "LyapunovResult",
    "largest_lyapunov",
    "lyapunov_kernel",
    "tangent_rhs",
    "second_derivative_form",
    "SyncResult",
    "event_times",
    "phases_from_events",
    "sync_error",
    "wrap_phase",
]
