"""Checkpoints on the continuations the test suite does not interrupt (docs/orbits.md).

Each case runs three times: without a checkpoint (the reference), with a fresh one (to
count its kernel calls), and interrupted halfway through those calls (Ctrl-C, as
``tests/test_checkpoint.py`` does), then resumed from that file. It prints whether the
resumed result equals the reference in every field, to the bit.

- ``stick``: the stick-phase event curve of ``tests/test_stickcurve.py`` (Fig. 12's
  period-2 orbit, DC motor, in k12);
- ``auto``: ``continue_orbit(shooting="auto", remesh=True)`` past the sharp upper fold of
  Fig. 6's period-1 branch, single shooting to its precision limit, then multiple
  shooting with re-meshing (400 points, leading multiplier to ~1e21).

    PYTHONPATH=. python3 scripts/checkpoint_resume_check.py [stick] [auto]

About 1 minute on one core of the 2-core VM (most of it the ``auto`` case).
"""

from __future__ import annotations

import logging
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.base import journal as jmod  # noqa: E402
from stickslip_fast.base.journal import describe  # noqa: E402

# the P2 orbit of Fig. 12 before its stick-phase event (tests/test_stickcurve.py)
ETA0 = 7.649827263760607
Z0 = np.array([-0.031603656037365875, 0.0, 0.14915739910072962, -0.006592611572902248,
               0.00983875819861892])  # fmt: skip
# the stable period-1 orbit at eta = 3.3, k12 = -0.8
Z33 = np.array([0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407])


class _Counts(logging.Handler):
    """Keeps (from the file, in all, computed) of each journal closed."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[tuple] = []

    def emit(self, record: logging.LogRecord) -> None:
        if "calls from the file" in record.getMessage():
            self.seen.append(record.args[1:])


def halfway(run, tmp: Path, counts: _Counts) -> tuple[bool, int]:
    """(resumed == reference, calls in all) for ``run(checkpoint)``."""
    ref = run(None)
    run(tmp / "count.ckpt")
    total = counts.seen[-1][1]
    real, n = jmod.call_interruptible, [0]

    def flaky(kernel, *args, abort):
        n[0] += 1
        if n[0] > total // 2:
            raise KeyboardInterrupt
        return real(kernel, *args, abort=abort)

    jmod.call_interruptible = flaky
    try:
        run(tmp / "half.ckpt")
    except KeyboardInterrupt:
        pass
    finally:
        jmod.call_interruptible = real
    return describe(run(tmp / "half.ckpt")) == describe(ref), total


def stick_case():
    s = ssf.System.preset("asymmetric", drive="dc-motor", eta=ETA0, k12=-0.8)
    branch = ssf.continue_orbit(ssf.find_orbit(s, Z0, 2), "eta", (ETA0, 7.70), ds=0.01,
                                ds_max=0.02, max_points=8, progress=False)  # fmt: skip
    event = next(b for b in branch.bifurcations if b.kind == "stick-phase")
    return lambda path: ssf.continue_bifurcation(
        branch, event, "k12", (-0.804, -0.79), direction=-1, ds=0.002, ds_max=0.002,
        max_points=4, checkpoint=path, progress=False,
    )  # fmt: skip


def auto_case():
    orbit = ssf.find_orbit(ssf.System.preset("asymmetric", eta=3.30, k12=-0.8), Z33, 1)
    return lambda path: ssf.continue_orbit(
        orbit, "eta", (3.3, 3.33), ds=1e-5, ds_max=1e-4, max_points=400, shooting="auto",
        remesh=True, checkpoint=path, progress=False,
    )  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    cases = {"stick": stick_case, "auto": auto_case}
    names = (argv if argv is not None else sys.argv[1:]) or list(cases)
    counts = _Counts()
    log = logging.getLogger("stickslip_fast.checkpoint")
    log.setLevel(logging.INFO)
    log.addHandler(counts)
    ok = True
    for name in names:
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            same, total = halfway(cases[name](), Path(tmp), counts)
        ok &= same
        print(f"{name}: {total} kernel calls, interrupted after {total // 2}, resumed: "
              f"{'bit-identical' if same else 'DIFFERENT'} ({time.perf_counter() - t0:.0f} s)")  # fmt: skip
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
