"""Commands that write documents and code: ``export`` and ``report``."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..export import FORMATS as EXPORT_FORMATS
from ..params import VARIANTS
from ._common import POSITIVE_ARG, UsageError, add_config_flags, load

__all__ = ["add_commands"]


def _cmd_export(args: argparse.Namespace) -> int:
    from ..export import export

    paths = export(load(args), args.format, args.output, variant=args.variant, rho=args.rho, dt=args.dt)
    for path in paths:
        print(path)
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from ..report.html import write_report

    out = Path(args.output)
    if not out.parent.is_dir():
        raise UsageError(f"obsdesign report: argument -o/--output: directory {str(out.parent)!r} does not exist")
    cfg = load(args)
    label = f"config file {args.config}" if args.config else f"preset {cfg.name}"
    write_report(cfg, out, source_label=label, progress=not args.quiet, sweep_dir=args.sweep,
                 compare_dir=args.compare)
    print(args.output)
    return 0


def add_commands(sub) -> None:
    """Add ``export`` and ``report`` to the subparsers ``sub``."""
    p = sub.add_parser("export", help="export the derivation or the designed observer as code")
    p.add_argument("--format", required=True, choices=EXPORT_FORMATS)
    add_config_flags(p, default_preset="vcm")
    p.add_argument("--variant", choices=VARIANTS, help="override the config's model variant")
    p.add_argument("--rho", type=POSITIVE_ARG, help="gain parameter rho (> 0)")
    p.add_argument("--dt", type=POSITIVE_ARG, help="sample time [s] of the discrete observer")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    p.set_defaults(run=_cmd_export)

    p = sub.add_parser("report", help="self-contained HTML design report")
    add_config_flags(p, default_preset="vcm")
    p.add_argument("-o", "--output", default="report.html", metavar="FILE", help="output file (default report.html)")
    p.add_argument("--sweep", metavar="DIR", help="add the summary of an 'obsdesign sweep' folder")
    p.add_argument("--compare", metavar="DIR", help="add the results of an 'obsdesign compare' folder")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(run=_cmd_report)
