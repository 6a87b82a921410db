"""Commands that write documents and code: ``export`` and ``report``."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..export import CONTROLLER_FORMATS, FMI_VERSIONS
from ..export import FORMATS as EXPORT_FORMATS
from ..export import TARGET_FORMATS
from ..export import TARGETS as EXPORT_TARGETS
from ..export import WHAT as EXPORT_WHAT
from ..params import PARAMETERS, VARIANTS
from ..sampled.choices import CONTROLLERS, ESTIMATORS, SCHEDULES
from ._common import (DESIGN_FLAGS, INPUT_DIR, INPUT_FILE, POSITIVE_ARG, UsageError, add_config_flags,
                      add_design_flags, check_output_dir, check_output_file, load, print_warnings, warn_unstable,
                      workers_arg)
from ._data import add_trace_flags, load_trace_args

__all__ = ["add_commands"]


def _cmd_export(args: argparse.Namespace) -> int:
    from ..export import export

    check_output_dir("export", "-o/--output", args.output)
    if args.what == "controller" and args.format == "latex":
        raise UsageError("obsdesign export: argument --format: the controller is exported as one of "
                         f"{', '.join(CONTROLLER_FORMATS)}, found 'latex'")
    for flag, value in (("--controller", args.controller), ("--stiffness", args.stiffness),
                        ("--estimator", args.estimator), ("--controller-waits", args.controller_waits or None)):
        if value is not None and args.what != "controller":
            raise UsageError(f"obsdesign export: argument {flag}: applies to --what controller only, found {value!r}")
    if args.fmi_version is not None and args.format != "fmu":
        raise UsageError(f"obsdesign export: argument --fmi-version: applies to --format fmu only, found "
                         f"--fmi-version {args.fmi_version} with --format {args.format}")
    if args.target != "host" and (args.what != "controller" or args.format != TARGET_FORMATS[args.target]):
        raise UsageError(f"obsdesign export: argument --target: {args.target} applies to --what controller "
                         f"--format {TARGET_FORMATS[args.target]} only, found --what {args.what} --format {args.format}")
    cfg = load(args).override(dt=args.dt)  # --rho, --kappa, --variant: applied by load, once
    if args.controller_waits and cfg.hardware.delay_samples == 0:
        raise UsageError("obsdesign export: argument --controller-waits: the controller waits [hardware] "
                         "delay_samples samples; expected delay_samples >= 1 in the config, found 0")
    from ._table import table_options  # --what friction-table: its flags, refused with the others

    paths = export(cfg, args.format, args.output, what=args.what, controller=args.controller,
                   schedule=args.stiffness, estimator=args.estimator, table=table_options(args),
                   target=args.target, waits=args.controller_waits, fmi_version=args.fmi_version)
    if args.controller_waits:
        d = cfg.hardware.delay_samples
        print_warnings([f"--controller-waits: the exported controller delays its command by {d} sample"
                        f"{'s' if d > 1 else ''} ([hardware] delay_samples), for a bench WITHOUT the drive's delay; "
                        "hardware that has the delay must not run it (the loop would have twice the delay, "
                        "docs/delay.md)"])
    warn_unstable(cfg, "the exported observer diverges")
    if args.format == "fmu":
        import zipfile

        with zipfile.ZipFile(paths[0]) as archive:
            if not any(name.startswith("binaries/") for name in archive.namelist()):
                print_warnings(["no C compiler found ($CC or cc): the FMU holds the sources only (a source FMU, "
                                "compiled by the importer)"])
    for path in paths:
        print(path)
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from ..report.html import write_report

    out = Path(args.output)
    check_output_file("report", "-o/--output", args.output, None)
    if args.data and (args.position is None or args.input is None):
        raise UsageError("obsdesign report: argument --data: expected --position NAME and --input NAME with it")
    if not args.data and (args.position or args.input or args.time or args.sample_time):
        raise UsageError("obsdesign report: the column flags (--position, --input, --time, --sample-time) "
                         "need --data FILE")
    if args.moving_speed is not None and not args.data:
        raise UsageError(f"obsdesign report: argument --moving-speed: needs --data FILE, found --moving-speed "
                         f"{args.moving_speed:g} without it")
    cfg = load(args)
    trace = load_trace_args(args, args.data) if args.data else None
    label = f"config file {args.config}" if args.config else f"preset {args.preset or args.default_preset}"
    flags = {f"{PARAMETERS[flag]}.{flag}": f"--{flag}" for flag in DESIGN_FLAGS if getattr(args, flag) is not None}
    write_report(cfg, out, source_label=label, progress=not args.quiet, sweep_dir=args.sweep, data=trace,
                 compare_dir=args.compare, paper_studies=args.paper_studies, flags=flags,
                 moving_speed=args.moving_speed, circle=args.circle, workers=args.workers)
    print(args.output)
    return 0


def add_commands(sub) -> None:
    """Add ``export`` and ``report`` to the subparsers ``sub``."""
    p = sub.add_parser("export", help="export the derivation, the designed observer or the whole controller as code")
    p.add_argument("--format", required=True, choices=EXPORT_FORMATS)
    p.add_argument("--what", choices=EXPORT_WHAT, default="observer",
                   help="observer (default), controller: observer, low-pass, PID and compensation of the "
                        "simulator, step(x_ref, x_meas) -> command [V]; friction-table: the feed-forward model as "
                        "a velocity -> force (current) table, CSV and C array (--format c)")
    p.add_argument("--controller", choices=[name for name in CONTROLLERS.names() if name != "open-loop"],
                   help="with --what controller: the simulator's controller to generate (default pid+observer)")
    p.add_argument("--stiffness", choices=[name for name in SCHEDULES.names() if name != "true"],
                   help="with --what controller: the observer's stiffness schedule, as in simulate (default "
                        "estimated, with the reversal hysteresis; 'true' needs the simulated plant)")
    p.add_argument("--estimator", choices=ESTIMATORS.names(),
                   help="with --what controller: the estimator, as in simulate (default paper; the baselines "
                        "tuned by the fair noise rule)")
    p.add_argument("--target", choices=EXPORT_TARGETS, default="host",
                   help="with --what controller: host (double, bit-exact with simulate; default), cortex-m4f "
                        "(--format c: float32, encoder counts of sensor.quantization, fixed cost a sample; "
                        "docs/on-the-drive.md) or real (--format st: the same float32 arithmetic in REAL; "
                        "docs/plc-export.md)")
    p.add_argument("--controller-waits", action="store_true",
                   help="with --what controller: the controller that waits, for a bench WITHOUT the drive's delay: "
                        "it returns its command of [hardware] delay_samples samples earlier, so the bench runs the "
                        "loop simulate runs with the delay (hardware with the delay must not use it; docs/delay.md)")
    p.add_argument("--fmi-version", choices=FMI_VERSIONS,
                   help="with --format fmu: the FMI version of the co-simulation FMU, 2 (FMI 2.0, default) or 3 "
                        "(FMI 3.0); the same controller C (docs/fmu-export.md)")
    add_config_flags(p, default_preset="vcm")
    p.add_argument("--variant", choices=VARIANTS, help="override the config's model variant")
    p.add_argument("--rho", type=POSITIVE_ARG, help="gain parameter rho (> 0)")
    p.add_argument("--dt", type=POSITIVE_ARG, help="sample time [s] of the discrete observer")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    from ._table import add_table_flags

    add_table_flags(p)
    p.set_defaults(run=_cmd_export)

    p = sub.add_parser("report", help="self-contained HTML design report")
    add_config_flags(p, default_preset="vcm")
    p.add_argument("-o", "--output", default="report.html", metavar="FILE", help="output file (default report.html)")
    p.add_argument("--sweep", metavar="DIR", type=INPUT_DIR, help="add the summary of an 'obsdesign sweep' folder")
    p.add_argument("--compare", metavar="DIR", type=INPUT_DIR, help="add the results of an 'obsdesign compare' folder")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--data", metavar="FILE", type=INPUT_FILE, help="add 'Validation on measured data' for a record (.csv or .mat)")
    add_trace_flags(p, required=False)
    p.add_argument("--moving-speed", type=POSITIVE_ARG, metavar="V",
                   help="--data: speed [m/s, rad/s] above which the axis counts as moving in the friction check "
                        "(default 5 %% of the record's peak speed; standstill is reported separately)")
    p.add_argument("--paper-studies", action=argparse.BooleanOptionalAction, default=None,
                   help="add the paper's reproduction studies and claims (default: for the paper's presets only)")
    p.add_argument("--circle", action=argparse.BooleanOptionalAction, default=True,
                   help="add the circle (ballbar) test of the compensation modes on this axis (default: yes; "
                        "--no-circle saves its few seconds)")
    p.add_argument("--workers", type=workers_arg,
                   help="processes (default: all cores; 2 or more run the Table 1 study and the circle test in a "
                        "helper process beside this one; 1: all here). The report is the same either way")
    add_design_flags(p, json_flag=None)
    p.set_defaults(run=_cmd_report)
