"""Command ``loop``: margins, sensitivities, bandwidth and closed-loop poles of the PID loop.

Two systems, each labelled: the continuous idealisation (ideal PID, no sampling) and the sampled
loop that runs (ZOH plant, the discrete PID with its derivative filter, ``--delay`` samples).

The work is :func:`obsdesign.design.loop.loop_analysis` (python-control); the figure is
:func:`obsdesign.design.loop.loop_figure`. Both are imported only after the arguments parsed.
"""

from __future__ import annotations

import argparse

from .._validate import MAX_DELAY_SAMPLES
from ._common import POSITIVE_ARG, add_config_flags, check_output_file, emit, finite_design, integer, load

__all__ = ["add_commands"]


def _cmd_loop(args: argparse.Namespace) -> int:
    check_output_file("loop", "--plot", args.plot, (".svg", ".png"))
    from ..design.loop import loop_analysis

    cfg = load(args)
    with finite_design(args, ("phi", "tau")):  # review l3, l4, l8: name the flag, as check and pid do
        analysis = loop_analysis(cfg, phi=args.phi, tau=args.tau, delay_samples=args.delay)
    if args.plot:
        from ..design.loop import loop_figure
        from ..report.figures import save_figure

        save_figure(loop_figure(analysis), args.plot)
    emit(args, analysis, analysis.to_dict(), units=cfg.units)
    return 0


def add_commands(sub) -> None:
    """Add ``loop`` to the subparsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``obsdesign`` parser.
    """
    p = sub.add_parser("loop", help="Bode/Nyquist view of L = C H, continuous and sampled: margins, |S|, |T|, "
                                    "|CS|, bandwidth, closed-loop poles")
    add_config_flags(p, default_preset="vcm")
    p.add_argument("--phi", type=POSITIVE_ARG, help="override the plant gain phi [m/(V s)] of eq:linplant (> 0)")
    p.add_argument("--tau", type=POSITIVE_ARG, help="override the plant time constant tau [s] of eq:linplant (> 0)")
    p.add_argument("--delay", type=integer(0, MAX_DELAY_SAMPLES), metavar="N",
                   help="the drive's delay in the sampled loop [samples] (0 to 10000; default hardware.delay_samples)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (continuous: gain_margin_db, phase_margin_deg, crossover_rad_s, max_S, "
                        "max_T, bandwidth_rad_s, closed_loop_poles, ...; the sampled loop under 'sampled')")
    p.add_argument("--plot", metavar="FILE", help="write the loop figure to FILE.svg or FILE.png")
    p.set_defaults(run=_cmd_loop)
