"""``stickslip-fast continue``: a branch from a config's orbit or equilibrium, and the branches
switched to at its period-doublings."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ..base.journal import journal
from .arguments import _check_writable, _config_from_args
from .config import ConfigError, RunConfig


def _cmd_continue(args: argparse.Namespace) -> int:
    cfg = _config_from_args(args)
    if cfg.continuation is None:
        raise ConfigError(
            f"{cfg.source}: continuation needs a [continue] section with param and bounds"
        )
    _check_writable(args.output, "-o")
    c = dict(cfg.continuation)
    param, bounds = c.pop("param"), c.pop("bounds")
    start = c.pop("start", "orbit")
    direction = c.pop("direction", 1.0)
    switch = c.pop("switch", False)
    curve = {k: c.pop(k) for k in ("param2", "bounds2", "direction2", "kinds2") if k in c}
    say = (lambda *a: None) if args.quiet else (lambda *a: print(*a, file=sys.stderr))
    c["progress"] = False if args.quiet else None  # a bar of the points in a terminal
    # every integration goes to a checkpoint beside the output until all files are written:
    # the same command resumes after a kill, bit-identically (base/journal.py)
    checkpoint = Path(f"{args.output}.checkpoint")
    config = dict(system=cfg.system, integration=cfg.integration, y0=cfg.y0,
                  sample_dt=cfg.sample_dt, continuation=cfg.continuation)  # fmt: skip
    with journal(checkpoint, "stickslip-fast continue", config) as j:
        if j.recorded:
            say(f"resuming from {checkpoint} ({j.recorded} integrations recorded) ...")
        _branches(cfg, c, args, say, (param, bounds, start, direction, switch, curve))
    checkpoint.unlink(missing_ok=True)
    return 0


def _branches(cfg, c, args, say, what):
    """The branch of ``cfg``'s orbit or equilibrium, and the branches and curves from it."""
    from ..bifurcation.continuation import (
        continue_equilibrium,
        continue_orbit,
        join_branches,
        switch_branch,
    )

    param, bounds, start, direction, switch, curve = what
    if start == "orbit":
        first, follow = _orbit_from_config(cfg, param, c.pop("period", None), say), continue_orbit
    else:
        first, follow = _equilibrium_from_config(cfg, param, start, say), continue_equilibrium
    say(f"continuing in {param} over {list(bounds)} ...")
    if direction == "both":
        branch = join_branches(follow(first, param, bounds, direction=-1.0, **c),
                               follow(first, param, bounds, direction=1.0, **c))  # fmt: skip
    else:
        branch = follow(first, param, bounds, direction=direction, **c)
    branch.to_hdf5(args.output)
    if not args.quiet:
        print(f"file:      {args.output}  (branch)")
        print(branch.summary())
    if switch:
        _switch_and_follow(branch, bounds, c, args, say, switch_branch, continue_orbit)
    if curve:
        _curves(branch, curve, c.get("tol", 1e-10), c.get("stick_events", True), args, say)


def _curves(branch, curve, tol, stick_events, args, say):
    """[continue].param2: every fold, period-doubling and Neimark-Sacker point of an orbit
    ``branch`` (every fold and Hopf point of an equilibrium branch; or the kinds of
    [continue].kinds2, e.g. "stick-phase") followed in param2, into OUTPUT's stem +
    ``.curve<k>.h5``."""
    from ..bifurcation.curve import continue_bifurcation

    out = Path(args.output)
    default = ("fold", "period-doubling", "neimark-sacker") if branch.period else ("fold", "hopf")
    kinds = curve.get("kinds2", default)
    bifs = [b for b in branch.bifurcations if b.kind in kinds]
    if not bifs:
        say(f"param2: the branch has no {' or '.join(kinds)}")
    for k, bif in enumerate(bifs, start=1):
        say(
            f"following the {bif.kind} at {branch.param} = {bif.value:.10g} in {curve['param2']} ..."
        )
        c = continue_bifurcation(branch, bif, curve["param2"], curve["bounds2"],
                                 direction=curve.get("direction2", 1.0), tol=tol,
                                 stick_events=stick_events,
                                 progress=False if args.quiet else None)  # fmt: skip
        path = out.with_name(f"{out.stem}.curve{k}{out.suffix or '.h5'}")
        c.to_hdf5(path)
        if not args.quiet:
            lo, hi = c.values.min(axis=0), c.values.max(axis=0)
            print(f"file:      {path}  ({c.kind} curve, {len(c.values)} points, "
                  f"{c.param} in [{lo[0]:.10g}, {hi[0]:.10g}], {c.param2} in "
                  f"[{lo[1]:.10g}, {hi[1]:.10g}], ended: {c.status}; codim-2: "
                  f"{[(p.kind, p.values.tolist()) for p in c.codim2]})")  # fmt: skip


