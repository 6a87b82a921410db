"""Commands on the design: ``derive``, ``check``, ``pid``, ``noise``."""

from __future__ import annotations

import argparse
import json
import sys

from .._validate import MAX_DELAY_SAMPLES
from ..params import PID_DESIGNS, VARIANTS
from ._common import (NONNEGATIVE_ARG, PHASE_ARG, POSITIVE_ARG, add_config_flags, add_design_flags, emit,
                      finite_design, integer, load, warn_unstable)

__all__ = ["add_commands"]


def _cmd_derive(args: argparse.Namespace) -> int:
    from ..symbolic import derive
    from ..symbolic.printing import derivation_json, derivation_latex, derivation_text

    d = derive(args.variant)
    if args.format == "json":
        print(json.dumps(derivation_json(d)))
    elif args.format == "latex":
        print(derivation_latex(d, standalone=True), end="")
    else:
        print(derivation_text(d), end="")
    return 0


def _cmd_check(args: argparse.Namespace) -> int:
    import warnings

    from .._memo import MemoWarning
    from ..design import check_stability

    cfg = load(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # reported in the output instead
        warnings.simplefilter("default", MemoWarning)  # a refused memo entry is still said
        with finite_design(args, ("rho", "kappa")):
            report = check_stability(cfg)
    loops, why = _loop_margins(cfg)  # information beside the verdicts: the exit status is the observer's
    doc = report.to_dict()
    doc["loop_margins"] = loops.to_dict() if loops is not None else {"error": why}
    emit(args, report, doc, units=cfg.units)
    if not args.json:
        print()
        print(loops.text(cfg.units) if loops is not None else f"loop margins: not computed: {why}")
        for note in report.warnings:
            print(f"warning: {note}")
    return 0 if report.all_hold else 1


def _loop_margins(cfg):
    """The PID loop's margins around the design model and the simulated plant, or why not (a PID without a
    design meeting its target is the PID's problem, not the observer's: ``check`` still gives its verdicts)."""
    from ..design.plant_loop import loop_margins_of

    try:
        return loop_margins_of(cfg), ""
    except ValueError as exc:
        return None, str(exc)


def _cmd_pid(args: argparse.Namespace) -> int:
    from ..design.pid_report import pid_designs

    cfg = load(args)
    with finite_design(args, ("phi", "tau", "max_s", "phase_margin")):
        phi = args.phi if args.phi is not None else (None if args.tau is None else cfg.plant.K * args.tau / cfg.plant.m)
        cfg = cfg.override(phi=phi, tau=args.tau, max_S=args.max_s, phase_margin_deg=args.phase_margin,
                           design=args.design, delay_samples=args.delay)
        designs = pid_designs(cfg)
    emit(args, designs, designs.to_dict(), units=cfg.units)
    return 0


def _cmd_noise(args: argparse.Namespace) -> int:
    from ..design import noise_analysis

    cfg = load(args)
    with finite_design(args, ("rho", "kappa", "noise_rms", "noise_bandwidth", "stiffness")):
        na = noise_analysis(cfg, noise_rms=args.noise_rms, noise_bandwidth=args.noise_bandwidth,
                            stiffness=args.stiffness)
        warn_unstable(cfg, "the noise variance of an unstable observer is unbounded, the values are not meaningful")
    emit(args, na, na.to_dict(), units=cfg.units)
    return 0


def add_commands(sub) -> None:
    """Add the design commands to the subparsers ``sub``."""
    p = sub.add_parser("derive", help="symbolic derivation of the observer")
    p.add_argument("--variant", choices=VARIANTS, default="lag", help="model variant (default: lag)")
    p.add_argument("--format", choices=("text", "latex", "json"), default="text")
    p.set_defaults(run=_cmd_derive)

    p = sub.add_parser("check", help="stability verdicts of an observer design (exit 1 if one fails)")
    add_config_flags(p, default_preset="table1")
    add_design_flags(p)
    p.set_defaults(run=_cmd_check)

    p = sub.add_parser("pid", help="sensitivity-based PID design (section 4.1)")
    add_config_flags(p, default_preset="vcm")
    p.add_argument("--phi", type=POSITIVE_ARG, help="plant gain phi [m/(V s)] (default: K tau / m)")
    p.add_argument("--tau", type=POSITIVE_ARG, help="plant time constant tau [s]")
    p.add_argument("--max-s", type=POSITIVE_ARG, help="bound of |S| [m/V]; k = 1/max|S|")
    p.add_argument("--phase-margin", type=PHASE_ARG, help="phase margin [deg], in (0, 90)")
    p.add_argument("--design", choices=PID_DESIGNS,
                   help="which PID the config carries (default: [pid] design, itself default auto)")
    p.add_argument("--delay", type=integer(0, MAX_DELAY_SAMPLES), metavar="N",
                   help="the drive's delay in the sampled loop [samples] (0 to 10000; default hardware.delay_samples)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=_cmd_pid)

    p = sub.add_parser("noise", help="measurement noise in the friction estimate (section 3.4)")
    add_config_flags(p, default_preset="vcm")
    add_design_flags(p)
    p.add_argument("--noise-rms", type=NONNEGATIVE_ARG, help="noise RMS [m] (>= 0)")
    p.add_argument("--noise-bandwidth", type=POSITIVE_ARG, help="noise bandwidth [Hz] (> 0)")
    p.add_argument("--stiffness", type=NONNEGATIVE_ARG, default=0.0, help="constant stiffness k [N/m] (default 0)")
    p.set_defaults(run=_cmd_noise)
