"""Commands on measured data: ``channels``, ``identify`` and ``observe`` (and the trace flags of ``report --data``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._validate import MAX_BOOTSTRAP
from ..params import preset_names
from ..sampled.choices import SCHEDULES
from ._dynamic import add_refine_flags, refine_from_args
from ._common import (FINITE_ARG, INPUT_FILE, POSITIVE_ARG, UsageError, add_encoder_flags, check_output_file, emit,
                      encoder_resolution, integer, print_warnings)

__all__ = ["add_commands", "add_trace_flags", "load_trace_args"]


def _unit(role: str):
    """An argparse type: a unit pint parses whose dimension fits the ``role`` column."""
    def parse(text: str) -> str:
        from ..data.units import parse_unit

        try:
            parse_unit("unit", text, role)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e).partition(": ")[2]) from None
        return text

    return parse


def _delimiter(text: str) -> str:
    from ..data.csvfile import DELIMITERS

    if text not in DELIMITERS:
        raise argparse.ArgumentTypeError(f"expected one of ',', ';', tab, space, '|', found {text!r}")
    return text


#: load_trace's parameters and the flags that set them: its messages name the flag on the command line.
_FLAGS = {"time_unit": "--time-unit", "position_unit": "--position-unit", "input_unit": "--input-unit",
          "rated": "--rated", "resolution": "--resolution", "rotary": "--rotary", "delimiter": "--delimiter",
          "decimal": "--decimal"}


def add_trace_flags(p: argparse.ArgumentParser, *, required: bool = True) -> None:
    """``--position NAME --input NAME [--time NAME] [--sample-time DT] [--input-gain G]`` and the unit flags."""
    p.add_argument("--position", required=required, metavar="NAME",
                   help="column, variable or channel of the displacement (group/channel where the format has groups)")
    p.add_argument("--input", required=required, metavar="NAME",
                   help="column, variable or channel of the actuator input (times --input-gain gives N or N m)")
    p.add_argument("--time", metavar="NAME",
                   help="column or channel of the time (default: the file's own time base, where it has one)")
    p.add_argument("--sample-time", type=POSITIVE_ARG, metavar="DT", help="sample time [s] (without a time column)")
    p.add_argument("--input-gain", type=FINITE_ARG, default=1.0, metavar="G",
                   help="force (torque) per SI unit of the input [N/A, N/V, N m/A], nonzero (default 1)")
    p.add_argument("--time-unit", type=_unit("time"), metavar="UNIT",
                   help="unit of the time column: s, ms, us, ... (default: the file's, else s)")
    p.add_argument("--position-unit", type=_unit("position"), metavar="UNIT",
                   help="unit of the position: a length (m, mm, um, inch), an angle (rad, deg, rev: a rotary axis) "
                        "or counts with --resolution (default: the file's, else m)")
    p.add_argument("--input-unit", type=_unit("input"), metavar="UNIT",
                   help="unit of the input: a current (A, mA), voltage (V), force (N) or torque ('N m', Nm: a rotary "
                        "axis), or %% of --rated (default: the file's, else N with gain 1, else V)")
    p.add_argument("--rated", nargs=2, metavar=("VALUE", "UNIT"),
                   help="the rated current or torque an input in %% is a fraction of (e.g. --rated 2.5 A)")
    add_encoder_flags(p, "size of one encoder count [m, or rad with --rotary] (with a position in counts)",
                      "encoder counts per revolution of a rotary axis, 1 to 2^40: --resolution 2 pi / N rad, "
                      "--rotary and, unless given, --position-unit counts")
    p.add_argument("--rotary", action="store_true",
                   help="a rotary axis with the position in counts (an angle or a torque implies it)")
    p.add_argument("--delimiter", type=_delimiter, metavar="D",
                   help="CSV delimiter: ',', ';', tab, space or '|' (default: detected)")
    p.add_argument("--decimal", choices=(".", ","), help="CSV decimal mark (default: detected)")


def load_trace_args(args: argparse.Namespace, path: str):
    """The trace of ``path`` with the column flags of :func:`add_trace_flags`."""
    from ..data import load_trace
    from ..data.logfile import MissingExtra
    from ..data.trace import check_sample_time

    if args.sample_time is not None:
        try:
            check_sample_time("--sample-time", args.sample_time, "the flag")
        except ValueError as e:
            raise UsageError(f"obsdesign {args.command}: argument {e}") from None
    per_rev = args.counts_per_rev is not None  # a rotary encoder in counts
    if per_rev and args.position_unit is not None:
        from ..data.units import unit_kind

        if unit_kind(args.position_unit, "position") != "count":
            raise UsageError(f"obsdesign {args.command}: argument --counts-per-rev: expected a position in counts "
                             f"(--position-unit counts, the default with this flag), found --position-unit "
                             f"{args.position_unit!r}")
    try:
        return load_trace(path, position=args.position, input=args.input, time=args.time,
                          sample_time=args.sample_time, input_gain=args.input_gain, time_unit=args.time_unit,
                          position_unit=args.position_unit or ("counts" if per_rev else None),
                          input_unit=args.input_unit, resolution=encoder_resolution(args),
                          rotary=args.rotary or per_rev, rated=None if args.rated is None else " ".join(args.rated),
                          delimiter=args.delimiter, decimal=args.decimal)
    except MissingExtra as e:
        raise UsageError(f"obsdesign {args.command}: {e}") from None
    except ValueError as e:
        param, _, rest = str(e).partition(": ")
        if per_rev and param in ("resolution", "rotary", "position_unit"):
            raise UsageError(f"obsdesign {args.command}: argument --counts-per-rev: {rest}") from None
        if param in _FLAGS:
            raise UsageError(f"obsdesign {args.command}: argument {_FLAGS[param]}: {rest}") from None
        if param == "time, sample_time" and args.time is None and args.sample_time is None:
            raise UsageError(f"obsdesign {args.command}: expected --time NAME or --sample-time DT for the time base "
                             f"of {path!r}, found neither (the file gives none of its own)") from None
        raise


def _cmd_channels(args: argparse.Namespace) -> int:
    from ..data.logfile import MissingExtra, read_log

    try:
        log = read_log(args.data, delimiter=args.delimiter, decimal=args.decimal)
    except MissingExtra as e:
        raise UsageError(f"obsdesign channels: {e}") from None
    rows = log.rows()
    payload = {"file": log.name, "format": log.format, "metadata": dict(log.metadata),
               "channels": [{"name": n, "unit": u, "length": k, "rate": r} for n, u, k, r in rows]}
    head = ("name", "unit", "length", "rate")
    table = [head] + [(n, u, str(k), r) for n, u, k, r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(4)]
    lines = [f"{log.name}: {log.format}, {len(rows)} {log.kind}s"]
    lines += [f"  {key}: {value}" for key, value in log.metadata.items()]
    lines += ["  " + "  ".join(cell.ljust(w) if i < 2 else cell.rjust(w) for i, (cell, w) in
                                enumerate(zip(row, widths))).rstrip() for row in table]
    emit(args, "\n".join(lines), payload)
    return 0


def _pairs(args: argparse.Namespace, flag: str, items, parse) -> dict:
    """``NAME=VALUE`` items of a repeated flag, parsed by ``parse`` (refused in one line naming the flag)."""
    from ..data.friction_fit import ASYMMETRIC, PARAMETERS

    names = tuple(dict.fromkeys(PARAMETERS + ASYMMETRIC))
    form = {"--fix": "NAME=VALUE", "--bounds": "NAME=LO:HI"}[flag]
    out = {}
    for item in items or ():
        name, sep, text = item.partition("=")
        try:
            if not sep or name not in names:
                raise ValueError
            value = parse(text)
        except ValueError:
            raise UsageError(f"obsdesign {args.command}: argument {flag}: expected {form} with NAME one of "
                             f"{', '.join(names)}, found {item!r}") from None
        if name in out:
            raise UsageError(f"obsdesign {args.command}: argument {flag}: expected each parameter once, found "
                             f"{name!r} twice")
        out[name] = value
    return out


def _bounds_pair(text: str) -> tuple[float, float]:
    lo, sep, hi = text.partition(":")
    if not sep:
        raise ValueError(text)
    pair = (float(lo) if lo.strip() else float("-inf"), float(hi) if hi.strip() else float("inf"))
    if any(x != x for x in pair) or not pair[0] < pair[1]:
        raise ValueError(text)
    return pair


def _delay_arg(text: str) -> int:
    from ..data.choices import MAX_GIVEN_DELAY

    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value <= MAX_GIVEN_DELAY:
        raise argparse.ArgumentTypeError(f"expected an integer from 0 to {MAX_GIVEN_DELAY}, found {text!r}")
    return value


def _window_arg(text: str) -> tuple[float, float]:
    try:
        t0, t1 = _bounds_pair(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected T0:T1 [s] with T0 < T1, found {text!r}") from None
    return t0, t1


def _load_config(args: argparse.Namespace):
    from ..params import load_preset
    from ..provenance import load_config

    return load_config(args.config) if args.config else load_preset(args.preset)


def _cmd_identify(args: argparse.Namespace) -> int:
    from ..data import identify

    from ..data.rules import design_rules

    check_output_file("identify", "-o/--output", args.output, (".toml",))
    fix = _pairs(args, "--fix", args.fix, float)
    bounds = _pairs(args, "--bounds", args.bounds, _bounds_pair)
    trace = load_trace_args(args, args.data)
    nyquist = 0.5 / trace.sample_time
    if args.filter_hz is not None and not args.filter_hz < nyquist:
        raise UsageError(f"obsdesign identify: argument --filter-hz: expected a cut-off below the Nyquist frequency "
                         f"{nyquist:g} Hz of {args.data!r}, found {args.filter_hz:g}")
    ident = identify(trace, model="asymmetric" if args.asymmetric else "coulomb-viscous", stribeck=args.stribeck,
                     fix=fix, bounds=bounds, min_speed=args.min_speed, window=args.window, n_boot=args.bootstrap,
                     seed=args.seed, input_timing=args.input_timing, delay_samples=args.delay_samples,
                     filter_hz=args.filter_hz, decimation=args.decimation,
                     stribeck_min_speed=args.stribeck_min_speed)
    ident, refined = refine_from_args(args, trace, ident)
    peak = ident.force_peak / abs(ident.input_gain) if ident.input_gain else 0.0
    if args.u_max is not None and peak > args.u_max * (1 + 1e-9):
        raise UsageError(f"obsdesign identify: argument --u-max: expected at least the log's peak |input| {peak:.6g} "
                         f"(the actuator reached it: a wrong limit or unit?), found {args.u_max:g}")
    payload = dict(ident.to_dict(), **({"refinement": refined} if refined else {}))
    text = str(ident)
    try:
        rules = design_rules(ident, u_max=args.u_max)
    except ValueError as e:
        if args.output:
            raise
        rules, text = [], f"{text}\nno design config: {e}"
    if rules:
        payload["config"] = {key: {"value": value, "unit": unit, "rule": rule} for key, value, unit, rule in rules}
        width = max(len(key) for key, *_ in rules)
        text += "\nDesign config (Identification.to_config; each rule):\n" + "\n".join(
            f"  {key:<{width}}  {value if isinstance(value, str) else format(value, '.6g')} {unit}  ({rule})"
            for key, value, unit, rule in rules)
    if args.output:
        stem = Path(args.data).stem
        name = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in stem) or "identified"
        ident.to_config(name=name, u_max=args.u_max).save(args.output)
    notes = list(ident.notices) + ([] if args.u_max is not None or not rules else [
        f"u_max = {rules[3][1]:.4g} {rules[3][2]} is 1.2 x the log's peak input, not the actuator's limit: give the "
        "limit with --u-max U (in the input unit)"])
    print_warnings(notes)
    emit(args, text, payload)
    if args.output:
        import sys

        print(f"obsdesign: wrote {args.output}", file=sys.stderr)
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
        from ..report.figures import relabel, save_figure

        save_figure(relabel(observation_figure(obs), obs.config.units), args.plot)  # the config's axis
    emit(args, obs, obs.summary())
    return 0


def add_commands(sub) -> None:
    """Add ``channels``, ``identify`` and ``observe`` to the subparsers ``sub``."""
    from ..data.choices import INPUT_TIMINGS, MAX_DELAY, MAX_GIVEN_DELAY, STRIBECK_CHOICES

    from ..data.formats import extensions_text

    files = f"measured record ({extensions_text()})"
    p = sub.add_parser("channels", help="list the channels of a log file: name, unit, length, rate")
    p.add_argument("data", metavar="FILE", type=INPUT_FILE, help=f"a log file ({extensions_text()})")
    p.add_argument("--delimiter", type=_delimiter, metavar="D",
                   help="CSV delimiter: ',', ';', tab, space or '|' (default: detected)")
    p.add_argument("--decimal", choices=(".", ","), help="CSV decimal mark (default: detected)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=_cmd_channels)

    p = sub.add_parser("identify", help="identify mass, viscous and Coulomb friction and offset from a record")
    p.add_argument("data", metavar="DATA", type=INPUT_FILE, help=files)
    add_trace_flags(p)
    p.add_argument("--asymmetric", action="store_true", help="separate viscous and Coulomb terms per direction")
    p.add_argument("--stribeck", choices=STRIBECK_CHOICES, default="auto",
                   help="the Stribeck term (Fs, vs): kept where it explains the data (auto, BIC), always, never")
    p.add_argument("--fix", action="append", metavar="NAME=VALUE", help="hold a parameter (SI units), repeatable")
    p.add_argument("--bounds", action="append", metavar="NAME=LO:HI",
                   help="bounds of a parameter (SI units; LO or HI may be empty), repeatable")
    p.add_argument("--min-speed", type=POSITIVE_ARG, metavar="V",
                   help="rows with |v| at or below V [m/s, rad/s] are left out (default 1 %% of the peak)")
    p.add_argument("--stribeck-min-speed", type=POSITIVE_ARG, metavar="V",
                   help="rows the Stribeck decision and a kept Stribeck fit use: |v| above V [m/s, rad/s], at most "
                        "--min-speed (default: the slowest speed the encoder and noise make trustworthy, "
                        "max(3 sigma_v, 2 counts per cut-off period); JSON stribeck_min_speed)")
    p.add_argument("--window", type=_window_arg, metavar="T0:T1", help="fit only the samples in [T0, T1] s")
    p.add_argument("--filter-hz", type=POSITIVE_ARG, metavar="HZ",
                   help="cut-off of the zero-phase low-pass [Hz], below Nyquist (default: from the record, one "
                        "octave above where the position spectrum meets its noise floor, at most a tenth of the rate)")
    p.add_argument("--decimation", type=integer(1), metavar="N",
                   help="decimation factor of the fit's rows (default: the sampling rate / the cut-off, rounded)")
    p.add_argument("--u-max", type=POSITIVE_ARG, metavar="U",
                   help="the actuator limit in the input unit (default 1.2 x the log's peak, with a warning)")
    p.add_argument("--bootstrap", type=integer(0, MAX_BOOTSTRAP), default=400, metavar="N",
                   help="bootstrap replicates of the intervals, at most 100000 (default 400; 0: 1.96 standard "
                        "errors)")
    p.add_argument("--seed", type=integer(0), default=0, help="seed of the bootstrap (default 0)")
    p.add_argument("--input-timing", choices=INPUT_TIMINGS, default="auto",
                   help="hold: the logged input is held until the next sample (a sampled controller's output); "
                        "sample: as logged; default auto: found from the data with the delay")
    p.add_argument("--delay-samples", type=_delay_arg, metavar="D",
                   help=f"samples (0 to {MAX_GIVEN_DELAY}) the position is logged after the input it answers to "
                        f"(default: found from the data, 0 to {MAX_DELAY})")
    add_refine_flags(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("-o", "--output", metavar="FILE.toml", help="write the identified design config")
    p.set_defaults(run=_cmd_identify)

    p = sub.add_parser("observe", help="run the designed observer over a measured record")
    p.add_argument("data", metavar="DATA", type=INPUT_FILE, help=files)
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
