"""Draw a census over a plane of two parameters: the maps of docs/census.md.

Reads the census file (``stickslip-fast census`` with ``param = [p1, p2]``) through
:func:`stickslip_fast.analysis.census.load_census` and draws three panels over
the plane, one cell per grid point:

- **attractors**: the number of attractors found in the cell (from its starts);
- **steady sliding**: the share of the starts that end in steady sliding (0: stick-slip
  from every start, 1: sliding from every start; in between it depends on the start);
- **dominant period**: the period of the attractor with the largest basin (or steady
  sliding, a stalled motor, "?" for unresolved runs).

Curves (fold or period-doubling curves of a two-parameter continuation) can be laid
over the panels with ``draw_maps(..., curves=[(values (n, 2), style dict), ...])``.

Usage::

    python3 scripts/plot_census_plane.py out/census_plane_eta_k12.h5 \\
        -o docs/figures/census_plane_eta_k12.png
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import BoundaryNorm, ListedColormap  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

LABELS = {"eta": r"$\eta$", "k12": r"$k_{12}$", "vb0": r"$v_{b0}$", "vb": r"$v_b$"}


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges around the grid values (midpoints; half a step beyond the ends)."""
    v = np.asarray(v, dtype=float)
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


#: Colours of the dominant-period map, the same in every figure (orbits by period).
PERIOD_COLOURS = {-3: "tab:gray", -2: "black", -1: "tab:purple", 0: "tab:blue"}
ORBIT_COLOURS = ["tab:orange", "tab:green", "tab:red", "tab:brown", "tab:pink", "tab:olive"]


def _discrete(ax, x, y, z, ticks, ticklabels, cmap_name, title, colours=None):
    """A map of small integers with one colour each and a labelled colour bar."""
    if colours is None:
        colours = plt.get_cmap(cmap_name)(np.linspace(0.05, 0.95, len(ticks)))
    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(len(ticks) + 1) - 0.5, len(ticks))
    index = np.searchsorted(ticks, z)
    mesh = ax.pcolormesh(x, y, index.T, cmap=cmap, norm=norm)
    cb = plt.colorbar(mesh, ax=ax, ticks=np.arange(len(ticks)))
    cb.ax.set_yticklabels(ticklabels)
    ax.set_title(title, fontsize=10)


def draw_maps(res, axes=None, curves=()):
    """Draw the three maps of a :class:`CensusPlaneResult` on three axes (made if None)."""
    if axes is None:
        _, axes = plt.subplots(1, 3, figsize=(15.5, 4.4))
    (p1, p2), (v1, v2) = res.params, res.values
    x, y = _edges(v1), _edges(v2)
    n_att = res.n_attractors(stalls_as_one=True)
    stalls = any(a.kind == "stalled" for row in res.attractors for c in row for a in c)
    ticks = np.arange(n_att.min(), n_att.max() + 1)
    _discrete(axes[0], x, y, n_att, ticks, [str(t) for t in ticks], "viridis",
              "attractors" + (" (stalled states counted once)" if stalls else ""))  # fmt: skip
    mesh = axes[1].pcolormesh(x, y, res.sliding_fraction().T, cmap="coolwarm", vmin=0, vmax=1)
    plt.colorbar(mesh, ax=axes[1], label="share of the starts")
    axes[1].set_title("basin fraction of steady sliding", fontsize=10)
    dom = res.dominant_period()
    ticks = np.unique(dom)
    names = {0: "sliding", -1: "?", -2: "failed", -3: "stalled"}
    colours = [PERIOD_COLOURS.get(int(t), ORBIT_COLOURS[(int(t) - 1) % 6]) for t in ticks]
    _discrete(axes[2], x, y, dom, ticks, [names.get(int(t), f"P{t}") for t in ticks], None,
              "period of the largest basin", colours)  # fmt: skip
    for ax in axes:
        for values, style in curves:
            ax.plot(values[:, 0], values[:, 1], **{"color": "k", "lw": 1.2, **style})
        ax.set_xlabel(LABELS.get(p1, p1))
        ax.set_ylabel(LABELS.get(p2, p2))
        ax.set_xlim(x[0], x[-1])
        ax.set_ylim(y[0], y[-1])
    return axes


def plot_plane(file, image, curve_files=(), title=None):
    """Draw a census plane's three maps from its file, with curve files laid over them.

    Parameters
    ----------
    file : str or Path
        A census file over a plane (``stickslip-fast census`` with two params).
    image : str or Path
        The figure to write.
    curve_files : sequence of str or Path
        Curve files of :func:`stickslip_fast.continue_bifurcation` in the census's
        two parameters.
    title : str, optional
        The figure's title (default: the file's).

    Returns
    -------
    Path
        ``image``.
    """
    import h5py

    from stickslip_fast.analysis.census import load_census
    from stickslip_fast.analysis.census_plane import CensusPlaneResult
    from stickslip_fast.bifurcation.curve import Curve

    res = load_census(file)
    if not isinstance(res, CensusPlaneResult):
        raise ValueError(f"{file} is a census over one parameter; use scripts/plot_bifurcation.py")
    curves = []
    for path in curve_files:
        curve = Curve.from_hdf5(path)
        if (curve.param, curve.param2) != tuple(res.params):
            raise ValueError(
                f"{path} is a curve in ({curve.param}, {curve.param2}), the census in {res.params}"
            )
        curves.append((curve.values, {"color": "k", "lw": 1.4}))
    fig, axes = plt.subplots(1, 3, figsize=(15.5, 4.4))
    draw_maps(res, axes, curves)
    with h5py.File(file, "r", libver="latest", swmr=True) as h5:
        title = title if title is not None else str(h5.attrs.get("title", ""))
    n1, n2 = res.shape
    fig.suptitle(f"{title}  ({n1} x {n2} cells x {len(res.starts)} starts)", fontsize=10)
    fig.tight_layout()
    out = Path(image)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("file", metavar="CENSUS.h5")
    p.add_argument("-o", "--output", required=True, metavar="FIG.png")
    p.add_argument("--title", default=None, help="figure title (default: the file's)")
    p.add_argument("--curve", action="append", default=[], metavar="CURVE.h5",
                   help="a curve file of continue_bifurcation to lay over the maps (repeatable)")  # fmt: skip
    args = p.parse_args(argv)
    try:
        out = plot_plane(args.file, args.output, args.curve, args.title)
    except ValueError as err:
        p.error(str(err))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
