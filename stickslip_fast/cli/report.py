"""The summaries ``stickslip-fast info`` (and every command unless --quiet) prints for a result file."""

from __future__ import annotations

import json

import numpy as np


def _header(name: str, attrs: dict, cfg: dict) -> list[str]:
    """The first lines of every summary: file, title, package, system."""
    lines = [f"file:      {name}"]
    if attrs.get("title"):
        lines.append(f"title:     {attrs['title']}")
    lines.append(
        f"package:   stickslip_fast {attrs.get('package_version', '?')}, "
        f"schema {attrs.get('schema_version')}, label rules {attrs.get('label_rules', 1)}, "
        f"created {attrs.get('created', '?')}"
    )
    sysd = {k: v for k, v in cfg.get("system", {}).items() if v is not None}
    lines.append("system:    " + " ".join(f"{k}={v}" for k, v in sysd.items()))
    return lines


def _census_report(path) -> str:
    """A text summary of a census file: configuration, progress, attractors per value."""
    from ..analysis.census import load_census
    from ..core.poincare import STATUS_NAMES
    from ..io import read_root_attrs

    attrs = read_root_attrs(path)
    cfg = json.loads(attrs["config"])
    res = load_census(path)
    done = res.raw["done"].astype(bool)
    lines = _header(f"{path}  (census)", attrs, cfg)
    if isinstance(cfg["param"], list):
        return "\n".join(lines + _plane_lines(res, cfg, done))
    v = res.values
    lines.append(
        f"census:    {res.param} in [{v.min():g}, {v.max():g}] ({v.size} values) x "
        f"{len(res.starts)} starts, stop={cfg['stop']}"
    )
    st = cfg["settings"]
    lines.append(
        f"settings:  method={st['method']} rtol={st['rtol']:g} atol={st['atol']:g} "
        f"t_end={st['t_end']:g} t_transient={st['t_transient']:g} max_points={st['max_points']}"
    )
    lines.append(
        f"progress:  {int(done.sum())} of {done.size} runs done ({100 * done.mean():.1f}%)"
    )
    if done.any():
        codes, counts = np.unique(res.status_code[done], return_counts=True)
        lines.append(
            "status:    " + ", ".join(f"{STATUS_NAMES[c]} {n}" for c, n in zip(codes, counts))
        )
        lines.append(f"tracks:    {len(res.tracks)} (classified from the runs done so far)"
                     if not done.all() else f"tracks:    {len(res.tracks)}")  # fmt: skip
        for t in res.tracks:
            desc = t.kind if t.kind != "orbit" else f"orbit P{'/P'.join(map(str, t.periods))}"
            frac = res.fractions()[t.birth : t.death + 1, t.id]
            lines.append(
                f"  #{t.id:<3d} {desc:<22s} {res.param} {v[t.birth]:g}..{v[t.death]:g}"
                f"{'  born' if t.born else ''}{'  dies' if t.dies else ''}"
                f"  basin {frac.min():.2f}-{frac.max():.2f}"
            )
    return "\n".join(lines)


def _plane_lines(res, cfg: dict, done: np.ndarray) -> list[str]:
    """The summary of a census over a plane: grid, progress, tracks, and the maps in brief."""
    from ..core.poincare import STATUS_NAMES

    (p1, p2), (v1, v2) = res.params, res.values
    st = cfg["settings"]
    lines = [
        f"census:    {p1} in [{v1.min():g}, {v1.max():g}] ({v1.size}) x {p2} in "
        f"[{v2.min():g}, {v2.max():g}] ({v2.size}) cells x {len(res.starts)} starts, "
        f"stop={cfg['stop']}",
        f"settings:  method={st['method']} rtol={st['rtol']:g} t_end={st['t_end']:g} "
        f"t_transient={st['t_transient']:g} max_points={st['max_points']}",
        f"progress:  {int(done.sum())} of {done.size} runs done ({100 * done.mean():.1f}%)",
    ]
    if not done.any():
        return lines
    codes, counts = np.unique(res.status_code[done], return_counts=True)
    lines.append("status:    " + ", ".join(f"{STATUS_NAMES[c]} {n}" for c, n in zip(codes, counts)))
    sl = res.sliding_fraction()
    lines.append(
        f"cells:     {int(np.sum(sl == 1.0))} steady sliding from every start, "
        f"{int(np.sum(sl == 0.0))} never, {int(np.sum((sl > 0) & (sl < 1)))} depending on the start"
    )
    lines.append(f"tracks:    {len(res.tracks)}")
    for t in res.tracks:
        desc = t.kind if t.kind != "orbit" else f"orbit P{'/P'.join(map(str, t.periods))}"
        i0, i1, j0, j1 = t.extent
        lines.append(
            f"  #{t.id:<3d} {desc:<22s} {t.n_cells:5d} cells, {p1} {v1[i0]:g}..{v1[i1]:g}, "
            f"{p2} {v2[j0]:g}..{v2[j1]:g}"
        )
    return lines


