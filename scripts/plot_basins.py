"""Draw basins files (stickslip_fast.basins): maps, attractors, boundary, saddle, entropy.

Reads only the HDF5 files (the ``/basins`` group and its ``boundary`` / ``edge``
subgroups; docs/basins.md). Each file is one panel: the cells coloured by attractor
id in the census figures' colours (``scripts/plot_bifurcation.py``: one colour per
track id), failed cells black; the attractors' Poincare points (projected onto the
plane) as large markers; the refined boundary points as small black dots; the
saddle orbit found by the edge check as a red cross; a saddle's stable manifold
(``stable_manifold``, the ``manifold`` subgroup) as magenta curves. With ``--entropy`` a last
panel draws the basin entropy S_b and the boundary basin entropy S_bb of every
file against eta.

Usage::

    python3 scripts/plot_basins.py out/basins_eta3.2.h5 -o docs/figures/basins_eta3.2.png
    python3 scripts/plot_basins.py A.h5 B.h5 C.h5 D.h5 --cols 2 --entropy -o fig.png
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402

KINDS = ("orbit", "equilibrium", "stalled", "unresolved")
LABELS = {"x1": "$x_1(0)$", "phi1": r"$\varphi_1(0)$", "dx1": r"$\dot x_1(0)$",
          "dphi1": r"$\dot\varphi_1(0)$", "x2": "$x_2(0)$", "phi2": r"$\varphi_2(0)$",
          "dx2": r"$\dot x_2(0)$", "dphi2": r"$\dot\varphi_2(0)$", "vb": "$v_b(0)$"}  # fmt: skip


def track_colour(track: int) -> Any:
    """The census figures' colour of a track id (as plot_bifurcation._track_colour)."""
    cmap = plt.get_cmap("tab20")
    return cmap((2 * track) % 20 + (track // 10) % 2)


#: --colours kind: one colour per (kind, period), the same in every panel
KIND_COLOURS = {"equilibrium": "tab:blue", "stalled": "tab:gray", "unresolved": "tab:purple"}
PERIOD_COLOURS = ["tab:orange", "tab:green", "tab:red", "tab:brown", "tab:pink", "tab:olive"]


def attractor_colours(d: dict, mode: str) -> dict[int, Any]:
    """Colour of every attractor id: the census's track colours, or by kind and period."""
    out = {}
    for r, aid in enumerate(d["id"]):
        kind = KINDS[int(d["kind"][r])]
        if mode == "id":
            out[int(aid)] = track_colour(int(aid))
        elif kind == "orbit":
            out[int(aid)] = PERIOD_COLOURS[(int(d["period"][r]) - 1) % len(PERIOD_COLOURS)]
        else:
            out[int(aid)] = KIND_COLOURS[kind]
    return out


def read(path: str | Path) -> dict[str, Any]:
    """Everything a panel needs from one basins file."""
    out: dict[str, Any] = {"path": str(path)}
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        if "basins" not in h5:
            raise SystemExit(f"{path}: no /basins group (not a finished basins file)")
        g = h5["basins"]
        out["attrs"] = {k: (v.item() if hasattr(v, "item") else v) for k, v in g.attrs.items()}
        for k in ("u", "v", "label", "base", "directions", "id", "kind", "period",
                  "fraction", "fraction_stderr", "points"):  # fmt: skip
            out[k] = g[k][...]
        out["title"] = h5.attrs.get("title", "")
        out["system"] = json.loads(h5.attrs["config"])["system"]
        for sub in ("boundary", "edge", "manifold"):
            out[sub] = {k: g[sub][k][...] for k in g[sub]} if sub in g else None
            if sub in g:
                out[sub + "_attrs"] = dict(g[sub].attrs)
    out["axis_names"] = json.loads(out["attrs"]["axis_names"])
    return out


def project(d: dict, states: np.ndarray) -> np.ndarray:
    """Plane coordinates (m, 2) of full states: least squares on the two directions."""
    rel = np.atleast_2d(states) - d["base"]
    coef, *_ = np.linalg.lstsq(d["directions"].T, rel.T, rcond=None)
    return coef.T


def _edges(a: np.ndarray) -> np.ndarray:
    mid = 0.5 * (a[1:] + a[:-1])
    return np.concatenate([[2 * a[0] - mid[0]], mid, [2 * a[-1] - mid[-1]]])


def draw_map(ax: Any, d: dict, mode: str = "id", window: Any = None) -> None:
    """One basin map with attractors, boundary, saddle and manifold (``window``: the
    axes' limits u0, u1, v0, v1 instead of the whole map)."""
    lab = d["label"]
    col = attractor_colours(d, mode)
    top = max([0, *col, *(int(i) for i in np.unique(lab))])
    colours = [col.get(i, "white") for i in range(top + 1)]
    cmap = ListedColormap(["black"] + colours)
    ax.pcolormesh(_edges(d["u"]), _edges(d["v"]), np.where(lab < 0, -1, lab).T + 1,
                  cmap=cmap, vmin=-0.5, vmax=top + 1.5, shading="flat",
                  rasterized=True)  # fmt: skip
    for r, aid in enumerate(d["id"]):
        kind = KINDS[int(d["kind"][r])]
        pts = d["points"][r]
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        uv = project(d, pts)
        name = f"P{d['period'][r]}" if kind == "orbit" else kind
        if len(d["base"]) >= 8 and kind == "orbit":  # two or more disks: disk 2 against 1
            gap = float(np.max(np.abs(pts[:, 4:8] - pts[:, 0:4])))
            name += ", in phase" if gap < 1e-6 else f", |disk 2 - disk 1| = {gap:.2f}"
        ax.plot(uv[:, 0], uv[:, 1], "o" if kind == "orbit" else "s", ms=8,
                mfc=col[int(aid)], mec="k", mew=1.2,
                label=f"id {aid}: {name}, {d['fraction'][r]:.3f} ± "
                      f"{d['fraction_stderr'][r]:.3f}")  # fmt: skip
    if d["boundary"] is not None:
        b = d["boundary"]
        ok = b["status"] == 0
        ax.plot(
            b["u"][ok],
            b["v"][ok],
            ".",
            ms=2.0,
            color="k",
            label=f"boundary ({ok.sum()} points, tol {d['boundary_attrs']['tol']:.0e})",
        )
    if d["manifold"] is not None:
        draw_manifold(ax, d)
    if d["edge"] is not None and np.all(np.isfinite(d["edge"]["saddle_points"])):
        e = d["edge"]
        uv = project(d, e["saddle_points"])
        md = np.nanmedian(e["min_distance"])
        ax.plot(uv[:, 0], uv[:, 1], "x", ms=11, mew=2.5, color="red",
                label=f"saddle P{d['edge_attrs']['saddle_period']} (boundary runs reach "
                      f"{md:.0e})")  # fmt: skip
    a, b_ = d["axis_names"]
    ax.set_xlabel(LABELS.get(a, a))
    ax.set_ylabel(LABELS.get(b_, b_))
    at = d["attrs"]
    ax.set_title(f"η = {at['eta']:g}: $S_b$ = {at['basin_entropy']:.3f}, $S_{{bb}}$ = "
                 f"{at['boundary_basin_entropy']:.3f}, α = {at['uncertainty_exponent']:.2f}",
                 fontsize=9)  # fmt: skip
    ax.set_xlim(*(window[:2] if window else _edges(d["u"])[[0, -1]]))
    ax.set_ylim(*(window[2:] if window else _edges(d["v"])[[0, -1]]))
    ax.legend(fontsize=6.5, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
              frameon=False)  # fmt: skip


def draw_manifold(ax: Any, d: dict) -> None:
    """The traced stable manifold: one line per branch, and the saddle's points."""
    m, a = d["manifold"], d["manifold_attrs"]
    for k, b in enumerate(np.unique(m["branch"])):
        on = m["branch"] == b
        ax.plot(m["u"][on], m["v"][on], "-", lw=1.4, color="magenta",
                label=(f"stable manifold of the P{a['saddle_period']} saddle (|μ| = "
                       f"{np.max(np.abs(m['mu'])):.3g}, {len(m['u'])} points)") if k == 0 else None)  # fmt: skip
    if d["edge"] is None:
        uv = project(d, m["saddle_points"])
        ax.plot(uv[:, 0], uv[:, 1], "x", ms=11, mew=2.5, color="red")


def draw_entropy(ax: Any, data: list[dict]) -> None:
    """S_b and S_bb of every file against eta (one point per file)."""
    key = [(d["attrs"]["eta"], d) for d in data]
    key.sort(key=lambda t: t[0])
    eta = np.array([k for k, _ in key])
    sb = np.array([d["attrs"]["basin_entropy"] for _, d in key])
    sbb = np.array([d["attrs"]["boundary_basin_entropy"] for _, d in key])
    cells = sorted({f"{d['label'].shape[0]}×{d['label'].shape[1]}" for _, d in key})
    ax.plot(eta, sb, "o-", label=f"$S_b$ (basin entropy; {', '.join(cells)} cells)")
    ax.plot(eta, sbb, "s--", label="$S_{bb}$ (boundary basin entropy)")
    ax.axhline(np.log(2), color="grey", lw=0.8, ls=":", label="ln 2 (log-2 criterion)")
    ax.set_xlabel("η")
    ax.set_ylabel("entropy (nats)")
    ax.set_title("basin entropy against η", fontsize=9)
    ax.legend(fontsize=7)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("files", nargs="+", metavar="BASINS.h5")
    p.add_argument("-o", "--output", required=True, metavar="FIG.png")
    p.add_argument("--cols", type=int, default=None, help="panels per row")
    p.add_argument("--entropy", action="store_true", help="add the entropy-against-eta panel")
    p.add_argument("--entropy-files", nargs="+", default=None, metavar="BASINS.h5",
                   help="draw the entropy panel from these files (e.g. a scan over eta at one "
                        "resolution) instead of the mapped ones; implies --entropy")  # fmt: skip
    p.add_argument("--title", default=None, help="figure title")
    p.add_argument("--colours", choices=("id", "kind"), default="id",
                   help="id: the census figures' track colours (default); kind: one colour "
                        "per kind and period, the same in every panel")  # fmt: skip
    p.add_argument("--window", type=float, nargs=4, default=None, metavar=("U0", "U1", "V0", "V1"),
                   help="draw only this part of the plane (every map panel)")  # fmt: skip
    args = p.parse_args(argv)
    data = [read(f) for f in args.files]
    args.entropy = args.entropy or args.entropy_files is not None
    n = len(data) + int(args.entropy)
    cols = args.cols or min(n, 3)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 5.6 * rows), squeeze=False)
    for ax, d in zip(axes.flat, data):
        draw_map(ax, d, args.colours, args.window)
    if args.entropy:
        extra = [read(f) for f in args.entropy_files] if args.entropy_files else data
        draw_entropy(axes.flat[len(data)], extra)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    if args.title:
        fig.suptitle(args.title, fontsize=10)
    fig.tight_layout()
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.output, dpi=130)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
