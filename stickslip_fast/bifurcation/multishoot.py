"""Multiple shooting for periodic orbits, and Floquet multipliers from a periodic QR scheme.

A periodic orbit of period T is cut evenly in time into m segments. The unknowns are the
segment starts y_0, ..., y_{m-1} and T; y_0 lies on the Poincare section (dx1 = 0, its
section coordinate is not an unknown: the phase condition), so there are
(n - 1) + (m - 1) n + 1 = m n unknowns for the m n continuity equations

    G_i = phi(y_i, T / m) - y_{(i + 1) mod m} = 0,        i = 0, ..., m - 1.

Their Jacobian is block-cyclic: dG_i/dy_i = Phi_i (the segment's state-transition matrix,
from the variational equations of :mod:`stickslip_fast.core.variational`),
dG_i/dy_{i+1} = -I, dG_i/dT = f(phi(y_i, T/m)) / m, and with a parameter lambda
dG_i/dlambda = s_i (the parameter sensitivity, integrated from 0 over the segment).
No segment carries the whole amplification of the orbit: an unstable orbit with
multiplier mu is solved with each segment amplifying by roughly mu^(1/m).

The nontrivial Floquet multipliers are the eigenvalues of the section Jacobian
D P = E^T Pi Phi_{m-1} ... Phi_0 E (E: the section coordinates, Pi: the projection along
the flow onto the section at the end, :mod:`.orbits`). :func:`periodic_multipliers`
computes them from the factors without forming the product: sweeps of QR factorisations
(a periodic QR / subspace iteration), then the eigenvalues of the similar matrix
(Q_0^T Q_m) R_{m-1} ... R_0, whose triangular factors are multiplied with a running scale
factor kept as a logarithm.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from ..base.interrupt import call_interruptible, new_abort_flag
from ..base.journal import call_journaled
from ..base.threads import finish, shared_pool, submit, thread_count
from ..core.poincare import STATUS_NAMES
from ..core.trajectory import kernel_variant
from ..core.variational import propagate_sensitivity, propagate_tangents
from ..model.system import System
from .returnmap import _MAX_STEPS, SECTION_INDEX, _field, _sensitivity_params

__all__ = [
    "periodic_multipliers", "MultiShooting", "refine_mesh", "remesh", "DEFAULT_SEGMENTS",
]  # fmt: skip

#: Segments per period when none are asked for.
DEFAULT_SEGMENTS = 8

#: Continuation by multiple shooting bisects the start's segments until none amplifies
#: by more than this (2-norm of its state-transition matrix; :func:`refine_mesh`): past a
#: sharp fold nearly all of an orbit's amplification happens in the short passage near
#: the capture into a stick phase, which even cuts leave in one segment.
MESH_LIMIT = 10.0

#: A continuation with ``remesh=True`` cuts the segments again (:func:`remesh`) where one
#: amplifies by more than this (the norm of its factor of the section Jacobian).
REMESH_LIMIT = 10.0 * MESH_LIMIT

#: The most segments a mesh gets (:func:`refine_mesh`, :func:`remesh`).
MAX_SEGMENTS = 64


def periodic_multipliers(
    factors: list[np.ndarray], max_sweeps: int = 12, tol: float = 1e-13, block_tol: float = 1e-10
) -> np.ndarray:
    """Eigenvalues of the product ``factors[-1] @ ... @ factors[0]`` without forming it.

    Parameters
    ----------
    factors : list of ndarray
        A_0 (n x k), A_1, ..., A_{m-1} (k x n): a product mapping R^k to R^k. Middle
        factors are n x n.
    max_sweeps : int
        Most QR sweeps around the period.
    tol : float
        The sweeps stop when Q, the basis at the period's end, equals the basis at its
        start to this tolerance (up to signs).
    block_tol : float
        Where the basis has not converged (a complex pair, or moduli too close to
        separate), the diagonal blocks coupled by entries above this are kept
        together and their eigenvalues taken from the block's product.

    Returns
    -------
    ndarray of complex, shape (k,)
        The eigenvalues, largest modulus first (moduli above ~1e308 are inf).
    """
    k = factors[0].shape[1]
    Q0 = np.eye(k)
    for _ in range(max(1, max_sweeps)):
        Q = Q0
        Rs = []
        for A in factors:
            Q, R = np.linalg.qr(A @ Q)
            Rs.append(R)
        C = Q0.T @ Q  # ~ a signed permutation-free diagonal (or 2x2 rotations) once converged
        done = float(np.max(np.abs(np.abs(np.diag(C)) - 1.0))) <= tol
        if done:
            break
        Q0 = Q
    ev = np.concatenate([_block_eigs(C, Rs, b) for b in _blocks(C, block_tol)])
    return ev[np.argsort(-np.abs(ev), kind="stable")]


def _blocks(C: np.ndarray, thr: float) -> list[slice]:
    """Diagonal blocks of C: a block ends at k where C below-left of (k, k) is below thr."""
    k = C.shape[0]
    out, start = [], 0
    for j in range(k):
        if j == k - 1 or float(np.max(np.abs(C[j + 1 :, : j + 1]))) <= thr:
            out.append(slice(start, j + 1))
            start = j + 1
    return out


def _block_eigs(C: np.ndarray, Rs: list[np.ndarray], b: slice) -> np.ndarray:
    """Eigenvalues of C[b, b] R_{m-1}[b, b] ... R_0[b, b], the product scaled as it grows
    (its scale kept as a logarithm, so that no partial product overflows)."""
    P = np.eye(b.stop - b.start)
    log_scale = 0.0
    for R in Rs:
        P = R[b, b] @ P
        s = float(np.max(np.abs(P)))
        if s > 0 and math.isfinite(s):
            P = P / s
            log_scale += math.log(s)
    ev = np.linalg.eigvals(C[b, b] @ P).astype(complex)
    if log_scale > 709.0:  # beyond the floating-point range: their moduli are inf
        return np.full(ev.shape, complex(np.inf, 0.0))
    return ev * math.exp(log_scale)


class MultiShooting:
    """The multiple-shooting system of one :class:`System` (a period cut into m segments).

    Parameters
    ----------
    system : System
    segments : int or array_like
        m >= 1 (even cuts), or the mesh: m + 1 increasing fractions of the period from
        0 to 1 (segment i runs over [mesh[i] T, mesh[i + 1] T]; :func:`refine_mesh`).
    rtol, atol, tangent_atol : float
        Integration tolerances (those of :func:`~stickslip_fast.bifurcation.returnmap.return_map`).
    param : str, optional
        A parameter whose sensitivity :meth:`evaluate` adds as the Jacobian's last column.
    param_step : float
        Relative step of the vector field's difference in ``param``.

    The unknown vector u = (y_0 without dx1, y_1, ..., y_{m-1}, T) has m n entries.
    """

    def __init__(self, system: System, segments: int, rtol: float, atol: float,
                 tangent_atol: float, param: str | None = None,
                 param_step: float = 1e-7) -> None:  # fmt: skip
        self.system = system
        if np.ndim(segments) == 0:
            self.mesh = np.linspace(0.0, 1.0, int(segments) + 1)
        else:
            self.mesh = np.asarray(segments, dtype=float)
        self.m = self.mesh.size - 1
        self.frac = np.diff(self.mesh)
        self.n = system.n_state
        self.mask = np.arange(self.n) != SECTION_INDEX
        self.kw = (float(rtol), float(atol), float(tangent_atol))
        self.param = param
        self.sens = _sensitivity_params(system, param, param_step)

    # -------------------------------------------------------------- packing
    def pack(self, Y: np.ndarray, T: float) -> np.ndarray:
        return np.r_[Y[0][self.mask], Y[1:].ravel(), T]

    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        n, m = self.n, self.m
        Y = np.empty((m, n))
        Y[0] = 0.0
        Y[0][self.mask] = u[: n - 1]
        Y[1:] = u[n - 1 : m * n - 1].reshape(m - 1, n)
        return Y, float(u[-1])

    # ------------------------------------------------------------- segments
    def flow(self, y: np.ndarray, tau: float, tangents: bool = True, abort=None):
        """(status, phi(y, tau), Phi (n x n, or with the sensitivity n x (n + 1)) or None).
        ``abort``: the flag that stops the integration (default: a flag of its own)."""
        abort = new_abort_flag() if abort is None else abort
        n = self.n
        rtol, atol, tatol = self.kw
        s = self.system
        variant = kernel_variant(s.n_oscillators, s.is_dc_motor)
        U = np.eye(n) if tangents else np.eye(n)[:, :1]
        sens_p, sens_inv = self.sens if tangents else (None, 0.0)
        if sens_p is not None:
            U = np.hstack([U, np.zeros((n, 1))])
        args = (np.ascontiguousarray(y, dtype=float), np.ascontiguousarray(U), s.to_array(),
                s.n_oscillators, s.is_dc_motor, variant, float(tau), 0, rtol, atol, tatol)  # fmt: skip
        if sens_p is None:
            code, y1, U1, _ = call_journaled(propagate_tangents, *args, _MAX_STEPS, abort=abort)
        else:
            code, y1, U1, _ = call_journaled(
                propagate_sensitivity, *args, sens_p, sens_inv, _MAX_STEPS, abort=abort
            )
        status = STATUS_NAMES[code]
        if status == "ok" and not np.all(np.isfinite(y1)):
            status = "nonfinite"
        return status, y1, (U1 if tangents else None)

    def evaluate(self, u: np.ndarray):
        """(status, G (m n,), DG (m n x m n [+ 1]), factors of the section Jacobian)."""
        n, m, mask = self.n, self.m, self.mask
        Y, T = self.unpack(u)
        if not (math.isfinite(T) and T > 0):
            return "bad-period", None, None, None
        N = m * n
        extra = 1 if self.sens[0] is not None else 0
        G = np.empty(N)
        DG = np.zeros((N, N + extra))
        phis = []
        for i, (st, y1, U1) in enumerate(self.segment_flows(Y, T)):
            if st != "ok":
                return st, None, None, None
            r = slice(i * n, (i + 1) * n)
            j = (i + 1) % m
            G[r] = y1 - Y[j]
            Phi = U1[:, :n]
            phis.append(Phi)
            DG[r, self._cols(i)] = Phi[:, mask] if i == 0 else Phi
            DG[r, self._cols(j)] -= np.eye(n)[:, mask] if j == 0 else np.eye(n)
            DG[r, N - 1] = _field(self.system, y1) * self.frac[i]
            if extra:
                DG[r, N] = U1[:, n]
            if i == m - 1:
                f_end = _field(self.system, y1)
        return "ok", G, DG, self.section_factors(phis, f_end)

    def segment_flows(self, Y: np.ndarray, T: float) -> Iterable[tuple]:
        """:meth:`flow` of every segment (starts Y, period T), in order.

        The segments are independent, so they run on up to ``numba.get_num_threads()``
        threads (the kernel releases the GIL); each is the same sequential integration
        whichever thread runs it, so the results do not depend on the thread count.
        Ctrl-C stops them all (one flag, armed in the calling thread).
        """
        taus = [float(self.frac[i] * T) for i in range(self.m)]
        threads = thread_count(self.m)
        if threads == 1:  # lazily: a caller that stops at a failed segment runs no more
            return (self.flow(Y[i], taus[i]) for i in range(self.m))

        # not run_concurrently: there the calling thread takes a share, and here it runs
        # inside call_interruptible's armed region, where a SIGINT that lands in a nested
        # compiled call surfaced as SystemError (tests/test_multishoot_threads.py, Ctrl-C);
        # the calling thread only waits
        def run_all(abort: np.ndarray) -> list[tuple]:
            pool = shared_pool(threads)
            futures = [submit(pool, self.flow, Y[i], taus[i], True, abort) for i in range(self.m)]
            try:
                return [f.result() for f in futures]
            finally:  # on Ctrl-C the running segments stop on the flag, the others never start
                finish(futures)

        return call_interruptible(run_all, abort=new_abort_flag())

    def _cols(self, i: int) -> slice:
        n = self.n
        return slice(0, n - 1) if i == 0 else slice(n - 1 + (i - 1) * n, n - 1 + i * n)

    def section_factors(self, phis: list[np.ndarray], f_end: np.ndarray) -> list[np.ndarray]:
        """The factors of D P = E^T Pi Phi_{m-1} ... Phi_0 E (:func:`periodic_multipliers`)."""
        mask = self.mask
        proj = (
            np.eye(self.n) - np.outer(f_end, np.eye(self.n)[SECTION_INDEX]) / f_end[SECTION_INDEX]
        )
        last = (proj @ phis[-1])[mask]
        if self.m == 1:
            return [last[:, mask]]
        return [phis[0][:, mask], *phis[1:-1], last]

    # ---------------------------------------------------------- conversions
    def states_at(self, Y: np.ndarray, T_old: float, times: np.ndarray, mesh=None):
        """States at ``times`` (in [0, T_old)) on the trajectory cut as Y over T_old (at the
        fractions ``mesh``, default even)."""
        m_old = Y.shape[0]
        starts = T_old * (np.linspace(0, 1, m_old + 1) if mesh is None else np.asarray(mesh))
        out = np.empty((len(times), self.n))
        for k, t in enumerate(times):
            j = min(int(np.searchsorted(starts, t, side="right")) - 1, m_old - 1)
            dt = t - starts[j]
            if dt <= 0:
                out[k] = Y[j]
                continue
            st, y1, _ = self.flow(Y[j], dt, tangents=False)
            if st != "ok":
                return st, out
            out[k] = y1
        return "ok", out

    def crossings(self, Y: np.ndarray, T: float):
        """Upward crossings of dx1 = 0 in (0, T) along the segments: (status, times, states)."""
        n = self.n
        rtol, atol, tatol = self.kw
        s = self.system
        variant = kernel_variant(s.n_oscillators, s.is_dc_motor)
        ts, ys = [], []
        for i in range(self.m):
            tau = self.frac[i] * T
            y, t_done = Y[i].copy(), 0.0
            while tau - t_done > 1e-12 * T:
                args = (np.ascontiguousarray(y), np.eye(n)[:, :1].copy(), s.to_array(),
                        s.n_oscillators, s.is_dc_motor, variant, float(tau - t_done), 1,
                        rtol, atol, tatol)  # fmt: skip
                code, y1, _, t = call_journaled(
                    propagate_tangents, *args, _MAX_STEPS, abort=new_abort_flag()
                )
                if STATUS_NAMES[code] != "ok":
                    return STATUS_NAMES[code], np.array(ts), np.array(ys)
                if not math.isfinite(t):
                    break
                t_done += t
                tc = self.mesh[i] * T + t_done
                if 1e-9 * T < tc < T * (1 - 1e-9):
                    ts.append(tc)
                    ys.append(y1.copy())
                y = y1.copy()
                y[SECTION_INDEX] = 0.0
        return "ok", np.array(ts), np.array(ys).reshape(len(ys), n)


def refine_mesh(
    ms: MultiShooting,
    Y: np.ndarray,
    T: float,
    limit: float = 4.0,
    max_segments: int = MAX_SEGMENTS,
) -> np.ndarray:
    """A mesh in which no segment amplifies by more than ``limit`` (2-norm of Phi), by
    bisecting the segments of ``ms`` (starts Y over T) that do, up to ``max_segments``."""
    mesh = list(ms.mesh)
    starts = list(Y)
    i = 0
    while i < len(mesh) - 1 and len(mesh) - 1 < max_segments:
        dt = (mesh[i + 1] - mesh[i]) * T
        st, _, U = ms.flow(starts[i], dt)
        if st != "ok" or np.linalg.norm(U[:, : ms.n], 2) <= limit or dt < 1e-6 * T:
            i += 1
            continue
        st, y_mid, _ = ms.flow(starts[i], 0.5 * dt, tangents=False)
        if st != "ok":
            i += 1
            continue
        mesh.insert(i + 1, 0.5 * (mesh[i] + mesh[i + 1]))
        starts.insert(i + 1, y_mid)
    return np.array(mesh)


def remesh(
    ms: MultiShooting,
    Y: np.ndarray,
    T: float,
    norms: np.ndarray,
    limit: float = MESH_LIMIT,
    max_segments: int = MAX_SEGMENTS,
) -> np.ndarray:
    """A new mesh for the orbit cut as ``ms.mesh`` (starts Y over T), whose segments
    amplify by ``norms``: runs of neighbours whose norms multiply to at most ``limit`` are
    merged (their inner cuts dropped), then :func:`refine_mesh` bisects those above it.

    Merging first frees segments where the orbit stopped amplifying for the passage
    where it now does (past a sharp fold: the capture into a stick phase).
    """
    keep, acc = [0], 1.0
    for i in range(1, ms.m):
        acc *= max(float(norms[i - 1]), 1.0)
        if acc * max(float(norms[i]), 1.0) > limit:
            keep.append(i)
            acc = 1.0
    merged = MultiShooting(ms.system, np.r_[ms.mesh[keep], 1.0], *ms.kw)
    return refine_mesh(merged, Y[keep], T, limit, max_segments)
