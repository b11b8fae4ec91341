"""``stickslip-fast basins``: the ``[basins]`` config table, the command and its report.

TOML layout (next to the usual ``[system]`` and ``[integration]`` tables)::

    [basins]
    plane = ["x1", "phi1"]                        # two state names, or two vectors
    g1 = { start = -0.3, stop = 0.3, num = 80 }   # or a list of values
    g2 = { start = -0.3, stop = 0.3, num = 80 }
    # base = [0.0, 0.0, 0.0, 0.0]                 # the other coordinates (default 0)
    # stop = "converged"                          # fixed | converged (the default)
    # chunk_size, identity_tol, entropy_box

    [basins.refine]        # optional: bisect the boundary (refine_boundary)
    tol = 1e-6
    max_segments = 400
    seed = 0

    [basins.edge]          # optional: the saddle check (edge_check), after refine
    n_tracks = 24
    t_end = 600.0
    near = 1e-3

    [basins.manifold]      # optional: a saddle's stable manifold (cli.basins_manifold)
    point = [0.0726, 0.0, 0.1222, -0.0067]
    seeds = "boundary"     # (needs refine) or "scan"
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["parse_basins_table", "cmd_basins", "basins_report", "is_basins_file", "BASINS_KEYS"]

BASINS_KEYS = {
    "plane", "g1", "g2", "base", "stop", "chunk_size", "identity_tol", "entropy_box",
    "refine", "edge", "manifold",
}  # fmt: skip
_REFINE = {"tol": float, "max_segments": int, "seed": int}
_EDGE = {"n_tracks": int, "t_end": float, "near": float, "seed": int}


def _sub(table: Any, name: str, types: dict) -> dict:
    from .config_values import typed_table

    return typed_table(table, f"basins.{name}", types)


def parse_basins_table(table: dict[str, Any], n_state: int | None = None) -> dict[str, Any]:
    """Validate a ``[basins]`` table (types only; :func:`basins` checks the values).

    ``n_state``: the system's state length, for ``[basins.manifold].point``.
    """
    from .config_values import ConfigError, _values_from_spec

    unknown = set(table) - BASINS_KEYS
    if unknown:
        raise ConfigError(f"unknown key(s) in [basins]: {sorted(unknown)}; known: "
                          f"{sorted(BASINS_KEYS)}")  # fmt: skip
    if "g1" not in table or "g2" not in table:
        raise ConfigError("[basins] needs 'g1' and 'g2' (the grid of the two axes)")
    out: dict[str, Any] = {
        "grid": (_values_from_spec(table["g1"], "[basins].g1"),
                 _values_from_spec(table["g2"], "[basins].g2")),
    }  # fmt: skip
    if "plane" in table:
        p = table["plane"]
        if not isinstance(p, list) or len(p) != 2:
            raise ConfigError(f"[basins].plane must be two state names or two vectors, got {p!r}")
        out["plane"] = tuple(p)
    if "base" in table:
        try:
            out["base"] = np.asarray(table["base"], dtype=float)
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"[basins].base must be a list of numbers: {exc}") from None
    for key, typ in (("chunk_size", int), ("entropy_box", int), ("identity_tol", float),
                     ("stop", str)):  # fmt: skip
        if key in table:
            v = table[key]
            good = (
                isinstance(v, str)
                if typ is str
                else (
                    not isinstance(v, bool) and isinstance(v, (int, float) if typ is float else int)
                )
            )
            if not good:
                raise ConfigError(f"[basins].{key} must be {typ.__name__}, got {v!r}")
            out[key] = typ(v)
    if "refine" in table:
        out["refine"] = _sub(table["refine"], "refine", _REFINE)
    if "edge" in table:
        if "refine" not in table:
            raise ConfigError("[basins.edge] needs [basins.refine] (it follows refined points)")
        out["edge"] = _sub(table["edge"], "edge", _EDGE)
    if "manifold" in table:
        from .basins_manifold import parse_manifold_table

        out["manifold"] = parse_manifold_table(table["manifold"], has_refine="refine" in table,
                                               n_state=n_state)  # fmt: skip
    return out


def cmd_basins(cfg: Any, args: Any) -> int:
    """Run a ``[basins]`` config into ``args.output`` (the CLI's ``basins`` command)."""
    from ..analysis.basins import basins
    from ..bifurcation.basin_saddles import edge_check
    from .config_values import ConfigError

    if cfg.basins is None:
        raise ConfigError(f"{cfg.source}: a basins map needs a [basins] section with g1 and g2")
    c = dict(cfg.basins)
    integ = dict(cfg.integration)
    if "stop" in integ:
        if "stop" in c and c["stop"] != integ["stop"]:
            raise ConfigError(f"{cfg.source}: [integration].stop and [basins].stop disagree")
        c["stop"] = integ.pop("stop")
    edge = c.pop("edge", None)
    manifold = c.pop("manifold", None)
    backend = args.backend or ("dask" if (args.scheduler or args.workers) else "local")
    res = basins(
        cfg.system, c.pop("grid"), out=args.output, threads=args.threads,
        progress=False if args.quiet else None, backend=backend, scheduler=args.scheduler,
        n_workers=args.workers, title=cfg.title, notes=cfg.notes, **c, **integ,
    )  # fmt: skip
    if edge is not None:
        edge_check(res, **edge)
    if manifold is not None:
        from .basins_manifold import run_manifold

        _, computed = run_manifold(res, manifold, c.get("refine"))
        if not computed and not args.quiet:
            print("manifold:  stored for the same settings; not recomputed")
    if not args.quiet:
        print(basins_report(args.output))
    return 0


def basins_report(path: Any) -> str:
    """A text summary of a basins file: grid, attractors with fractions, measures."""
    from ..analysis.basins import load_basins

    r = load_basins(path)
    n1, n2 = r.shape
    a, b = r.axis_names
    lines = [
        f"file:      {path}  (basins)",
        f"plane:     {a} in [{r.g1[0]:g}, {r.g1[-1]:g}] x {b} in [{r.g2[0]:g}, {r.g2[-1]:g}]"
        f" ({n1} x {n2} cells), eta = {r.system.eta:g}",
        "attractors:",
    ]
    fr = r.fractions(stderr=True)
    for att in r.attractors:
        f, se = fr[att.id]
        per = f" period {att.period}" if att.period else ""
        lines.append(f"  id {att.id}: {att.kind}{per}, fraction {f:.4f} +- {se:.4f}")
    if -1 in fr:
        lines.append(f"  failed: {fr[-1][0]:.4f}")
    m = r.measures()
    lines.append(
        f"measures:  S_b = {m['basin_entropy']:.4f}, S_bb = {m['boundary_basin_entropy']:.4f} "
        f"(box {m['entropy_box']}), uncertainty exponent {m['uncertainty_exponent']:.3f} +- "
        f"{m['uncertainty_exponent_stderr']:.3f} (boundary dimension "
        f"{m['boundary_dimension']:.3f}), Wada: grid test {'yes' if m['wada'] else 'no'}, "
        f"merging test {'yes' if m['wada_merge'] else 'no'}"
    )
    if r.boundary is not None:
        bd = r.boundary
        lines.append(f"boundary:  {len(bd.u)} segments refined to {bd.tol:g} "
                     f"({bd.n_pairs} boundary pairs, {bd.n_runs} runs)")  # fmt: skip
    if r.edge is not None:
        lines += _edge_lines(r.edge)
    if r.manifold is not None:
        from .basins_manifold import manifold_line

        lines.append(manifold_line(r.manifold))
    from ..io.basins_extras import manifold_scan_summary

    sc = manifold_scan_summary(path)
    if sc is not None:
        lines.append(
            f"seed scan: {sc['grid'][0]} x {sc['grid'][1]} nodes, {sc['seeds']} seeds from "
            f"{sc['edges']} sign-change edges, {sc['n_evals']} evaluations; stored, so a trace "
            "of the same saddle with the same scan settings reads it"
        )
    return "\n".join(lines)


def _edge_lines(e: Any) -> list[str]:
    """The report's lines on the saddle check."""
    lines = []
    sm = e.summary
    mu = ", ".join(f"{abs(z):.4g}" for z in e.saddle_multipliers[:3])
    lines.append(
        f"edge:      {len(e.u)} brackets followed: their two runs split after a median "
        f"{sm['median_split_crossing']:g} crossings (t = {sm['median_t_split']:.4g})"
    )
    if e.saddle_period == 0:
        lines.append("saddle:    no saddle orbit of the periods searched was found")
        return lines
    lines.append(
        f"saddle:    period {e.saddle_period} ({e.saddle_status}), |multipliers| {mu}; "
        f"boundary runs: median closest approach {sm['boundary_median_min_distance']:.2e}, "
        f"control runs: {sm['control_median_min_distance']:.2e}"
    )
    return lines


def is_basins_file(path: Any) -> bool:
    """Whether a census file is a basins file (its configuration says kind "basins")."""
    import json

    from ..io import read_root_attrs

    return json.loads(read_root_attrs(path)["config"]).get("kind") == "basins"
