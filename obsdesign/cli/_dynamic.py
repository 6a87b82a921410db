"""``identify --refine`` (dynamic friction by output error) and ``experiment`` (an identification experiment)."""

from __future__ import annotations

import argparse

from ._common import POSITIVE_ARG, UsageError, add_encoder_flags, check_output_file, emit, encoder_resolution, integer

__all__ = ["add_refine_flags", "refine_from_args", "add_commands"]


def add_refine_flags(p: argparse.ArgumentParser) -> None:
    """``--refine NAMES`` and ``--refine-model MODEL`` of ``identify``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The ``identify`` parser.
    """
    p.add_argument("--refine", metavar="NAMES",
                   help="refine these parameters by output error, comma-separated; e.g. 's' or 's,delay' (paper), "
                        "'sigma0' or 'sigma0,sigma1' with --refine-model lugre (a segment fit that also refits m, "
                        "sigma, Cf, offset and profiles each bristle parameter asked for)")
    p.add_argument("--refine-model", default="paper", metavar="MODEL",  # checked when used: no NumPy in the parser
                   help="plant friction model of the refinement: paper, lugre or gms (default: paper)")
    p.add_argument("--segment", type=POSITIVE_ARG, metavar="SECONDS",
                   help="segment length of the lugre refinement [s], at least 20 samples (default 0.1)")
    p.add_argument("--time-budget", type=POSITIVE_ARG, metavar="SECONDS",
                   help="stop the refinement after this long: lugre with the best fit so far (and says so), "
                        "paper/gms with a one-line reason")


def refine_from_args(args: argparse.Namespace, trace, ident):
    """``(ident, payload)``: ``ident`` with a refined ``s`` and the refinement's JSON (``None`` without ``--refine``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``identify`` arguments.
    trace : Trace
        The record.
    ident : Identification
        Its static fit.
    """
    if args.refine is None:
        for flag, value in (("--segment", args.segment), ("--time-budget", args.time_budget)):
            if value is not None:
                raise UsageError(f"obsdesign {args.command}: argument {flag}: only with --refine")
        return ident, None
    from ..data.output_error import MODELS, refinable, refine

    if args.refine_model not in MODELS:
        raise UsageError(f"obsdesign {args.command}: argument --refine-model: expected one of {', '.join(MODELS)}, "
                         f"found {args.refine_model!r}")
    names = tuple(n.strip() for n in args.refine.split(","))
    allowed = refinable(args.refine_model)
    if not all(names) or len(set(names)) != len(names) or any(n not in allowed for n in names):
        raise UsageError(f"obsdesign {args.command}: argument --refine: expected distinct names of "
                         f"{','.join(allowed)} separated by commas, found {args.refine!r}")
    if args.refine_model != "lugre" and args.segment is not None:
        raise UsageError(f"obsdesign {args.command}: argument --segment: only with --refine-model lugre, found "
                         f"--refine-model {args.refine_model}")
    import sys

    from ..data.output_error import SEGMENT, RefineFailed

    if args.refine_model == "lugre" and ident.model != "coulomb-viscous":
        raise UsageError(f"obsdesign {args.command}: argument --refine-model: lugre's segment fit is symmetric; "
                         f"expected the symmetric identification, found --asymmetric")
    segment = SEGMENT if args.segment is None else args.segment
    if args.refine_model == "lugre" and segment / trace.sample_time < 20:
        raise UsageError(f"obsdesign {args.command}: argument --segment: expected at least 20 samples "
                         f"({20 * trace.sample_time:g} s), found {args.segment:g}")
    try:
        result = refine(trace, ident, parameters=names, model=args.refine_model, segment=segment,
                        time_budget=args.time_budget, progress=True)
    except RefineFailed as e:
        print(f"obsdesign {args.command}: --refine {args.refine}: could not be identified: {e}", file=sys.stderr)
        raise SystemExit(1) from None
    if not args.json:
        print(result)
    return result.apply(ident), result.to_dict()


