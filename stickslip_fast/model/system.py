"""System parameters: validation, the paper's presets, physical -> nondimensional.

Everything downstream (model, integrators, sweeps, files) reads parameters from
a :class:`System`. The compiled kernels get them packed into a float64 array by
:meth:`System.to_array`; :data:`PARAM_INDEX` maps a field name to its slot, so a
sweep can overwrite one slot per trajectory.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..base.messages import plain
from .params import ETA_MAX, ETA_MIN, N_PARAMS, P_ETAP, PARAM_INDEX, eta_prime

__all__ = [
    "System",
    "PARAM_INDEX",
    "SWEEPABLE",
    "DRIVES",
    "PRESETS",
    "ETA_MIN",
    "ETA_MAX",
    "dc_motor_constants",
    "SynchronousStartWarning",
    "warn_if_synchronous",
    "smallest_eps",
    "slowest_belt_speed",
]

DRIVES = ("constant", "dc-motor")

#: Fields a sweep may vary (the float fields; ``n_oscillators`` changes the state size).
SWEEPABLE = tuple(PARAM_INDEX)

_FLOAT_FIELDS = ("m", "k12", "c", "c12", "mu", "eps", "eta", "vb", "vb0", "Tb", "beta")

# The paper's parameter sets (nondimensional). "asymmetric" is its Eq. (nondimensional
# parameter values); for the constant-speed belt we take v_b = v_b0 (the belt runs at
# the motor's no-load speed, 0.05 m/s). The literature set (Eq. literature values)
# gives no motor data; for the DC motor we take v_b0 = v_b = 0.15 and the motor
# constants of the asymmetric set (T_b = 0.5, beta = 0.0014) -- see docs/model.md.
PRESETS: dict[str, dict[str, Any]] = {
    "literature": dict(
        m=90.0, k12=0.85, c=1e-4, c12=0.0, mu=5.0, eps=1e-5, eta=2.7,
        vb=0.15, vb0=0.15, Tb=0.5, beta=0.0014,
    ),
    "asymmetric": dict(
        m=2.0, k12=-0.8, c=0.0, c12=0.0, mu=0.0491, eps=1e-5, eta=1.5,
        vb=0.0112, vb0=0.0112, Tb=0.5, beta=0.0014,
    ),
    "symmetric": dict(
        m=2.0, k12=0.0, c=0.0, c12=0.0, mu=0.0491, eps=1e-5, eta=1.5,
        vb=0.0112, vb0=0.0112, Tb=0.5, beta=0.0014,
    ),
}  # fmt: skip


@dataclass(frozen=True)
class System:
    """Parameters of a chain of ``n_oscillators`` identical disks on belts.

    All quantities are the paper's nondimensional ones (Eqs. 4-6 and 15-18).
    The defaults are the paper's main set (asymmetric springs, eta = 1.5) on a
    constant-speed belt.

    Parameters
    ----------
    m : float
        Nondimensional moment of inertia, B / (m r^2). Must be > 0.
    k12 : float
        Stiffness coupling (k2 - k1) / (k1 + k2).
    c, c12 : float
        Damping matrix [[c, c12], [c12, c]]. Negative c (an energy source,
        "negative damping") is allowed: runaway motion is classified, not an error.
    mu : float
        Friction scale mu-bar (>= 0).
    eps : float
        Smoothing parameter eps-bar of the friction law. Must be > 0.
    eta : float
        Ratio of static to kinetic friction, in [1, 10] (the range of the paper's
        fit for eta').
    drive : {"constant", "dc-motor"}
        Constant belt speed ``vb``, or one DC motor shared by all disks.
    vb : float
        Belt speed of the constant drive.
    vb0, Tb, beta : float
        DC motor: no-load belt speed, time constant (> 0) and load coefficient (>= 0).
    n_oscillators : int
        Number of disks N >= 1.
    """

    m: float = 2.0
    k12: float = -0.8
    c: float = 0.0
    c12: float = 0.0
    mu: float = 0.0491
    eps: float = 1e-5
    eta: float = 1.5
    drive: str = "constant"
    vb: float = 0.0112
    vb0: float = 0.0112
    Tb: float = 0.5
    beta: float = 0.0014
    n_oscillators: int = 1
    _n_state: int = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in _FLOAT_FIELDS:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(
                value, (int, float, np.floating, np.integer)
            ):
                raise ValueError(f"System.{name} must be a real number, got {plain(value)}")
            value = float(value)
            if not math.isfinite(value):
                raise ValueError(f"System.{name} must be finite, got {plain(value)}")
            object.__setattr__(self, name, value)
        if self.m <= 0:
            raise ValueError(f"System.m must be > 0, got {plain(self.m)}")
        if self.eps <= 0:
            raise ValueError(f"System.eps must be > 0, got {plain(self.eps)}")
        if self.Tb <= 0:
            raise ValueError(f"System.Tb must be > 0, got {plain(self.Tb)}")
        # friction scale and motor load are products of positive physical constants (Eqs. 6,
        # 18); negative values would make friction drive the disk (docs/model.md)
        for name in ("mu", "beta"):
            if getattr(self, name) < 0:
                raise ValueError(
                    f"System.{name} must be >= 0 (it scales the friction force; a negative "
                    f"value has no physical meaning), got {getattr(self, name)!r}"
                )
        if not ETA_MIN <= self.eta <= ETA_MAX:
            raise ValueError(
                f"System.eta must lie in [{ETA_MIN}, {ETA_MAX}] (the range of the paper's "
                f"fit for eta'; no extrapolation), got {plain(self.eta)}"
            )
        if self.drive not in DRIVES:
            raise ValueError(f"System.drive must be one of {DRIVES}, got {self.drive!r}")
        n = self.n_oscillators
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"System.n_oscillators must be an integer >= 1, got {n!r}")
        object.__setattr__(self, "n_oscillators", int(n))
        object.__setattr__(self, "_n_state", 4 * int(n) + (1 if self.drive == "dc-motor" else 0))

    # ------------------------------------------------------------------ presets
    @classmethod
    def preset(cls, name: str, **overrides: Any) -> System:
        """One of the paper's parameter sets, with optional field overrides.

        Parameters
        ----------
        name : {"literature", "asymmetric", "symmetric"}
            ``"literature"``: the paper's Eq. (literature parameter values), used
            for Figs. 2, 3, 9. ``"asymmetric"``: its main set (Eq. nondimensional
            parameter values), k12 = -0.8. ``"symmetric"``: the same with k12 = 0.
        **overrides
            Any :class:`System` field, e.g. ``drive="dc-motor", n_oscillators=2``.

        Raises
        ------
        ValueError
            For an unknown preset name or field, or an invalid value.
        """
        if name not in PRESETS:
            raise ValueError(f"unknown preset {name!r}; choose one of {sorted(PRESETS)}")
        return cls.from_dict({**PRESETS[name], **overrides})

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> System:
        """Build a System from a mapping, rejecting unknown keys by name."""
        allowed = {f.name for f in dataclasses.fields(cls) if f.init}
        unknown = sorted(set(values) - allowed)
        if unknown:
            raise ValueError(f"unknown System field(s) {unknown}; allowed: {sorted(allowed)}")
        return cls(**values)

    @classmethod
    def from_physical(
        cls,
        m_hat: float,
        r_hat: float,
        B_hat: float,
        k1_hat: float,
        k2_hat: float,
        c1_hat: float = 0.0,
        c2_hat: float = 0.0,
        vb_hat: float = 0.05,
        mu: float = 1.0,
        g: float = 9.81,
        *,
        eps: float = 1e-5,
        eta: float = 1.5,
        drive: str = "constant",
        Tb: float = 0.5,
        beta: float = 0.0014,
        n_oscillators: int = 1,
    ) -> System:
        """Nondimensionalise the physical quantities with the paper's formulas (Eq. 6).

        alpha = sqrt((k1 + k2) / m), m = B / (m r^2), k12 = (k2 - k1) / (k1 + k2),
        c = (c1 + c2) / sqrt(m (k1 + k2)), c12 = (c2 - c1) / sqrt(m (k1 + k2)),
        mu-bar = mu m g / (r (k1 + k2)), v_b = v_b_hat / (alpha r).

        The belt speed ``vb_hat`` gives both the constant drive's ``vb`` and the
        motor's no-load speed ``vb0``. ``eps``, ``Tb`` and ``beta`` are passed
        nondimensional (use :func:`dc_motor_constants` for the motor's).

        Examples
        --------
        >>> s = System.from_physical(5, 0.1, 0.1, 9000, 1000, vb_hat=0.05, mu=1, g=9.81)
        >>> round(s.m, 6), round(s.k12, 6), round(s.mu, 4), round(s.vb0, 4)
        (2.0, -0.8, 0.0491, 0.0112)
        """
        named = dict(m_hat=m_hat, r_hat=r_hat, B_hat=B_hat, k1_hat=k1_hat, k2_hat=k2_hat)
        for name, value in named.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be finite and > 0, got {plain(value)}")
        for name, value in dict(c1_hat=c1_hat, c2_hat=c2_hat, vb_hat=vb_hat, mu=mu, g=g).items():
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {plain(value)}")
        k_sum = k1_hat + k2_hat
        alpha = math.sqrt(k_sum / m_hat)
        damp = math.sqrt(m_hat * k_sum)
        vb = vb_hat / (alpha * r_hat)
        return cls(
            m=B_hat / (m_hat * r_hat**2),
            k12=(k2_hat - k1_hat) / k_sum,
            c=(c1_hat + c2_hat) / damp,
            c12=(c2_hat - c1_hat) / damp,
            mu=mu * m_hat * g / (r_hat * k_sum),
            eps=eps,
            eta=eta,
            drive=drive,
            vb=vb,
            vb0=vb,
            Tb=Tb,
            beta=beta,
            n_oscillators=n_oscillators,
        )

    # ------------------------------------------------------------ conveniences
    def replace(self, **changes: Any) -> System:
        """A copy with some fields changed (validated again)."""
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self) if f.init})
        if unknown:
            raise ValueError(f"unknown System field(s) {unknown}")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """All init fields as plain Python values (for files and configs)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.init}

    @property
    def n_state(self) -> int:
        """Length of the state vector: 4 N, plus 1 for the DC motor's belt speed."""
        return self._n_state

    @property
    def state_names(self) -> list[str]:
        """Column names of every state array: x1, dx1, phi1, dphi1, ..., [vb]."""
        names = []
        for i in range(1, self.n_oscillators + 1):
            names += [f"x{i}", f"dx{i}", f"phi{i}", f"dphi{i}"]
        if self.drive == "dc-motor":
            names.append("vb")
        return names

    @property
    def is_dc_motor(self) -> bool:
        return self.drive == "dc-motor"

    def to_array(self) -> np.ndarray:
        """Pack the float parameters for the compiled kernels (see PARAM_INDEX)."""
        p = np.zeros(N_PARAMS)
        for name, idx in PARAM_INDEX.items():
            p[idx] = getattr(self, name)
        # the compiled fit's Python source: the same IEEE arithmetic (tests/test_jit_entry.py),
        # without compiling its entry twin in every first run (base.jit)
        p[P_ETAP] = eta_prime.py_func(self.eta)
        return p

    def initial_state(self, y0: Any = None) -> np.ndarray:
        """Validate an initial state; ``None`` is the zero state (v_b(0) = 0)."""
        if y0 is None:
            return np.zeros(self.n_state)
        try:
            y = np.asarray(y0, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"y0 must be an array of {self.n_state} numbers: {exc}") from None
        if y.ndim != 1 or y.size != self.n_state:
            raise ValueError(
                f"y0 must have length {self.n_state} ({', '.join(self.state_names)}), "
                f"got shape {y.shape}"
            )
        if not np.all(np.isfinite(y)):
            raise ValueError("y0 must be finite")
        return y.copy()

    def synchronous_start(self, y: np.ndarray) -> bool:
        """Whether ``y`` starts every disk in disk 1's state on a shared DC motor (N >= 2).

        The disks are identical and the model treats each alike, so disks started
        alike stay alike to the last bit: such a run sees only the synchronous
        (in-phase) subspace, whatever its stability across the disks. On a constant
        belt the disks are uncoupled and each simply follows its own attractor.
        """
        if not self.is_dc_motor or self.n_oscillators < 2:
            return False
        disks = np.asarray(y, dtype=float)[: 4 * self.n_oscillators].reshape(-1, 4)
        return bool(np.all(disks == disks[0]))


class SynchronousStartWarning(UserWarning):
    """N >= 2 disks on one DC motor start in one state, so the run stays in phase.

    The run then explores only the invariant synchronous subspace: its period and
    status are right for that motion, but an in-phase orbit can be unstable across
    the disks (e.g. the symmetric set at eta = 5: leading multiplier 1.09), so the
    slightest difference between the disks would leave it. Give the disks
    different starts (the paper's Figs. 14-18 do) or check the orbit's stability
    across the disks with :func:`~stickslip_fast.sync_stability`.
    """


def warn_if_synchronous(system: System, what: str, stacklevel: int) -> None:
    """Warn (:class:`SynchronousStartWarning`) if ``system``'s default start, the zero
    state, puts its disks alike on a shared DC motor. ``what`` names the start."""
    if system.synchronous_start(system.initial_state(None)):
        warnings.warn(
            f"{what} puts all {system.n_oscillators} disks in the same state on one DC "
            "motor, so they stay identical to the last bit and the result describes in-phase "
            "motion only, which can be unstable across the disks; give the disks different "
            "starts (y0), or check the orbit's stability across the disks with "
            "sync_stability(find_orbit(...))",
            SynchronousStartWarning,
            stacklevel=stacklevel + 1,
        )


def smallest_eps(system: System, names=(), axes=()) -> float:
    """The smallest eps a run of ``system`` over the swept ``names`` / ``axes`` meets: the
    swept values where eps is swept, else the system's own."""
    swept = [float(np.min(a)) for n, a in zip(names, axes, strict=True) if n == "eps" and len(a)]
    return min(swept) if swept else system.eps


def slowest_belt_speed(system: System, names=(), axes=()) -> float | None:
    """The smallest nonzero belt speed |v_b| (|v_b0| on a DC motor) that a run of
    ``system`` over the swept ``names`` / ``axes`` meets: the swept values where the
    field is swept, else the system's own; None if every one is 0."""
    field = "vb0" if system.is_dc_motor else "vb"
    swept = [np.asarray(a, dtype=float) for n, a in zip(names, axes, strict=True) if n == field]
    speeds = np.abs(np.concatenate(swept)) if swept else np.array([abs(getattr(system, field))])
    moving = speeds[speeds > 0]
    return float(moving.min()) if moving.size else None


def dc_motor_constants(
    R: float,
    K_E: float,
    K_T: float,
    i_g: float,
    I_hat: float,
    c_hat: float,
    r_b: float,
    u: float,
    alpha: float,
    r_hat: float,
    n_oscillators: int = 1,
) -> dict[str, float]:
    """The DC motor's nondimensional constants (the paper's Eq. 18).

    T_b = alpha R I / (R c + K_E K_T i_g^2),
    v_b0 = r_b K_T i_g u / (alpha r (R c + K_E K_T i_g^2)),
    beta = N r_b K_T i_g / (alpha r (R c + K_E K_T i_g^2)).

    The paper's beta carries the friction scale through the belt equation's
    T_s term exactly as printed; it is reproduced here as printed.
    """
    den = R * c_hat + K_E * K_T * i_g**2
    if den == 0:
        raise ValueError("R c_hat + K_E K_T i_g^2 must be nonzero")
    return {
        "Tb": alpha * R * I_hat / den,
        "vb0": r_b * K_T * i_g * u / (alpha * r_hat * den),
        "beta": n_oscillators * r_b * K_T * i_g / (alpha * r_hat * den),
    }
