"""Plot a sweep file: bifurcation diagram (1-D sweeps) or period map (2-D sweeps).

Usage::

    python scripts/plot_bifurcation.py OUT.h5 -o fig.png [--vars x1,phi1] [--period]
    python scripts/plot_bifurcation.py CENSUS.h5 -o census.png [--vars x1,phi1]
    python scripts/plot_bifurcation.py OUT.h5 -o fig.png --branch B1.h5 --branch B2.h5 [--multipliers]

Reads only the HDF5 file written by :func:`stickslip_fast.sweep` or
:func:`stickslip_fast.census` (it simulates nothing).

Census files (:func:`plot_census`): every attractor found at every value, its
points coloured by track (one colour per attractor followed over the values),
dot size and opacity growing with the basin fraction; equilibria (steady
sliding) as solid lines and stalled motors as dashed lines in the track's
colour; "unresolved" runs (no period <= 64) as faint clouds. Below, the basin
fractions stacked against the parameter in the same colours (failed runs in
black on top). See docs/census.md, "How to read a census figure". 1-D sweeps: one panel per variable kind (x, phi, dx, ...) with the
Poincare points against the swept parameter as small rasterized dots; for
N >= 2 the disks (x1, x2, ...) are overlaid in different colours on the same
panel; for mode "continuation-both" the up and down branches are overlaid in two
colours (hysteresis). Values without an orbit are never drawn as points:
equilibria ("steady sliding") and stalled motors are drawn as a line at the
final state, failures as ticks on the lower edge. ``--period`` adds a panel with
the detected period, and a file holding a ``sync_error`` dataset gets a panel
for it. 2-D sweeps: a period map (``pcolormesh``) coloured by period, with
"no period", equilibrium, stalled and failed values in distinct colours.

Branch files (``stickslip-fast continue``, :meth:`Branch.to_hdf5`) are drawn over a
1-D sweep or a census with ``--branch`` (repeatable): the continued section point
against the parameter, black for orbits and grey for equilibria, solid where
stable and dashed where unstable, with each located bifurcation marked and
labelled (F fold, PD period-doubling, NS Neimark-Sacker, H Hopf, S stick phase, G section
grazing, SB symmetry-breaking). Only the orbit's first section point is continued, so a period-p
branch is one curve through one of its p points. ``--multipliers`` adds a
panel with the largest |Floquet multiplier| of every orbit branch (1 marks the
stability boundary) and the largest real part of the eigenvalues of every
equilibrium branch (0 marks it).

The output format follows the extension (.png, .pdf, .svg).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import BoundaryNorm, ListedColormap  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from stickslip_fast.core.poincare import STATUS_NAMES  # noqa: E402
from stickslip_fast.io import read_sweep  # noqa: E402

__all__ = [
    "plot_sweep", "plot_bifurcation", "plot_period_map", "plot_census", "overlay_branches", "main",
]  # fmt: skip

LABELS = {
    "x": "$x$",
    "dx": r"$\dot x$",
    "phi": r"$\varphi$",
    "dphi": r"$\dot\varphi$",
    "vb": "$v_b$",
}
PARAM_LABELS = {"eta": r"$\eta$", "k12": "$k_{12}$", "vb": "$v_b$", "vb0": "$v_{b0}$"}
#: How values without an orbit are drawn: (label, colour).
REST_STYLE = {
    "equilibrium": ("steady sliding (equilibrium)", "0.55"),
    "stalled": ("stalled motor", "tab:red"),
}
FAIL_COLOUR = "black"
DISK_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:purple")
BRANCH_COLOURS = {"up": "tab:blue", "down": "tab:orange"}


def _split(name: str) -> tuple[str, int]:
    """'phi2' -> ('phi', 2); 'vb' -> ('vb', 0)."""
    m = re.fullmatch(r"([a-z]+?)(\d+)", name)
    return (m.group(1), int(m.group(2))) if m else (name, 0)


def _default_vars(state_names: Sequence[str]) -> list[str]:
    n = sum(1 for s in state_names if _split(s)[0] == "x")
    return [f"x{i}" for i in range(1, n + 1)] + [f"phi{i}" for i in range(1, n + 1)]


def _status_names(codes: np.ndarray) -> np.ndarray:
    names = np.array((*STATUS_NAMES, "missing"), dtype=object)
    return names[np.where(codes < 0, len(STATUS_NAMES), codes)]


def _title(data: dict[str, Any]) -> str:
    title = str(data["attrs"].get("title", "")) or Path(str(data.get("path", ""))).name
    return title


def plot_bifurcation(
    data: dict[str, Any],
    variables: Sequence[str] | None = None,
    *,
    period_panel: bool = False,
    title: str | None = None,
    markersize: float = 1.2,
) -> plt.Figure:
    """Bifurcation diagram of a 1-D sweep, as read by :func:`read_sweep`.

    Parameters
    ----------
    data : dict
        The result of :func:`stickslip_fast.io.read_sweep`.
    variables : sequence of str, optional
        State names to draw (default: x_i and phi_i of every disk). Names of
        one kind (x1, x2) share a panel.
    period_panel : bool
        Add a panel with the detected period of every value.
    title : str, optional
        Figure title (default: the file's title).
    markersize : float
        Size of the Poincare dots (points).

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = data["state_names"]
    variables = list(variables) if variables else _default_vars(names)
    for v in variables:
        if v not in names:
            raise ValueError(f"unknown variable {v!r}; the file has {names}")
    kinds: list[str] = []
    for v in variables:
        k = _split(v)[0]
        if k not in kinds:
            kinds.append(k)
    param = data["param"][0]
    axis = np.asarray(data["axes"][0])
    branches = ["up", "down"] if data["branches"] else [None]
    extra = []
    if period_panel:
        extra.append("period")
    if "sync_error" in data.get("analyses", {}):
        extra.append("sync_error")
    if "lyapunov_fit" in data.get("analyses", {}):
        extra.append("lyapunov_fit")
    n_pan = len(kinds) + len(extra)
    ratios = [3.0] * len(kinds) + [1.2] * len(extra)
    fig, axs = plt.subplots(
        n_pan, 1, sharex=True, figsize=(7.0, 2.3 * len(kinds) + 1.1 * len(extra) + 0.6),
        gridspec_kw={"height_ratios": ratios}, squeeze=False,
    )  # fmt: skip
    axs = axs[:, 0]
    handles: list[dict[str, Any]] = [{} for _ in range(n_pan)]
    for b_i, branch in enumerate(branches):
        sl = (b_i,) if branch is not None else ()
        pts = data["points"][sl]
        status = _status_names(data["status"][sl])
        final = data["final_state"][sl]
        for v in variables:
            kind, disk = _split(v)
            ax = axs[kinds.index(kind)]
            col = names.index(v)
            if branch is not None:
                colour = BRANCH_COLOURS[branch]
                if len([w for w in variables if _split(w)[0] == kind]) > 1:
                    colour = DISK_COLOURS[(2 * max(disk - 1, 0) + b_i) % len(DISK_COLOURS)]
                label = f"{v}, {branch} branch"
            else:
                colour = DISK_COLOURS[max(disk - 1, 0) % len(DISK_COLOURS)]
                label = v
            vals = pts[..., col]
            xs = np.broadcast_to(axis[:, None], vals.shape)
            ok = np.isfinite(vals)
            h = ax.scatter(xs[ok], vals[ok], s=markersize**2, c=colour, marker="o",
                           linewidths=0, rasterized=True, alpha=0.8 if branch == "down" else 1.0,
                           label=label)  # fmt: skip
            handles[kinds.index(kind)].setdefault(f"pts:{label}", h)
            for st, (st_label, st_colour) in REST_STYLE.items():
                mask = status == st
                if not np.any(mask):
                    continue
                y = np.where(mask, final[..., col], np.nan)
                (line,) = ax.plot(axis, y, color=st_colour, lw=2.5, alpha=0.6,
                                  solid_capstyle="butt", label=st_label)  # fmt: skip
                lone = mask & ~np.roll(mask, 1) & ~np.roll(mask, -1)  # isolated values
                ax.plot(axis[lone], y[lone], ls="none", marker="_", ms=6, mew=2.5,
                        color=st_colour, alpha=0.6)  # fmt: skip
                handles[kinds.index(kind)].setdefault(f"rest:{st_label}", line)
            fail = ~np.isin(status, ("ok", *REST_STYLE))
            if np.any(fail):
                tr = ax.get_xaxis_transform()
                f = ax.plot(axis[fail], np.zeros(int(fail.sum())), ls="none", marker="|",
                            ms=8, color=FAIL_COLOUR, transform=tr,
                            label="no orbit / failed (" + ", ".join(sorted(set(status[fail]))) + ")")  # fmt: skip
                handles[kinds.index(kind)].setdefault("fail", f[0])
        for e, name in enumerate(extra):
            ax = axs[len(kinds) + e]
            if name == "period":
                per = data["period"][sl].astype(float)
                per[(status != "ok") | (per <= 0)] = np.nan
                ax.plot(axis, per, ls="none", marker=".", ms=2,
                        color=BRANCH_COLOURS.get(branch, "k") if branch else "k")  # fmt: skip
                nop = (status == "ok") & (data["period"][sl] == 0)
                if np.any(nop):
                    h = ax.plot(axis[nop], np.zeros(int(nop.sum())), ls="none", marker="x",
                                ms=3, color="tab:red", label="orbit, no period <= 64")  # fmt: skip
                    handles[len(kinds) + e].setdefault("nop", h[0])
                ax.yaxis.get_major_locator().set_params(integer=True)
                ax.set_ylabel("period")
            else:
                y = data["analyses"][name][sl]
                ax.plot(axis, y, ls="none", marker=".", ms=2,
                        color=BRANCH_COLOURS.get(branch, "k") if branch else "k")  # fmt: skip
                ax.set_ylabel("sync error" if name == "sync_error" else r"$\lambda_1$")
    for k, kind in enumerate(kinds):
        axs[k].set_ylabel(LABELS.get(kind, kind) + r" at min $x_1$")
    axs[-1].set_xlabel(PARAM_LABELS.get(param, param))
    axs[0].set_title(_title(data) if title is None else title, fontsize=9)
    if "period" in extra:
        per_ax = axs[len(kinds) + extra.index("period")]
        per_ax.set_ylim(-1, max(2.0, float(np.max(data["period"], initial=0))) + 1)
    for ax, hd in zip(axs, handles):
        if hd:
            leg = ax.legend(handles=list(hd.values()), fontsize=7, loc="best", markerscale=4,
                            framealpha=0.8)  # fmt: skip
            for lh in leg.legend_handles:
                if hasattr(lh, "set_alpha"):
                    lh.set_alpha(1.0)
    fig.tight_layout()
    return fig


def plot_period_map(data: dict[str, Any], title: str | None = None) -> plt.Figure:
    """Period map of a 2-D sweep: colour = period, statuses in distinct colours.

    Parameters
    ----------
    data : dict
        The result of :func:`stickslip_fast.io.read_sweep` for a 2-D sweep
        (the "up" branch is drawn if the file has branches).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    p1, p2 = data["param"]
    a1, a2 = (np.asarray(a) for a in data["axes"])
    sl = (0,) if data["branches"] else ()
    status = _status_names(data["status"][sl])
    period = data["period"][sl].astype(float)
    has_period = (status == "ok") & (period > 0)
    per = np.where(has_period, period, np.nan)
    # categorical layer: 0 none, 1 no period detected, 2 equilibrium, 3 stalled, 4 failed, 5 missing
    cat = np.full(status.shape, np.nan)
    cat[(status == "ok") & (period <= 0)] = 1
    cat[status == "equilibrium"] = 2
    cat[status == "stalled"] = 3
    cat[~np.isin(status, ("ok", "equilibrium", "stalled", "missing"))] = 4
    cat[status == "missing"] = 5
    cat_colours = ["black", "0.7", "tab:red", "magenta", "white"]
    cat_labels = ["orbit, no period <= 64", "steady sliding (equilibrium)", "stalled motor",
                  "no orbit: failed, unsettled or no crossings", "not computed"]  # fmt: skip

    def edges(a: np.ndarray) -> np.ndarray:
        if a.size == 1:
            return np.array([a[0] - 0.5, a[0] + 0.5])
        mid = 0.5 * (a[1:] + a[:-1])
        return np.concatenate([[2 * a[0] - mid[0]], mid, [2 * a[-1] - mid[-1]]])

    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    top = int(np.nanmax(per)) if np.any(has_period) else 1
    bounds = np.arange(0.5, top + 1.5)
    cmap = plt.get_cmap("viridis", len(bounds) - 1)
    mesh = ax.pcolormesh(edges(a1), edges(a2), per.T, cmap=cmap,
                         norm=BoundaryNorm(bounds, cmap.N), shading="flat")  # fmt: skip
    ccmap = ListedColormap(cat_colours)
    ax.pcolormesh(edges(a1), edges(a2), np.ma.masked_invalid(cat.T), cmap=ccmap,
                  norm=BoundaryNorm(np.arange(0.5, 6.5), ccmap.N), shading="flat")  # fmt: skip
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label("period")
    if top <= 12:
        cb.set_ticks(np.arange(1, top + 1))
    present = [i for i in range(5) if np.any(cat == i + 1)]
    if present:
        ax.legend(handles=[Patch(facecolor=cat_colours[i], edgecolor="k", label=cat_labels[i])
                           for i in present], fontsize=7, loc="upper left",
                  bbox_to_anchor=(0.0, -0.12), ncol=3, frameon=False)  # fmt: skip
    ax.set_xlabel(PARAM_LABELS.get(p1, p1))
    ax.set_ylabel(PARAM_LABELS.get(p2, p2))
    ax.set_title(_title(data) if title is None else title, fontsize=9)
    fig.tight_layout()
    return fig


def _track_colour(track: int) -> Any:
    cmap = plt.get_cmap("tab20")
    return cmap((2 * track) % 20 + (track // 10) % 2)


def plot_census(
    result: Any,
    variables: Sequence[str] | None = None,
    *,
    title: str | None = None,
    max_legend: int = 12,
) -> plt.Figure:
    """Census figure: attractors by track over the parameter, and stacked basin fractions.

    Parameters
    ----------
    result : CensusResult
        What :func:`stickslip_fast.analysis.census.load_census` returns.
    variables : sequence of str, optional
        State names to draw (default x_i and phi_i); names of one kind share a panel.
    title : str, optional
    max_legend : int
        Tracks named in the legend (those with the largest basin, summed over values).

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = result.state_names
    variables = list(variables) if variables else _default_vars(names)
    for v in variables:
        if v not in names:
            raise ValueError(f"unknown variable {v!r}; the file has {names}")
    kinds: list[str] = []
    for v in variables:
        if _split(v)[0] not in kinds:
            kinds.append(_split(v)[0])
    vals = np.asarray(result.values)
    fr = result.fractions()
    fig, axs = plt.subplots(
        len(kinds) + 1, 1, sharex=True, figsize=(9.0, 2.4 * len(kinds) + 2.0),
        gridspec_kw={"height_ratios": [3.0] * len(kinds) + [1.6]}, squeeze=False,
    )  # fmt: skip
    axs = axs[:, 0]
    markers = ("o", "s", "^", "D")
    for v in variables:
        kind, disk = _split(v)
        ax = axs[kinds.index(kind)]
        col = names.index(v)
        mk = markers[max(disk - 1, 0) % len(markers)]
        for track in result.tracks:
            colour = _track_colour(track.id)
            if track.kind in ("equilibrium", "stalled"):
                y = np.full(vals.size, np.nan)
                for i in range(track.birth, track.death + 1):
                    for a in result.attractors[i]:
                        if a.id == track.id:
                            y[i] = a.points[0, col]
                lw = 1.0 + 2.5 * np.nanmax(fr[:, track.id])
                ls = "-" if track.kind == "equilibrium" else "--"
                ax.plot(vals, y, color=colour, lw=lw, ls=ls, alpha=0.85, solid_capstyle="butt")
                lone = np.isfinite(y) & ~np.isfinite(np.roll(y, 1)) & ~np.isfinite(np.roll(y, -1))
                ax.plot(vals[lone], y[lone], ls="none", marker="_", ms=7, mew=lw, color=colour)
                continue
            xs, ys, sz, al = [], [], [], []
            for i in range(track.birth, track.death + 1):
                for a in result.attractors[i]:
                    if a.id != track.id:
                        continue
                    pts = a.points[:, col]
                    faint = a.kind == "unresolved"
                    xs.append(np.full(pts.size, vals[i]))
                    ys.append(pts)
                    sz.append(np.full(pts.size, (0.6 if faint else 1.0) + 3.0 * a.fraction))
                    al.append(np.full(pts.size, (0.15 if faint else 0.35) + 0.65 * a.fraction))
            if xs:
                rgba = np.tile(matplotlib.colors.to_rgba(colour), (sum(x.size for x in xs), 1))
                rgba[:, 3] = np.concatenate(al)
                ax.scatter(np.concatenate(xs), np.concatenate(ys), s=np.concatenate(sz) ** 2,
                           c=rgba, marker=mk, linewidths=0, rasterized=True)  # fmt: skip
    for k, kind in enumerate(kinds):
        axs[k].set_ylabel(LABELS.get(kind, kind) + r" at min $x_1$")
    for ax in axs[:-1]:
        ax.margins(y=0.08)
    # stacked basin fractions, failed runs on top (runs not computed yet stay blank)
    ax = axs[-1]
    order = [t.id for t in result.tracks]
    failed = np.mean((result.labels < 0) & (result.status_code >= 0), axis=1)
    stack = [fr[:, t] for t in order] + [failed]
    colours = [_track_colour(t) for t in order] + [FAIL_COLOUR]
    ax.stackplot(vals, *stack, colors=colours, linewidth=0, step="mid")
    ax.set_ylim(0, 1)
    ax.set_ylabel("basin fraction")
    ax.set_xlabel(PARAM_LABELS.get(result.param, result.param))
    # legend: the largest tracks
    total = fr.sum(axis=0)
    top = sorted(order, key=lambda t: -total[t])[:max_legend]
    handles = []
    for t in sorted(top):
        tr = result.tracks[t]
        desc = tr.kind if tr.kind != "orbit" else "P" + "/P".join(map(str, tr.periods))
        if tr.kind == "equilibrium":
            desc = "steady sliding"
        span = f"{vals[tr.birth]:g}-{vals[tr.death]:g}"
        handles.append(Patch(facecolor=_track_colour(t), label=f"#{t} {desc} ({span})"))
    if np.any(failed > 0):
        handles.append(Patch(facecolor=FAIL_COLOUR, label="failed / no crossings"))
    handles.append(Line2D([], [], color="0.3", lw=2, label="equilibrium (line)"))
    handles.append(Line2D([], [], color="0.3", lw=2, ls="--", label="stalled motor (dashed)"))
    axs[0].legend(handles=handles, fontsize=6.5, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  frameon=False, title="tracks (values)", title_fontsize=7)  # fmt: skip
    n_s = len(result.starts)
    default = f"census: {len(vals)} values x {n_s} starts"
    axs[0].set_title(default if title is None else title, fontsize=9)
    fig.tight_layout()
    return fig


def plot_sweep(
    path: str | Path,
    out: str | Path,
    variables: Sequence[str] | None = None,
    *,
    period_panel: bool = False,
    title: str | None = None,
    dpi: int = 150,
    branches: Sequence[str | Path] = (),
    multiplier_panel: bool = False,
) -> Path:
    """Read a sweep file and write its figure to ``out`` (format from the extension).

    Parameters
    ----------
    path : str or Path
        Sweep file written by :func:`stickslip_fast.sweep`.
    out : str or Path
        Image file (.png, .pdf, ...).
    variables : sequence of str, optional
        State names for a 1-D sweep (default x_i, phi_i).
    period_panel : bool
        Add a period panel (1-D sweeps).
    title : str, optional
    dpi : int
        Resolution of raster output.
    branches : sequence of path
        Branch files to overlay (1-D sweeps and censuses; see :func:`overlay_branches`).
    multiplier_panel : bool
        With branches: add the panel of their leading multipliers.

    Returns
    -------
    Path
        ``out``.
    """
    import h5py

    from stickslip_fast.bifurcation.continuation import Branch

    loaded = [Branch.from_hdf5(b) for b in branches]

    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        kind = h5.attrs.get("kind")
        file_title = str(h5.attrs.get("title", ""))
    if kind == "census":
        from stickslip_fast.analysis.census import load_census

        res = load_census(path)
        if not hasattr(res, "param"):  # a census over a plane: maps, not a diagram
            raise SystemExit(f"{path} is a census over two parameters: draw it with "
                             "scripts/plot_census_plane.py")  # fmt: skip
        fig = plot_census(res, variables, title=title if title is not None else file_title or None)
        if loaded:
            overlay_branches(fig, loaded, res.param, res.state_names, variables,
                             multiplier_panel=multiplier_panel)  # fmt: skip
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(out, dpi=dpi)
        plt.close(fig)
        return out
    data = read_sweep(path)
    data["path"] = str(path)
    if len(data["param"]) == 2:
        if loaded:
            raise ValueError("branches go on 1-D sweeps and censuses, not on a 2-D period map")
        fig = plot_period_map(data, title=title)
    else:
        fig = plot_bifurcation(data, variables, period_panel=period_panel, title=title)
        if loaded:
            overlay_branches(fig, loaded, data["param"][0], data["state_names"], variables,
                             multiplier_panel=multiplier_panel)  # fmt: skip
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of the runs of equal values of ``mask``, overlapping by one point."""
    out, a = [], 0
    for i in range(1, mask.size + 1):
        if i == mask.size or mask[i] != mask[a]:
            out.append((a, min(i + 1, mask.size)))
            a = i
    return out


def overlay_branches(
    fig: plt.Figure,
    branches: Sequence[Any],
    param: str,
    state_names: Sequence[str],
    variables: Sequence[str] | None = None,
    *,
    multiplier_panel: bool = False,
) -> plt.Figure:
    """Draw continuation branches over a bifurcation or census figure.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        From :func:`plot_bifurcation` or :func:`plot_census`: its first axes are
        the variable panels (one per kind of variable, in the order of ``variables``).
    branches : sequence of Branch
        :class:`stickslip_fast.bifurcation.continuation.Branch`, e.g. from ``Branch.from_hdf5``.
    param : str
        The figure's parameter; every branch must be continued in it.
    state_names : sequence of str
        The figure's state names; every branch's system must have the same.
    variables : sequence of str, optional
        As given to the figure (default x_i and phi_i).
    multiplier_panel : bool
        Append a panel of the largest |multiplier| (orbits) and the largest
        eigenvalue real part (equilibria) against the parameter.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``.

    Raises
    ------
    ValueError
        A branch in another parameter, or of a system with other state variables.
    """
    names = list(state_names)
    variables = list(variables) if variables else _default_vars(names)
    kinds: list[str] = []
    for v in variables:
        if _split(v)[0] not in kinds:
            kinds.append(_split(v)[0])
    axs = fig.axes[: len(kinds)]
    for b in branches:
        if b.param != param:
            raise ValueError(
                f"a branch continued in {b.param!r} cannot go on a figure of {param!r}"
            )
        if b.points.shape[1] != len(names):
            raise ValueError(
                f"a branch of {b.points.shape[1]} state variables cannot go on a figure of "
                f"{len(names)} ({', '.join(names)})"
            )
    for v in variables:
        ax = axs[kinds.index(_split(v)[0])]
        col = names.index(v)
        for b in branches:
            colour = "0.35" if b.period == 0 else "black"
            for a, z in _runs(np.asarray(b.stable, dtype=bool)):
                ax.plot(b.values[a:z], b.points[a:z, col], color=colour, lw=1.3,
                        ls="-" if b.stable[a] else "--", zorder=5)  # fmt: skip
            for bif in b.bifurcations:
                ax.plot([bif.value], [bif.point[col]], marker="o", ms=5, mfc="white",
                        mec="crimson", mew=1.5, zorder=6)  # fmt: skip
                ax.annotate(bif.label, (bif.value, bif.point[col]), xytext=(3, 4),
                            textcoords="offset points", fontsize=7, color="crimson", zorder=6)  # fmt: skip
    mine = [Line2D([], [], color="black", lw=1.3, label="branch, stable"),
            Line2D([], [], color="black", lw=1.3, ls="--", label="branch, unstable")]  # fmt: skip
    leg = axs[0].get_legend()
    if leg is None:
        axs[0].legend(handles=mine, fontsize=6.5, loc="best", framealpha=0.8)
    elif leg.get_bbox_to_anchor().bounds == axs[0].bbox.bounds:
        # the sweep's legend, inside the panel: one legend with the branch entries added
        labels = [t.get_text() for t in leg.get_texts()] + [h.get_label() for h in mine]
        axs[0].legend(handles=list(leg.legend_handles) + mine, labels=labels, fontsize=6.5,
                      loc="best", framealpha=0.8)  # fmt: skip
    else:  # the census's track legend, outside the panel, stays; the branch entries go inside
        axs[0].add_artist(leg)
        axs[0].legend(handles=mine, fontsize=6.5, loc="best", framealpha=0.8)
    if multiplier_panel:
        old = fig.axes
        heights = [ax.get_position().height for ax in old]
        gs = fig.add_gridspec(len(old) + 1, 1, height_ratios=heights + [0.35 * max(heights)])
        for i, ax in enumerate(old):
            ax.set_subplotspec(gs[i])
        mx = fig.add_subplot(gs[-1], sharex=old[0])
        for b in branches:
            if b.period == 0:
                y, colour = b.multipliers.real.max(axis=1), "0.35"
            else:
                y, colour = np.abs(b.multipliers).max(axis=1), "black"
            mx.plot(b.values, y, color=colour, lw=1.0)
        top = max((float(np.nanmax(ln.get_ydata())) for ln in mx.lines), default=1.0)
        bottom = min((float(np.nanmin(ln.get_ydata())) for ln in mx.lines), default=0.0)
        if top > 2.5:  # a multiplier racing off near a branch end would hide the rest
            mx.set_ylim(min(-0.1, bottom) - 0.1, 2.5)
            mx.text(0.99, 0.95, f"clipped at 2.5 (max {top:.3g})", transform=mx.transAxes,
                    ha="right", va="top", fontsize=6.5, color="0.3")  # fmt: skip
        mx.axhline(1.0, color="crimson", lw=0.8, ls=":")
        mx.axhline(0.0, color="0.5", lw=0.8, ls=":")
        mx.set_ylabel(r"max $|\mu|$ / max Re $\lambda$", fontsize=8)
        mx.set_xlabel(old[-1].get_xlabel())
        old[-1].set_xlabel("")
        old[-1].tick_params(labelbottom=False)
        fig.tight_layout()
    return fig


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("file", help="sweep or census result file (HDF5)")
    p.add_argument("-o", "--output", required=True, help="image file (.png, .pdf)")
    p.add_argument("--vars", help="comma-separated state names, e.g. x1,phi1 or x1,x2")
    p.add_argument("--period", action="store_true", help="add a period panel")
    p.add_argument("--title", help="figure title (default: the file's title)")
    p.add_argument("--dpi", type=int, default=150)
    p.add_argument("--branch", action="append", default=[], metavar="BRANCH.h5",
                   help="overlay a branch file (stickslip-fast continue); repeatable")  # fmt: skip
    p.add_argument("--multipliers", action="store_true",
                   help="with --branch: add a panel of the branches' leading multipliers")  # fmt: skip
    args = p.parse_args(argv)
    variables = [v.strip() for v in args.vars.split(",")] if args.vars else None
    out = plot_sweep(args.file, args.output, variables, period_panel=args.period,
                     title=args.title, dpi=args.dpi, branches=args.branch,
                     multiplier_panel=args.multipliers)  # fmt: skip
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
