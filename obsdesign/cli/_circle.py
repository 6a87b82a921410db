"""``obsdesign simulate circle``: the two-axis circle (ballbar) test (:mod:`obsdesign.sim.circle`)."""

from __future__ import annotations

import argparse

from .._validate import parse_number, POSITIVE
from ._common import NONNEGATIVE_ARG, POSITIVE_ARG, UsageError, emit, integer, load

__all__ = ["add_circle_flags", "cmd_circle"]


def _feeds(text: str) -> tuple[float, ...]:
    """``--feed 2e-3,6.3e-3,2e-2``: path velocities [m/s]."""
    try:
        return tuple(parse_number(p, "--feed", POSITIVE, "m/s") for p in text.split(","))
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _modes(text: str) -> tuple[str, ...]:
    """``--modes pid,observer``: at least one mode, each once."""
    modes = tuple(p.strip() for p in text.split(",") if p.strip())
    if not modes or len(set(modes)) != len(modes):
        raise argparse.ArgumentTypeError(f"expected a comma list of distinct modes (pid and the compensation modes), "
                                         f"found {text!r}")
    return modes


def add_circle_flags(p) -> None:
    """The flags of ``simulate circle`` (ignored by the other scenarios)."""
    g = p.add_argument_group("circle (simulate circle)")
    g.add_argument("--radius", type=POSITIVE_ARG, default=5e-3, help="circle radius [m] (default 5e-3)")
    g.add_argument("--feed", type=_feeds, default=(1e-2,), help="path velocity [m/s], or a comma list (default 1e-2)")
    g.add_argument("--direction", choices=("ccw", "cw", "both"), default="ccw", help="direction (default ccw)")
    g.add_argument("--modes", type=_modes, help="compare: comma list of pid and the compensation modes "
                                                 "(observer, feedforward, blend); default the config's mode")
    g.add_argument("--revolutions", type=integer(1, 1000), default=1, help="evaluated revolutions, at most 1000 "
                                                                         "(default 1)")
    g.add_argument("--lookahead", type=integer(0), help="feed-forward ramp before a reversal [samples] "
                                                        "([compensation] lookahead)")
    g.add_argument("--buildup", type=NONNEGATIVE_ARG, help="feed-forward build-up distance [m] ([compensation] buildup)")
    g.add_argument("--ff-presliding", choices=("on", "off"),
                   help="feed-forward Coulomb term on the pre-sliding curve of [friction] s (on, the default) or "
                        "switched at the reversal like a drive's velocity table (off) ([compensation] ff_presliding)")


def cmd_circle(args: argparse.Namespace) -> int:
    """Run the circle test and print one row per mode, feed and direction (``--json``: the rows)."""
    from ..sim.circle import circle_modes

    if args.out is not None:  # the circle has no single trace to write
        raise UsageError("obsdesign simulate circle: argument --out: not with circle (its rows: --json; its "
                         "picture: --plot)")
    if args.config is None and args.preset is None:
        args.preset = "vcm"
    cfg = load(args).override(noise_rms=args.noise_rms, noise_bandwidth=args.noise_bandwidth,
                              quantization=args.quantization, dt=args.dt,
                              lookahead=args.lookahead, buildup=args.buildup,
                              ff_presliding=None if args.ff_presliding is None else args.ff_presliding == "on")
    modes = args.modes
    if modes is None:
        modes = ("pid",) if args.controller == "pid" else (cfg.compensation.mode,)
    elif args.controller is not None:
        raise UsageError("obsdesign simulate circle: argument --controller: not with --modes (pid is a mode there)")
    directions = ("ccw", "cw") if args.direction == "both" else (args.direction,)
    rows = circle_modes(cfg, modes=modes, feeds=args.feed, directions=directions, seeds=(args.seed,),
                        radius=args.radius, revolutions=args.revolutions, stiffness=args.stiffness,
                        estimator=args.estimator)
    if args.plot:  # the ballbar picture of the first feed and direction, one panel per mode
        from ..report.circle_section import save_ballbar_figure
        from ..sim.circle import simulate_circle

        panels = {}
        for mode in modes:
            c = cfg if mode == "pid" else cfg.override(mode=mode)
            panels[mode] = simulate_circle(c, radius=args.radius, feed=args.feed[0], direction=directions[0],
                                           controller="pid" if mode == "pid" else "pid+observer", seed=args.seed,
                                           revolutions=args.revolutions, stiffness=args.stiffness,
                                           estimator=args.estimator, keep_trace=True)
        save_ballbar_figure(panels, args.plot)
    lines = [f"circle radius {args.radius:g} m, {cfg.name}: glitch peak / circularity / radial RMS [um]"]
    for r in rows:
        lines.append(f"  {r['mode']:12s} feed {r['feed']:g} m/s {r['direction']:3s}  {r['glitch_peak'] * 1e6:9.3f} "
                     f"{r['circularity'] * 1e6:9.3f} {r['radial_rms'] * 1e6:9.3f}")
    emit(args, "\n".join(lines), {"radius": args.radius, "rows": rows})
    return 0