def _switch_and_follow(branch, bounds, settings, args, say, switch_branch, continue_orbit):
    """[continue].switch: from each period-doubling of ``branch``, the doubled orbit's
    branch, from each symmetry-breaking point, the branch with the disks apart, and from
    each branch point, the crossing branch, each continued away from it, into OUTPUT's
    stem + ``.pd<k>.h5`` / ``.sb<k>.h5`` / ``.bp<k>.h5``."""
    from ..bifurcation.walk_args import BRANCH_POINT_DS

    out = Path(args.output)
    found = False
    for kind, tag in (("period-doubling", "pd"), ("symmetry-breaking", "sb"),
                      ("branch-point", "bp")):  # fmt: skip
        bifs = [b for b in branch.bifurcations if b.kind == kind]
        found = found or bool(bifs)
        for k, bif in enumerate(bifs, start=1):
            say(f"switching at the {kind} at {branch.param} = {bif.value:.10g} ...")
            orbit = switch_branch(branch, bif, tol=settings.get("tol", 1e-10),
                                  shooting=settings.get("shooting", "single"),
                                  **{key: settings[key] for key in ("segments",) if key in settings})  # fmt: skip
            if not orbit.converged:
                print(f"{kind} {k} at {bif.value:.10g}: {orbit.message}", file=sys.stderr)
                continue
            walk = dict(settings)  # continue_orbit walks away from the orbit's origin
            if kind == "branch-point" and "ds" in walk:  # and from a branch point: at most
                walk["ds"] = min(walk["ds"], BRANCH_POINT_DS)  # its small first step
            new = continue_orbit(orbit, branch.param, bounds, **walk)
            path = out.with_name(f"{out.stem}.{tag}{k}{out.suffix or '.h5'}")
            new.to_hdf5(path)
            if not args.quiet:
                print(f"file:      {path}  (period-{orbit.period} branch from the "
                      f"{kind} at {bif.value:.10g})")  # fmt: skip
                print(new.summary())
    if not found:
        say("switch: the branch has no period-doubling, symmetry-breaking or branch point")


def _orbit_from_config(cfg: RunConfig, param: str, period, say):
    """The orbit of the config's system: a simulation from [initial], then Newton."""
    from ..analysis.simulate import simulate
    from ..bifurcation.orbits import find_orbit
    from ..bifurcation.synchrony import sync_stability, synchronous_point

    value = getattr(cfg.system, param)
    say(f"settling at {param} = {value:g} (t_end {cfg.integration['t_end']:g}) ...")
    sim = simulate(cfg.system, y0=cfg.y0, **cfg.integration)
    if sim.status != "ok" or sim.period < 1:
        raise ValueError(
            f"the simulation at {param} = {value:g} ended {sim.status!r} with period "
            f"{sim.period}: no periodic orbit to continue; change [system].{param}, "
            "[initial] or [integration].t_end"
        )
    orbit = find_orbit(cfg.system, sim, period)
    if not orbit.converged:
        raise ValueError(
            f"Newton on the return map did not converge at {param} = {value:g} "
            f"(status {orbit.status!r}: {orbit.message})"
        )
    lead = np.abs(orbit.multipliers).max() if orbit.multipliers.size else float("nan")
    say(f"orbit: period {orbit.period}, T = {orbit.T:.10g}, residual {orbit.residual:.2g}, "
        f"|leading multiplier| {lead:.4g}")  # fmt: skip
    if cfg.system.n_oscillators >= 2 and all(
        synchronous_point(cfg.system, z) for z in orbit.points
    ):
        sync = sync_stability(orbit)
        across, along = (_number(m[0]) for m in (sync.transverse, sync.longitudinal))
        say(f"in phase: leading multiplier across the disks {across} "
            f"({'stable' if sync.transverse_stable else 'not stable'} across them), "
            f"along them {along}")  # fmt: skip
    return orbit


def _number(m: complex) -> str:
    """A multiplier for the terminal: its real part when it is real."""
    return f"{m.real:.4g}" if m.imag == 0 else f"{m:.4g}"


def _equilibrium_from_config(cfg: RunConfig, param: str, start: str, say):
    """The config's system's rest point (``start`` "sliding" or "stall")."""
    from ..bifurcation.orbits import find_equilibrium

    eq = find_equilibrium(cfg.system, start)
    if not eq.converged:
        raise ValueError(
            f"no {start} equilibrium found at {param} = {getattr(cfg.system, param):g} "
            f"(residual {eq.residual:.2g}); change [system] or [continue].start"
        )
    say(f"equilibrium ({eq.kind}): stable {eq.stable}, leading eigenvalue "
        f"{eq.eigenvalues[0]:.4g}")  # fmt: skip
    return eq
