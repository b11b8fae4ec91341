"""Plot a single run: time history and phase portraits with the Poincare points.

Usage::

    python scripts/plot_timeseries.py RUN.h5 [RUN2.h5 ...] -o fig.png [--t-window 500]

Reads only trajectory files written by ``stickslip-fast simulate CONFIG.toml -o
RUN.h5`` (:func:`stickslip_fast.io.write_trajectory`). One row per file with
(a) the time history of x_i and phi_i, (b) x-dx, (c) phi-dphi and (d) x-phi
phase portraits; the Poincare points (local minima of x_1, full state) are
marked. For N >= 2 the disks are overlaid in different colours. The shown
window ends at the last sample and covers two full periods when a period was
detected (else the last 20 crossings), unless ``--t-window`` is given.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from stickslip_fast.io import read_trajectory  # noqa: E402

__all__ = ["plot_run_row", "plot_runs", "main"]

DISK_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:purple")


def _window(run: dict[str, Any], t_window: float | None) -> float:
    """Start time of the shown window."""
    t = run["t"]
    if t.size == 0:
        return 0.0
    if t_window is not None:
        return max(float(t[0]), float(t[-1]) - t_window)
    tp = run["t_poincare"]
    p = int(run["period"])
    n_back = 2 * p if p > 0 else 20
    if tp.size > n_back:
        return max(float(t[0]), float(tp[-n_back - 1]))
    return float(t[0])


def plot_run_row(
    axs: Sequence[plt.Axes], run: dict[str, Any], t_window: float | None = None, label: str = ""
) -> None:
    """Draw one run on four axes: time history, x-dx, phi-dphi, x-phi.

    Parameters
    ----------
    axs : sequence of 4 Axes
    run : dict
        The result of :func:`stickslip_fast.io.read_trajectory`.
    t_window : float, optional
        Length of the shown time window (default: two periods).
    label : str
        Prefix of the panel titles (e.g. "η = 2.7").
    """
    names = run["state_names"]
    n = run["system"].n_oscillators
    t, y = run["t"], run["y"]
    t0 = _window(run, t_window)
    sel = t >= t0
    tp, pts = run["t_poincare"], run["poincare"]
    psel = tp >= t0
    for i in range(1, n + 1):
        c = DISK_COLOURS[(i - 1) % len(DISK_COLOURS)]
        ix, idx, ip, idp = (names.index(f"{v}{i}") for v in ("x", "dx", "phi", "dphi"))
        lw = 0.7
        axs[0].plot(t[sel], y[sel, ix], color=c, lw=lw, label=f"$x_{i}$", rasterized=True)
        axs[0].plot(t[sel], y[sel, ip], color=c, lw=lw, ls="--", alpha=0.7,
                    label=rf"$\varphi_{i}$", rasterized=True)  # fmt: skip
        for ax, (a, b) in zip(axs[1:], ((ix, idx), (ip, idp), (ix, ip))):
            ax.plot(y[sel, a], y[sel, b], color=c, lw=lw, rasterized=True, label=f"disk {i}")
            if psel.any():
                ax.plot(pts[psel, a], pts[psel, b], ls="none", marker="o", ms=3.5, mfc="none",
                        mec="red" if i == 1 else "darkred", mew=1.0, zorder=5)  # fmt: skip
        if psel.any():
            axs[0].plot(tp[psel], pts[psel, ix], ls="none", marker="o", ms=3, mfc="none",
                        mec="red" if i == 1 else "darkred", mew=0.8, zorder=5)  # fmt: skip
    status = run["status"]
    per = run["period"]
    info = f"{status}" + (f", period {per}" if status == "ok" and per else "")
    info += f", {int(tp.size)} Poincaré pts" if tp.size else ""
    axs[0].set_title(f"{label}(a) time history [{info}]", fontsize=8)
    axs[1].set_title(f"{label}(b) " + r"$x$–$\dot x$", fontsize=8)
    axs[2].set_title(f"{label}(c) " + r"$\varphi$–$\dot\varphi$", fontsize=8)
    axs[3].set_title(f"{label}(d) " + r"$x$–$\varphi$", fontsize=8)
    axs[0].set_xlabel("$t$")
    axs[0].set_ylabel(r"$x_i$, $\varphi_i$ (dashed)")
    axs[1].set_xlabel("$x$")
    axs[1].set_ylabel(r"$\dot x$")
    axs[2].set_xlabel(r"$\varphi$")
    axs[2].set_ylabel(r"$\dot\varphi$")
    axs[3].set_xlabel("$x$")
    axs[3].set_ylabel(r"$\varphi$")
    axs[0].legend(fontsize=6, loc="upper right", ncol=2)
    if n > 1:
        axs[1].legend(fontsize=6, loc="best")


def plot_runs(
    paths: Sequence[str | Path],
    out: str | Path,
    *,
    t_window: float | None = None,
    title: str | None = None,
    dpi: int = 150,
) -> Path:
    """Read trajectory files and write one figure with a row of panels per file.

    Parameters
    ----------
    paths : sequence of path
        Trajectory files (:func:`stickslip_fast.io.write_trajectory`).
    out : str or Path
        Image file; the format follows the extension.
    t_window : float, optional
        Length of the shown time window.
    title : str, optional
        Figure title (default: the first file's title).
    dpi : int

    Returns
    -------
    Path
    """
    runs = [read_trajectory(p) for p in paths]
    rows = len(runs)
    fig, axs = plt.subplots(rows, 4, figsize=(13.0, 3.0 * rows + 0.5), squeeze=False,
                            gridspec_kw={"width_ratios": [2.2, 1, 1, 1]})  # fmt: skip
    for r, run in enumerate(runs):
        label = rf"$\eta$={run['system'].eta:g}: " if rows > 1 else ""
        plot_run_row(axs[r], run, t_window, label)
    fig.suptitle(runs[0]["title"] if title is None else title, fontsize=9)
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("files", nargs="+", help="trajectory file(s) (HDF5), one row each")
    p.add_argument("-o", "--output", required=True, help="image file (.png, .pdf)")
    p.add_argument("--t-window", type=float, help="length of the shown time window")
    p.add_argument("--title", help="figure title")
    p.add_argument("--dpi", type=int, default=150)
    args = p.parse_args(argv)
    out = plot_runs(args.files, args.output, t_window=args.t_window, title=args.title,
                    dpi=args.dpi)  # fmt: skip
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
