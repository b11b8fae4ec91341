"""Compile the CUDA sweep kernels to PTX without a GPU and report their resource use.

    python3 scripts/cuda_ptx_report.py [--cc 9.0] [--out DIR]

Needs the ``[cuda]`` extra (numba-cuda with NVVM) but no GPU or driver. For
each specialisation (N = 1 .. MAX_OSCILLATORS, constant belt and DC motor) it
compiles the kernel for the real CUDA target, which the simulator used by the
tests cannot check, and, when ``ptxas`` is found (on PATH or in the
nvidia-cuda-nvcc wheel), assembles it with ``ptxas -v`` to report registers,
stack frame and spills per thread. These are compile-time facts for the given
compute capability, not measurements on a device.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def find_ptxas() -> str | None:
    exe = shutil.which("ptxas")
    if exe:
        return exe
    try:
        import nvidia.cuda_nvcc as nvcc  # the nvidia-cuda-nvcc-cu12 wheel

        for base in nvcc.__path__:
            cand = Path(base) / "bin" / "ptxas"
            if cand.exists():
                return str(cand)
    except ImportError:
        pass
    return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cc", default="9.0", help="compute capability, e.g. 8.0 or 9.0")
    ap.add_argument("--out", help="also write the PTX files into this folder")
    args = ap.parse_args(argv)
    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
        print("unset NUMBA_ENABLE_CUDASIM: this compiles for the real target", file=sys.stderr)
        return 2
    from stickslip_fast.backends import cuda as cb

    cc = tuple(int(x) for x in args.cc.split("."))
    ptxas = find_ptxas()
    print(f"compute capability {args.cc}; ptxas: {ptxas or 'not found (PTX only)'}")
    print(
        "| N | drive | PTX lines | registers | stack frame (B) | spill stores (B) | spill loads (B) |"
    )
    print("|---|---|---|---|---|---|---|")
    for n_osc in range(1, cb.MAX_OSCILLATORS + 1):
        for dc in (False, True):
            ptx = cb.compile_ptx(n_osc, dc, cc)
            if args.out:
                Path(args.out).mkdir(parents=True, exist_ok=True)
                (Path(args.out) / f"sweep_n{n_osc}_{'dc' if dc else 'const'}.ptx").write_text(ptx)
            regs = frame = st = ld = "-"
            if ptxas:
                with tempfile.TemporaryDirectory() as tmp:
                    src = Path(tmp) / "k.ptx"
                    src.write_text(ptx)
                    res = subprocess.run(
                        [ptxas, f"-arch=sm_{cc[0]}{cc[1]}", "-v", str(src), "-o", str(Path(tmp) / "k.cubin")],
                        capture_output=True, text=True, check=True,
                    )  # fmt: skip
                # the kernel's own line is the last "Used N registers" (device functions come first)
                used = re.findall(r"Used (\d+) registers", res.stderr)
                frames = re.findall(
                    r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads",
                    res.stderr,
                )
                regs = used[-1] if used else "?"
                if frames:
                    frame, st, ld = max(frames, key=lambda f: int(f[0]))
            drive = "dc-motor" if dc else "constant"
            print(f"| {n_osc} | {drive} | {ptx.count(chr(10))} | {regs} | {frame} | {st} | {ld} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
