"""Pseudo-arclength continuation of orbits and equilibria: the public face of its pieces.

:func:`continue_orbit` follows a fixed point z(s) of P^p(., lambda) in (z, lambda), where
lambda is one :class:`System` field, through folds onto the unstable side. At every point it
records the Floquet multipliers (the variational Jacobian of :mod:`.orbits`)
and detects and locates folds (lambda turns back; a multiplier through +1),
period-doublings (a real multiplier through -1) and Neimark-Sacker points (a complex pair
through the unit circle). The method and its limits: docs/orbits.md.

The pieces: :mod:`.arclength` (the predictor-corrector and the locators, on any smooth map given as a
callable, tested on maps whose bifurcations are known in closed form), :mod:`.detection`
(the test functions), :mod:`.orbit_branch` (orbits), :mod:`.switching` (branch
switching at a period-doubling), :mod:`.equilibrium_branch` (equilibria) and
:mod:`.branch` (the :class:`Branch` record and its file). This module re-exports them.
"""

from __future__ import annotations

from .arclength import (  # noqa: F401
    STALL_WINDOW,
    _restart,
    pseudo_arclength,
)
from .branch import (  # noqa: F401
    BRANCH_SCHEMA,
    READABLE_BRANCH_SCHEMAS,
    Bifurcation,
    Branch,
    join_branches,
)
from .corrector import (  # noqa: F401
    NOISE_FLOOR,
    Evaluator,
    _correct,
    _locate,
    _locate_change,
    _round_off_floor,
    _tangent,
)
from .detection import (  # noqa: F401
    _eigs_by_real_part,
    _equilibrium_tests,
    _sorted_eigs,
    _tests,
)
from .equilibrium_branch import (  # noqa: F401
    continue_equilibrium,
)
from .orbit_branch import (  # noqa: F401
    SHARP_END_STAGES,
    _orbit_evaluator,
    continue_orbit,
)
from .switching import (  # noqa: F401
    SWITCH_DELTAS,
    period_doubling_start,
    switch_branch,
)
from .walk_args import _check_args, _difference  # noqa: F401

__all__ = [
    "Branch",
    "Bifurcation",
    "continue_equilibrium",
    "continue_orbit",
    "join_branches",
    "period_doubling_start",
    "pseudo_arclength",
    "switch_branch",
    "BRANCH_SCHEMA",
    "SHARP_END_STAGES",
]
