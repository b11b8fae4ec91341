"""Classify the zero-state diagram's transitions with a census file.

Usage::

    python scripts/census_transitions.py CENSUS.h5 [--start 0] [--markdown]

For every pair of neighbouring values where the given start (default 0, the
zero state: the paper's fixed initial condition) changes attractor, it prints
whether the attractor it leaves **dies** there (a bifurcation: its track ends)
or **goes on** (the track lives on to the value printed), and whether the
attractor it joins is **born** there or already existed. Verdict: a
bifurcation when the attractor left dies or the one joined is born there; a
basin-boundary crossing when both exist on both sides. Reads only the file (re-classified with the file's settings).
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from stickslip_fast.analysis.census import CensusResult, load_census  # noqa: E402

__all__ = ["transitions", "main"]


def _describe(res: CensusResult, i: int, track: int) -> str:
    if track < 0:
        return f"failed ({res.status[i, 0]})"
    for a in res.attractors[i]:
        if a.id == track:
            what = f"P{a.period} orbit" if a.kind == "orbit" else a.kind
            if a.kind == "equilibrium":
                what = "steady sliding"
            return f"#{track} {what} (basin {a.fraction:.2f})"
    return f"#{track}"


def transitions(res: CensusResult, start: int = 0) -> list[dict]:
    """The changes of attractor of ``start`` between neighbouring values, classified."""
    vals = res.values
    out = []
    for i in range(len(vals) - 1):
        a, b = int(res.labels[i, start]), int(res.labels[i + 1, start])
        if a == b or "missing" in (res.status[i, start], res.status[i + 1, start]):
            continue
        row = {
            "from_value": float(vals[i]),
            "to_value": float(vals[i + 1]),
            "from": _describe(res, i, a),
            "to": _describe(res, i + 1, b),
        }
        if a >= 0:
            t = res.tracks[a]
            row["old_track"] = (
                f"dies after {vals[t.death]:g}" if t.death == i else f"goes on to {vals[t.death]:g}"
            )
            row["old_dies"] = t.death == i
        else:
            row["old_track"], row["old_dies"] = "-", False
        if b >= 0:
            t = res.tracks[b]
            row["new_track"] = (
                f"born at {vals[t.birth]:g}"
                if t.birth == i + 1
                else f"exists from {vals[t.birth]:g}"
            )
            row["new_born"] = t.birth == i + 1
        else:
            row["new_track"], row["new_born"] = "-", False
        if row["old_dies"]:
            row["verdict"] = "bifurcation (the attractor left dies)"
        elif row["new_born"]:
            row["verdict"] = "bifurcation (the attractor joined is born; the one left goes on)"
        elif a >= 0 and b >= 0:
            row["verdict"] = "basin-boundary crossing (both attractors exist on both sides)"
        else:
            row["verdict"] = "-"
        out.append(row)
    return out


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("file", help="census result file (HDF5)")
    p.add_argument("--start", type=int, default=0, help="start index (default 0: zero state)")
    p.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = p.parse_args(argv)
    res = load_census(args.file)
    rows = transitions(res, args.start)
    p_ = res.param
    if args.markdown:
        print(f"| {p_} | from | to | attractor left | attractor joined | verdict |")
        print("|---|---|---|---|---|---|")
        for r in rows:
            print(
                f"| {r['from_value']:g} → {r['to_value']:g} | {r['from']} | {r['to']} | "
                f"{r['old_track']} | {r['new_track']} | {r['verdict']} |"
            )
    else:
        for r in rows:
            print(
                f"{p_} {r['from_value']:g} -> {r['to_value']:g}: {r['from']} -> {r['to']}; "
                f"left: {r['old_track']}; joined: {r['new_track']}; {r['verdict']}"
            )
    print("\ntracks:")
    fr = res.fractions()
    for t in res.tracks:
        per = "/".join(map(str, t.periods))
        span = fr[t.birth : t.death + 1, t.id]
        print(
            f"  #{t.id} {t.kind} P{per} {p_} {res.values[t.birth]:g}..{res.values[t.death]:g}"
            f"{' born' if t.born else ''}{' dies' if t.dies else ''} "
            f"basin {span.min():.2f}-{span.max():.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
