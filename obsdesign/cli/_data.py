"""Commands on measured data: ``identify`` and ``observe`` (and the trace flags of ``report --data``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..params import preset_names
from ..sampled.choices import SCHEDULES
from ._dynamic import add_refine_flags, refine_from_args
from ._common import FINITE_ARG, INPUT_FILE, POSITIVE_ARG, UsageError, check_output_file, emit

__all__ = ["add_commands", "add_trace_flags", "load_trace_args"]


def add_trace_flags(p: argparse.ArgumentParser, *, required: bool = True) -> None:
    """``--position NAME --input NAME [--time NAME] [--sample-time DT] [--input-gain G]``."""
    p.add_argument("--position", required=required, metavar="NAME", help="column or variable of the displacement [m]")
    p.add_argument("--input", required=required, metavar="NAME",
                   help="column or variable of the actuator input (times --input-gain gives N)")
    p.add_argument("--time", metavar="NAME", help="column or variable of the time [s]")
    p.add_argument("--sample-time", type=POSITIVE_ARG, metavar="DT", help="sample time [s] (without a time column)")
    p.add_argument("--input-gain", type=FINITE_ARG, default=1.0, metavar="G",
                   help="force per unit of the logged input [N/unit], nonzero (default 1: logged in N)")


def load_trace_args(args: argparse.Namespace, path: str):
    """The trace of ``path`` with the column flags of :func:`add_trace_flags`."""
    from ..data import load_trace
    from ..data.trace import check_sample_time

    if args.time is None and args.sample_time is None:
        raise UsageError(f"obsdesign {args.command}: expected --time NAME or --sample-time DT for the time base "
                         f"of {path!r}, found neither")
    if args.sample_time is not None:
        try:
            check_sample_time("--sample-time", args.sample_time, "the flag")
        except ValueError as e:
            raise UsageError(f"obsdesign {args.command}: argument {e}") from None
    return load_trace(path, position=args.position, input=args.input, time=args.time,
                      sample_time=args.sample_time, input_gain=args.input_gain)


def _load_config(args: argparse.Namespace):
    from ..params import load_config, load_preset

    return load_config(args.config) if args.config else load_preset(args.preset)


def _cmd_identify(args: argparse.Namespace) -> int:
    from ..data import identify

    check_output_file("identify", "-o/--output", args.output, (".toml",))
    trace = load_trace_args(args, args.data)
    ident = identify(trace, model="asymmetric" if args.asymmetric else "coulomb-viscous")
    ident, refined = refine_from_args(args, trace, ident)
    if args.output:
        stem = Path(args.data).stem
        name = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in stem) or "identified"
        ident.to_config(name=name).save(args.output)
    emit(args, ident, dict(ident.to_dict(), **({"refinement": refined} if refined else {})))
    return 0


def _cmd_observe(args: argparse.Namespace) -> int:
    from ..data import observe

    check_output_file("observe", "--out", args.out, (".csv", ".npz"))
    check_output_file("observe", "--plot", args.plot, (".svg", ".png"))
    cfg = _load_config(args)
    trace = load_trace_args(args, args.data)
    if abs(cfg.observer.dt - trace.sample_time) > 1e-6 * trace.sample_time:
        raise UsageError(
            f"obsdesign observe: the config's observer.dt = {cfg.observer.dt:.9g} s differs from the trace's sample "
            f"time {trace.sample_time:.9g} s; the trace's sample time wins (the observer runs at the rate the data "
            f"were sampled): set dt = {trace.sample_time:.9g} in the [observer] table of the config, or build one "
            f"with 'obsdesign identify DATA ... -o FILE.toml'")
    obs = observe(cfg, trace, stiffness=args.stiffness)
    if args.out:
        (obs.to_npz if args.out.lower().endswith(".npz") else obs.to_csv)(args.out)
    if args.plot:
        from ..report.data_section import observation_figure
        from ..report.figures import save_figure

        save_figure(observation_figure(obs), args.plot)
    emit(args, obs, obs.summary())
    return 0


def add_commands(sub) -> None:
    """Add ``identify`` and ``observe`` to the subparsers ``sub``."""
    p = sub.add_parser("identify", help="identify mass, viscous and Coulomb friction and offset from a record")
    p.add_argument("data", metavar="DATA", type=INPUT_FILE, help="measured record (.csv with a header row, or .mat)")
    add_trace_flags(p)
    p.add_argument("--asymmetric", action="store_true", help="separate viscous and Coulomb terms per direction")
    add_refine_flags(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("-o", "--output", metavar="FILE.toml", help="write the identified design config")
    p.set_defaults(run=_cmd_identify)

    p = sub.add_parser("observe", help="run the designed observer over a measured record")
    p.add_argument("data", metavar="DATA", type=INPUT_FILE, help="measured record (.csv with a header row, or .mat)")
    group = p.add_mutually_exclusive_group(required=True)
    group.add_argument("--preset", choices=preset_names(), help="shipped preset")
    group.add_argument("--config", metavar="FILE", help="TOML config file (e.g. from 'obsdesign identify -o')")
    add_trace_flags(p)
    p.add_argument("--stiffness", choices=SCHEDULES.names(), default="estimated",
                   help="observer stiffness schedule (default: estimated)")
    p.add_argument("--out", metavar="FILE", help="write the estimates to FILE.csv or FILE.npz")
    p.add_argument("--plot", metavar="FILE", help="write a figure to FILE.svg or FILE.png")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.set_defaults(run=_cmd_observe)