def _report(path, verify: bool = False) -> str:
    """A text summary of a result file: configuration, progress, periods, statuses.

    A trajectory file (``simulate -o``) gets its own summary. With ``verify``,
    every chunk of a sweep file is read (checksums) and the swept values are
    checked against their SHA-256; a damaged file raises
    :class:`~stickslip_fast.io.ResultFileError` after the summary is printed.
    """
    from ..io import file_kind, read_trajectory_header, sweep_summary, verify_sweep, writer_alive

    if file_kind(path) == "trajectory":
        return _trajectory_report(path, read_trajectory_header(path))
    text, has_fletcher = _sweep_report(path, sweep_summary(path))
    if not verify:
        return text
    if writer_alive(path):
        return text + "\nintegrity: not checked (a sweep is writing this file now)"
    problems, bad = verify_sweep(path)
    if problems:
        print(text)
        from ..io import ResultFileError

        raise ResultFileError(
            f"{path} is corrupted: {'; '.join(problems)} ({int(bad.sum())} of {bad.size} "
            "values affected). Run the same sweep again to recompute them."
        )
    checksums = "Fletcher-32 and SHA-256 verified" if has_fletcher else "SHA-256 verified"
    return text + f"\nintegrity: ok (every chunk read; {checksums})"


def _sweep_report(path, info: dict) -> tuple[str, bool]:
    from ..core.poincare import STATUS_NAMES

    cfg, attrs = info["config"], info["attrs"]
    done, status, period = info["done"], info["status"], info["period"]
    lines = _header(str(path), attrs, cfg)
    axes = [f"{n} in [{a.min():g}, {a.max():g}] ({a.size} values)" for n, a in info["axes"].items()]
    lines.append("sweep:     " + " x ".join(axes) + f", mode {cfg['mode']}")
    st = cfg["settings"]
    lines.append(
        f"settings:  method={st['method']} rtol={st['rtol']:g} atol={st['atol']:g} "
        f"t_end={st['t_end']:g} t_transient={st['t_transient']:g} max_points={st['max_points']}"
    )
    lines.append(
        f"progress:  {int(done.sum())} of {done.size} values done ({100 * done.mean():.1f}%)"
    )
    if done.any():
        codes, counts = np.unique(status[done], return_counts=True)
        lines.append(
            "status:    "
            + ", ".join(
                f"{STATUS_NAMES[c] if 0 <= c < len(STATUS_NAMES) else f'code {c}'} {n}"
                for c, n in zip(codes, counts)
            )
        )
        ok = done & (status == 0)
        if ok.any():
            per, pc = np.unique(period[ok], return_counts=True)
            hist = ", ".join(f"{'none' if p == 0 else f'P{p}'}: {n}" for p, n in zip(per, pc))
            lines.append(f"periods:   {hist}")
    return "\n".join(lines), bool(info.get("fletcher32"))


def _trajectory_report(path, tr: dict) -> str:
    """The summary of a single-run file written by ``simulate -o`` (from
    ``read_trajectory_header``: its arrays are not read)."""
    a, cfg = tr["attrs"], tr["config"]
    st = cfg.get("settings", {})
    lines = _header(f"{path} (single run, simulate -o)", a, cfg)
    if st:
        lines.append(
            f"settings:  method={a.get('method', st.get('method'))} rtol={st['rtol']:g} "
            f"atol={st['atol']:g} t_end={st['t_end']:g} t_transient={st['t_transient']:g}"
        )
    period = int(a["period"])
    lines.append(
        f"result:    status {a['status']}, period {period if period else 'none detected'}, "
        f"{int(a['n_steps'])} steps ({int(a['n_rejected'])} rejected), "
        f"{int(a['n_crossings'])} Poincare crossings"
    )
    n_t = tr["n_samples"]
    sample = cfg.get("sample_dt")
    lines.append(
        f"data:      {tr['n_points']} Poincare points, {n_t} samples"
        + (f" every {sample:g}" if n_t and sample else "")
        + f"; state {', '.join(tr['state_names'])}"
    )
    return "\n".join(lines)
