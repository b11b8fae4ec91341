"""The stale-cache guard: an edit in one module must reach cached kernels of another.

Numba keys a cached kernel on its own file only, so without the guard an edit of
``linalg.bordered_matvec`` is not seen by the cached ``model.jacobian_vector``
that calls it. Runs on a copy of the package in fresh processes.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import stickslip_fast

SNIPPET = """
import numpy as np
from stickslip_fast.base.jit import python_callable
from stickslip_fast.model.equations import jacobian_vector
from stickslip_fast import System
s = System.preset("asymmetric")
blocks, col, row, out = np.empty((1, 4, 4)), np.zeros((1, 4)), np.zeros((1, 4)), np.empty(4)
# from Python: the entry twin (base.jit), which links the compiled-only jacobian_vector
entry = python_callable(jacobian_vector)
entry(np.array([0.01, 0.001, 0.0, 0.0]), np.ones(4), s.to_array(), 1, False, blocks, col, row, out)
print(repr(float(out[1])), entry.stats.cache_hits.total())
"""


def _run(root: Path, guard: bool) -> tuple[float, int]:
    env = dict(os.environ, PYTHONPATH=str(root), STICKSLIP_FAST_CACHE_GUARD="1" if guard else "0")
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run(
        [sys.executable, "-c", SNIPPET], env=env, capture_output=True, text=True, timeout=600,
        check=True, cwd=root,
    ).stdout.split()  # fmt: skip
    return float(out[0]), int(out[1])


def test_edit_in_another_module_reaches_cached_kernel(tmp_path):
    pkg = tmp_path / "stickslip_fast"
    shutil.copytree(
        Path(stickslip_fast.__file__).parent, pkg, ignore=shutil.ignore_patterns("__pycache__")
    )
    first, hits = _run(tmp_path, guard=True)
    assert hits == 0
    again, hits = _run(tmp_path, guard=True)
    assert again == first and hits == 1  # unchanged sources: the cache is used

    src = pkg / "model" / "linalg.py"
    text = src.read_text()
    edited = text.replace(
        "                b[r, 0] * u[j] + b[r, 1] * u[j + 1] + b[r, 2] * u[j + 2] + b[r, 3] * u[j + 3]\n",
        "                2.0 * (b[r, 0] * u[j] + b[r, 1] * u[j + 1] + b[r, 2] * u[j + 2] + b[r, 3] * u[j + 3])\n",
    )
    assert edited != text
    src.write_text(edited)

    stale, hits = _run(tmp_path, guard=False)
    assert stale == first and hits == 1  # the defect: Numba alone serves the old kernel
    fresh, hits = _run(tmp_path, guard=True)
    assert fresh == 2.0 * first and hits == 0
