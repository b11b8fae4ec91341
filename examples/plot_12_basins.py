"""
Basins of attraction, and whether they are Wada
===============================================

At η = 9.0 three attractors share the plane of starts at rest: the period-2
orbit, a period-6 orbit and steady sliding. :func:`stickslip_fast.basins` runs
one start per cell of a grid over (x₁, φ₁) and labels each cell with the
attractor it reaches (the census's ids). Are the three basins *Wada*, every
boundary point on the boundary of all three? Two tests answer on a grid
(docs/basins.md): the grid test asks whether each boundary cell sees every basin
within r cells; the merging method of Daza, Wagemakers and Sanjuán (2018) merges
all basins but one and compares the boundaries of those two-colour maps. On a
finite grid both pass at some r; the question is whether that r stays put as the
grid is refined (Wada), or grows (not Wada).
"""

import matplotlib.pyplot as plt
import numpy as np

import stickslip_fast as ssf

system = ssf.System.preset("asymmetric", eta=9.0)
maps = {}
for n in (40, 80):
    g = np.linspace(-0.3, 0.3, n)
    maps[n] = ssf.basins(system, (g, g), plane=("x1", "phi1"), progress=False)
res = maps[80]
for a in res.attractors:
    print(f"id {a.id}: {a.kind}, period {a.period}, fraction {a.fraction:.3f}")
print(f"S_b = {res.basin_entropy():.3f}, S_bb = {res.boundary_basin_entropy():.3f}")

# %%
# The map at 80 × 80 cells (``res.labels``: an attractor id per cell), and each
# test's share at r = 1 … 5 on both grids. The grid test's share of boundary cells
# that see all three basins *falls* as the grid is refined, and the merging test's
# share of a merged boundary that lies farther than r cells from another one
# *rises*: at a fixed r, a finer grid puts more cells between a stretch of boundary
# shared by two basins and the third. Not Wada (at 160 × 160 the merging test leaves
# 36 % uncovered at r = 5; Newton's basins for z³ = 1, which are Wada, need r = 2 at
# every resolution).

fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10, 4.2), layout="constrained")
names = {a.id: f"{a.kind} P{a.period}" if a.period else a.kind for a in res.attractors}
ids = sorted(names)
img = ax0.imshow(np.searchsorted(ids, res.labels).T, origin="lower", cmap="viridis",
                 extent=(res.g1[0], res.g1[-1], res.g2[0], res.g2[-1]), aspect="auto")  # fmt: skip
cbar = fig.colorbar(img, ax=ax0, ticks=range(len(ids)))
cbar.ax.set_yticklabels([names[i] for i in ids])
ax0.set(xlabel="x₁(0)", ylabel="φ₁(0)", title="η = 9.0, starts at rest (80 × 80)")
for n, style in ((40, "o--"), (80, "s-")):
    w, wm = maps[n].wada(), maps[n].wada_merge()
    print(f"{n} x {n}: grid test {np.round(w.fraction, 3)}, merging test "
          f"{np.round(wm.uncovered, 3)}, Wada: {w.is_wada} / {wm.is_wada}")  # fmt: skip
    ax1.plot(
        w.radii, w.fraction, style, color="C0", label=f"grid test, {n}²: boundary cells seeing all"
    )
    ax1.plot(
        wm.radii, wm.uncovered, style, color="C3", label=f"merging test, {n}²: boundary uncovered"
    )
ax1.set(xlabel="r (cells)", ylabel="share", ylim=(0, 1), title="the two Wada tests")
ax1.legend(fontsize=8)
plt.show()
