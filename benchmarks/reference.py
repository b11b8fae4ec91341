"""Independent tight-tolerance references for the peer benchmark, cached under results/.

Trajectory references: SciPy ``solve_ivp`` Radau at rtol 1e-12 / atol 1e-14 on the plain
NumPy model of ``tests/reference/scipy_model.py`` (written from the paper, imports nothing
from stickslip_fast), with its analytic Jacobian and SciPy's own event location. These take
minutes each, so they are computed once and stored in ``results/reference_trajectories.json``
(recomputed when the stored settings differ).

Run ``python -m benchmarks.reference`` to (re)build the cache.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).resolve().parent / "results"
TRAJ_CACHE = RESULTS / "reference_trajectories.json"
REF_RTOL, REF_ATOL = 1e-12, 1e-14


def scipy_model():
    """The independent NumPy reference model (tests/reference/scipy_model.py)."""
    p = str(ROOT / "tests" / "reference")
    if p not in sys.path:
        sys.path.insert(0, p)
    import scipy_model as sm

    return sm


def asymmetric_params(eta: float) -> dict:
    """Parameter dict of the asymmetric preset with a constant belt (from the engine's preset)."""
    sys.path.insert(0, str(ROOT))
    import stickslip_fast as ssf

    return ssf.System.preset("asymmetric", eta=eta).to_dict()


def trajectory_key(eta: float, t_end: float, t_transient: float) -> str:
    return f"asymmetric_eta{eta:g}_t{t_end:g}_tr{t_transient:g}"


def trajectory_reference(
    eta: float, t_end: float, t_transient: float, log=print, cache: Path = TRAJ_CACHE
) -> dict:
    """Poincare points (dx1 upward crossings, t >= t_transient) of a tight Radau run from rest.

    Returns a dict with ``t`` (n,), ``points`` (n, 4) as NumPy arrays and the run's
    settings and cost; cached in ``cache``.
    """
    key = trajectory_key(eta, t_end, t_transient)
    store = json.loads(cache.read_text()) if cache.exists() else {}
    rec = store.get(key)
    if rec is None or rec.get("rtol") != REF_RTOL or rec.get("atol") != REF_ATOL:
        sm = scipy_model()
        p = asymmetric_params(eta)
        log(f"  building reference {key}: SciPy Radau rtol={REF_RTOL:g} on the NumPy model ...")
        t0 = time.perf_counter()
        te, ye, sol = sm.scipy_poincare(
            p, t_end, t_transient, np.zeros(4), method="Radau", rtol=REF_RTOL, atol=REF_ATOL,
            return_sol=True,
        )  # fmt: skip
        rec = dict(
            eta=eta,
            t_end=t_end,
            t_transient=t_transient,
            method="scipy Radau (NumPy model, analytic Jacobian, SciPy event location)",
            rtol=REF_RTOL,
            atol=REF_ATOL,
            nfev=int(sol.nfev),
            wall_s=time.perf_counter() - t0,
            t=te.tolist(),
            points=ye.tolist(),
        )
        store = json.loads(cache.read_text()) if cache.exists() else {}
        store[key] = rec
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_text(json.dumps(store, indent=1))
        log(f"    {len(te)} points in {rec['wall_s']:.0f} s")
    out = dict(rec)
    out["t"] = np.asarray(rec["t"], dtype=float)
    out["points"] = np.asarray(rec["points"], dtype=float).reshape(-1, 4)
    return out


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--eta", type=float, nargs="*", default=[2.0, 9.99])
    ap.add_argument("--t-end", type=float, default=1500.0)
    ap.add_argument("--t-transient", type=float, default=1000.0)
    a = ap.parse_args()
    for e in a.eta:
        trajectory_reference(e, a.t_end, a.t_transient)