def _cmd_experiment(args: argparse.Namespace) -> int:
    from ..data.experiment import design_experiment
    from ..export.literals import check_identifier

    check_output_file("experiment", "--csv", args.csv, (".csv",))
    check_output_file("experiment", "--c", args.c, (".c", ".h"))
    try:
        check_identifier("--name", args.name)
    except ValueError as e:
        raise UsageError(f"obsdesign experiment: argument {e}") from None
    try:
        rotary = args.rotary or args.counts_per_rev is not None
        exp = design_experiment(stroke=args.stroke, speed=args.speed, force=args.force, mass=args.mass, dt=args.dt,
                                travel=args.travel, resolution=encoder_resolution(args), levels=args.levels,
                                blocks=args.blocks, dwell=args.dwell, ramp=args.ramp, rotary=rotary,
                                stribeck_speed=args.stribeck_speed)
    except ValueError as e:  # the API names its parameter: the flag of the same name
        name, _, rest = str(e).partition(": ")
        if name == "resolution" and args.counts_per_rev is not None:  # the count's size from N: say it in counts
            name, rest = "counts_per_rev", (f"expected more than 2 pi / travel = {6.283185307179586 / args.travel:.6g} "
                                            f"counts (one count below --travel {args.travel:g} rad), found "
                                            f"{args.counts_per_rev}")
        raise UsageError(f"obsdesign experiment: argument --{name.replace('_', '-')}: {rest}") from None
    if args.csv:
        exp.to_csv(args.csv)
    if args.c:
        exp.to_c(args.c, args.name)
    emit(args, exp, exp.to_dict())
    return 0


def add_commands(sub) -> None:
    """Add ``experiment`` to the subparsers ``sub``.

    Parameters
    ----------
    sub : argparse subparsers
        The subcommands of ``obsdesign``.
    """
    p = sub.add_parser("experiment", help="write a reference trajectory that makes the friction identifiable")
    p.add_argument("--rotary", action="store_true",
                   help="a rotary axis: every value below in rad, rad/s, N m, kg m^2 (--counts-per-rev implies it)")
    p.add_argument("--stroke", type=POSITIVE_ARG, required=True, metavar="M", help="usable travel [m, rad]")
    p.add_argument("--speed", type=POSITIVE_ARG, required=True, metavar="V", help="largest speed [m/s, rad/s]")
    p.add_argument("--force", type=POSITIVE_ARG, required=True, metavar="F",
                   help="actuator force limit [N] (torque limit [N m] with --rotary)")
    p.add_argument("--mass", type=POSITIVE_ARG, required=True, metavar="KG",
                   help="rough moving mass [kg] (inertia [kg m^2] with --rotary)")
    p.add_argument("--dt", type=POSITIVE_ARG, required=True, metavar="DT", help="sample time [s]")
    p.add_argument("--travel", type=POSITIVE_ARG, default=1e-3, metavar="M",
                   help="largest expected pre-sliding travel 1/s [m, rad] (default 1e-3)")
    add_encoder_flags(p, "encoder resolution [m, rad]", "encoder counts per revolution, 1 to 2^40 (resolution 2 pi / N "
                      "rad; a rotary axis)")
    p.add_argument("--stribeck-speed", type=POSITIVE_ARG, nargs=2, metavar=("LO", "HI"),
                   help="range of the expected Stribeck speed vs [m/s, rad/s]: the staircase covers LO/3 to 3 HI "
                        "and the plan says whether Fs and vs are identifiable")
    p.add_argument("--levels", type=integer(2), default=6, metavar="N", help="speed levels (2 to 20, default 6)")
    p.add_argument("--blocks", type=integer(1), default=5, metavar="N",
                   help="pre-sliding blocks of 5 dwelling reversals (default 5)")
    p.add_argument("--dwell", type=POSITIVE_ARG, default=0.1, metavar="S", help="dwell after each reversal [s]")
    p.add_argument("--ramp", type=POSITIVE_ARG, default=0.05, metavar="S", help="shortest speed ramp [s]")
    p.add_argument("--csv", metavar="FILE.csv", help="write t, x_ref, v_ref")
    p.add_argument("--c", metavar="FILE.c", help="write the position reference as a C array")
    p.add_argument("--name", default="obsdesign_experiment", metavar="IDENT", help="name of the C array")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=_cmd_experiment, resolution=0.0)
