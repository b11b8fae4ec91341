"""The record of a two-parameter curve of codim-1 points: :class:`Curve`, :class:`Codim2Point`
(file schema: docs/file-format.md, "Curve files")."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np


@dataclass
class Codim2Point:
    """A codim-2 point on a :class:`Curve`: ``kind`` (see :attr:`Curve.codim2`), ``values``
    (the branch's parameter, ``param2``), ``index`` (the curve point before it) and
    ``point`` (the orbit's state on the section there, or the equilibrium's state)."""

    kind: str
    values: np.ndarray
    index: int
    point: np.ndarray


@dataclass
class Curve:
    """A curve of codim-1 points of periodic orbits or equilibria in two parameters.

    Attributes
    ----------
    system : System
        The system of the start (at the start's values of both parameters).
    param, param2 : str
        The branch's parameter and the second one.
    kind : str
        The codim-1 kind followed: "fold", "period-doubling", "neimark-sacker",
        "symmetry-breaking" or "stick-phase" (orbits), "fold" or "hopf" (equilibria).
    period : int
        Section crossings per period of the orbits; 0 for equilibria.
    values : ndarray, shape (k, 2)
        (param, param2) along the curve.
    points : ndarray, shape (k, n_state)
        The orbit's state on the section at each point (equilibria: the state).
    T : ndarray, shape (k,)
        Period in time (equilibria: NaN on a fold curve, 2 pi / omega on a Hopf curve,
        NaN past a Bogdanov-Takens point where omega^2 < 0).
    multipliers : ndarray of complex, shape (k, n_state - 1)
        Floquet multipliers (one is +1 on a fold curve, -1 on a period-doubling curve,
        up to the sharpness of the fold: where the multiplier changes by O(1) over
        1e-10 in the state, as on Fig. 6's lower fold in v_b, it can read 1.2-1.4);
        for equilibria, shape (k, n_state): the Jacobian's eigenvalues, largest real
        part first.
    codim2 : list of Codim2Point
        On every curve: "cusp" (the curve's parameter-plane tangent vanishes) and
        "extremum" (the curve turns back in ``param2``: beyond it, at fixed ``param2``,
        the two codim-1 points met and vanished). Orbits (the second multiplier):
        "1:1" (+1 on a fold curve), "fold-flip" (-1 on a fold curve, +1 on a
        period-doubling curve), "1:2" (-1 on a period-doubling curve); on a
        Neimark-Sacker curve (:mod:`~stickslip_fast.bifurcation.nscurve`) "1:1" and
        "1:2" (theta = 0, pi: the curve ends there), "1:3" and "1:4" (theta = 2 pi / 3,
        pi / 2), "fold-ns" and "flip-ns" (another multiplier at +1, -1). Equilibria:
        "bogdanov-takens" (a second zero eigenvalue on a fold curve; omega -> 0 on a
        Hopf curve), "zero-hopf" (a pair +-i omega on a fold curve; a zero eigenvalue
        on a Hopf curve), "bautin" (the Hopf curve's first Lyapunov coefficient
        changes sign). Symmetry-breaking curves: "1:1" and "fold-flip" (a multiplier of
        the whole map other than the transverse +1 at +1 or -1: e.g. the curve meets a
        fold of the in-phase orbits). Orbit curves, with ``stick_events``:
        "stick-phase" (the orbit's count of stick phases changes); at a curve's end,
        "section-grazing" (the orbit grazes the section there, so the curve stops).
    status : str
        How the curve ended (:func:`~stickslip_fast.bifurcation.arclength.pseudo_arclength`'s
        statuses, or "start-failed"; a Neimark-Sacker curve also "1:1" or "1:2": it
        ended at that resonance, its last point; or "no-complex-pair": the start has
        no complex multipliers).
    theta : ndarray, shape (k,), optional
        Neimark-Sacker curves: the angle of the critical multipliers e^{+-i theta}, in
        [0, pi] (None on other curves).
    event : dict, optional
        Stick-phase curves (:mod:`~stickslip_fast.bifurcation.stickcurve`): the
        slip-speed extremum followed, ``{"disk": int (0-based), "extremum": "min" or
        "max", "threshold": the stick speed in units of eps}`` (None on other curves).
    event_time : ndarray, shape (k,), optional
        Stick-phase curves: the time t* of the extremum after the orbit's point on the
        section (``points``).
    """

    system: Any
    param: str
    param2: str
    kind: str
    period: int
    values: np.ndarray
    points: np.ndarray
    T: np.ndarray
    multipliers: np.ndarray
    codim2: list[Codim2Point] = field(default_factory=list)
    status: str = ""
    theta: np.ndarray | None = None
    event: dict | None = None
    event_time: np.ndarray | None = None

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the curve (schema: docs/file-format.md, "Curve files")."""
        from ..io.curvefile import write_curve

        return write_curve(path, {
            "param": self.param, "param2": self.param2, "curve_kind": self.kind,
            "period": int(self.period), "status": self.status,
            "system": json.dumps(self.system.to_dict()), "values": self.values,
            "points": self.points, "T": self.T, "multipliers_real": self.multipliers.real,
            "multipliers_imag": self.multipliers.imag,
            "codim2_kind": [c.kind for c in self.codim2],
            "codim2_values": [c.values for c in self.codim2],
            "codim2_index": [c.index for c in self.codim2],
            "codim2_point": [c.point for c in self.codim2], "theta": self.theta,
            "event_time": self.event_time,
            "event": None if self.event is None else json.dumps(self.event),
        })  # fmt: skip

    @classmethod
    def from_hdf5(cls, path: str | Path) -> Curve:
        """Read a curve file written by :meth:`to_hdf5` (ValueError for another file)."""
        from ..io.curvefile import read_curve
        from ..model.system import System

        d = read_curve(path)
        codim2 = [Codim2Point(k, np.array(v), int(i), np.array(p)) for k, v, i, p in
                  zip(d["codim2_kind"], d["codim2_values"], d["codim2_index"], d["codim2_point"])]  # fmt: skip
        return cls(
            system=System.from_dict(json.loads(d["system"])), param=str(d["param"]),
            param2=str(d["param2"]), kind=str(d["curve_kind"]), period=int(d["period"]),
            values=d["values"], points=d["points"], T=d["T"],
            multipliers=d["multipliers_real"] + 1j * d["multipliers_imag"], codim2=codim2,
            status=str(d["status"]), theta=d.get("theta"),
            event_time=d.get("event_time"),
            event=None if d.get("event") is None else json.loads(d["event"]),
        )  # fmt: skip
