"""A corpus of random runs for the classification tests (issue 26).

Each case is a random (drive, N, eta, start) of a parameter set (the asymmetric one
unless ``preset`` says another). A case is run twice through the sweep kernels: with the documented defaults (only
``t_end`` given) and *settled* (3x longer, points and rest judged on the last
third). :func:`verdict` sets a label against the settled one.
"""

from __future__ import annotations

import numpy as np

import stickslip_fast as ssf
from stickslip_fast.analysis.census import default_box
from stickslip_fast.backends.local import compute_restart_chunk
from stickslip_fast.base.status import STATUS_NAMES
from stickslip_fast.core.settings import Settings, system_defaults

T_END = 3000.0
SETTLED = {"t_end": 9000.0, "t_transient": 6000.0}
DRIVES = ("constant", "dc-motor")


def system_of(drive: str, n_osc: int, preset: str = "asymmetric") -> ssf.System:
    return ssf.System.preset(preset, drive=drive, n_oscillators=n_osc)


def start_of(system: ssf.System, eta: float, u: np.ndarray) -> np.ndarray:
    """The start in the census's default box at ``eta`` for uniform numbers ``u`` in [0, 1)."""
    box = default_box(system.replace(eta=eta))
    return box[:, 0] + u[: system.n_state] * (box[:, 1] - box[:, 0])


def random_cases(
    n: int, seed: int, preset: str = "asymmetric"
) -> list[tuple[str, int, float, np.ndarray]]:
    """``n`` cases (drive, N, eta, start); a fifth of them from the zero state."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(n):
        drive = DRIVES[int(rng.integers(2))]
        n_osc = int(rng.integers(1, 3))
        eta = float(rng.uniform(1.0, 10.0))
        system = system_of(drive, n_osc, preset)
        u = rng.random(9)
        y0 = system.initial_state(None) if rng.random() < 0.2 else start_of(system, eta, u)
        cases.append((drive, n_osc, eta, y0))
    return cases


def run(
    cases,
    preset: str = "asymmetric",
    eps: float | None = None,
    vb: float | None = None,
    **settings,
) -> list[tuple[str, int]]:
    """(status, period) of every case, the cases of one (drive, N) in one parallel chunk;
    with ``eps`` or ``vb``, of the preset with that eps or belt speed (``vb`` and
    ``vb0``). atol, equilibrium_tol and dwell not given take their defaults for the
    system, as in ``sweep``."""
    out: list[tuple[str, int] | None] = [None] * len(cases)
    for drive in DRIVES:
        for n_osc in (1, 2):
            idx = [k for k, c in enumerate(cases) if c[0] == drive and c[1] == n_osc]
            if not idx:
                continue
            etas = np.array([[cases[k][2]] for k in idx])
            y0s = np.array([cases[k][3] for k in idx])
            system = system_of(drive, n_osc, preset)
            if eps is not None:
                system = system.replace(eps=eps)
            if vb is not None:
                system = system.replace(vb=vb, vb0=vb)
            atol, eq_tol, dwell = system_defaults(
                system, atol=settings.get("atol"),
                equilibrium_tol=settings.get("equilibrium_tol"), dwell=settings.get("dwell"),
            )  # fmt: skip
            s = Settings.resolve(**dict(settings, atol=atol, equilibrium_tol=eq_tol, dwell=dwell))
            res = compute_restart_chunk(system, ("eta",), etas, y0s, s)
            for j, k in enumerate(idx):
                out[k] = (STATUS_NAMES[int(res["status"][j])], int(res["period"][j]))
    return out  # type: ignore[return-value]


def verdict(label: tuple[str, int], settled: tuple[str, int]) -> str:
    """``same``, ``false`` (claims more than the settled run: another period, rest where
    it moves, motion where it rests) or ``none found`` (period 0 where the settled run
    has one, or ``unsettled``: an honest "not found" or "not decided")."""
    if label == settled:
        return "same"
    if (label == ("ok", 0) and settled[0] == "ok") or label[0] == "unsettled":
        return "none found"
    return "false"
