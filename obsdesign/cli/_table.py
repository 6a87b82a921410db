"""The flags of ``obsdesign export --what friction-table`` (:mod:`obsdesign.export.friction_table`)."""

from __future__ import annotations

import argparse

from .._validate import FINITE, MOTOR_CONSTANT, V_MAX, parse_number
from ._common import UsageError, integer, number

__all__ = ["add_table_flags", "table_options"]


def _velocities(text: str) -> tuple[float, ...]:
    try:
        return tuple(parse_number(p, "--velocities", FINITE, "m/s") for p in text.split(","))
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def add_table_flags(p) -> None:
    """Add the table's flags to the ``export`` parser ``p``."""
    g = p.add_argument_group("friction table (--what friction-table)")
    g.add_argument("--points", type=integer(2, 1000), help="breakpoints, placed to bound the interpolation error "
                                                           "(2 to 1000, default 20)")
    g.add_argument("--velocities", type=_velocities, help="the breakpoints [m/s] instead, a comma list from 0")
    g.add_argument("--v-max", type=number(V_MAX, " m/s"), help="largest velocity [m/s], at most 1e3 (default the "
                                                             "axis's)")
    g.add_argument("--motor-constant", type=number(MOTOR_CONSTANT, " N/A"), help="force per current [N/A], 1e-6 to "
                                                                             "1e6: adds the current column")


def table_options(args: argparse.Namespace) -> dict | None:
    """The options of :func:`~obsdesign.export.friction_table.friction_table` (None for another ``--what``)."""
    given = {"points": args.points, "velocities": args.velocities, "v_max": args.v_max,
             "motor_constant": args.motor_constant}
    if args.what != "friction-table":
        flag = next((k for k, v in given.items() if v is not None), None)
        if flag is not None:
            raise UsageError(f"obsdesign export: argument --{flag.replace('_', '-')}: applies to --what "
                             f"friction-table only")
        return None
    if args.points is not None and args.velocities is not None:
        raise UsageError("obsdesign export: argument --points: not with --velocities")
    return {k: v for k, v in given.items() if v is not None}
