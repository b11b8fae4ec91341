"""Work for tests/test_properties.py, run in a child process so a hang can be timed out.

Every function returns plain data describing what happened: a raised exception
(its type, message and traceback), or the classified result.
"""

from __future__ import annotations

import contextlib
import io
import traceback

import numpy as np


def _raised(exc: BaseException) -> dict:
    return {
        "kind": "raised",
        "type": type(exc).__name__,
        "bases": [c.__name__ for c in type(exc).__mro__],
        "message": str(exc),
        "traceback": traceback.format_exc(),
    }


def _describe(res) -> dict:
    pts = np.asarray(res.poincare)
    return {
        "kind": "result",
        "status": res.status,
        "period": int(res.period),
        "n_steps": int(res.n_steps),
        "n_points": int(len(res.t_poincare)),
        "points_finite": bool(np.all(np.isfinite(pts))),
        "final_finite": bool(np.all(np.isfinite(res.final_state))),
    }


def system_then_simulate(fields: dict, sim_kw: dict) -> dict:
    """``System.preset("asymmetric", **fields)``, then a short :func:`simulate`."""
    import stickslip_fast as ssf

    try:
        system = ssf.System.preset("asymmetric", **fields)
    except Exception as exc:  # noqa: BLE001 - reported to the test
        return {**_raised(exc), "stage": "System"}
    try:
        return _describe(ssf.simulate(system, **sim_kw))
    except Exception as exc:  # noqa: BLE001
        return {**_raised(exc), "stage": "simulate"}


def cli(argv: list[str], sweep_out: str | None = None) -> dict:
    """``stickslip-fast ARGV`` in this process: exit status, stdout, stderr.

    With ``sweep_out``, a successful sweep's file is read back and classified.
    """
    from stickslip_fast.cli import main

    out, err = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = main(argv)
    except BaseException as exc:  # noqa: BLE001 - SystemExit from argparse included
        if isinstance(exc, SystemExit):
            return {"kind": "exit", "rc": exc.code, "stdout": out.getvalue(),
                    "stderr": err.getvalue()}  # fmt: skip
        return {**_raised(exc), "stderr": err.getvalue()}
    report = {"kind": "exit", "rc": rc, "stdout": out.getvalue(), "stderr": err.getvalue()}
    if rc == 0 and sweep_out is not None:
        from stickslip_fast.analysis.sweep import load_sweep

        r = load_sweep(sweep_out)
        ok = r.status == "ok"
        report["sweep"] = {
            "n_ok": int(ok.sum()),
            "ok_with_points": bool(np.all(r.count[ok] > 0)),
            "ok_points_finite": bool(
                all(np.all(np.isfinite(r.points[i][: r.count[i]])) for i in zip(*np.nonzero(ok)))
            ),
            "ok_steps": bool(np.all(r.n_steps[ok] > 0)),
            "all_done": bool(np.all(np.isin(r.status, list(_statuses())))),
        }
    return report


def _statuses():
    from stickslip_fast import STATUS_NAMES

    return STATUS_NAMES


def ping() -> bool:
    """Import and compile in the child before the timed examples start.

    Every kernel specialisation the examples can reach (drives, disk counts,
    methods, sweep modes) is compiled here, outside the per-example timeout: on
    an empty Numba cache compiling takes minutes on a loaded machine.
    """
    import tempfile
    import warnings

    import stickslip_fast as ssf
    from stickslip_fast.analysis.sweep import sweep

    warnings.simplefilter("ignore")
    for drive in ("constant", "dc-motor"):
        for n in (1, 2):
            system = ssf.System.preset("asymmetric", drive=drive, n_oscillators=n)
            for method in ("rodas5p", "dopri5"):
                ssf.simulate(system, 5.0, 0.0, method=method, sample_dt=1.0)
                for mode in ("restart", "continuation", "continuation-both"):
                    sweep(system, "eta", [2.0, 3.0], t_end=5.0, mode=mode, method=method,
                          progress=False)  # fmt: skip
            sweep(system, ("eta", "k12"), ([2.0, 3.0], [0.0, 0.1]), t_end=5.0, progress=False)
    with tempfile.TemporaryDirectory() as tmp:
        sweep(ssf.System.preset("asymmetric"), "eta", [2.0, 3.0], t_end=5.0, progress=False,
              out=f"{tmp}/warm.h5")  # fmt: skip
    return True
