"""The ``obsdesign`` command.

Every subcommand validates its input where it enters; bad input ends with one
line on stderr and exit status 2, never a traceback.

Examples
--------
>>> main(["derive", "--variant", "static", "--format", "json"])  # doctest: +ELLIPSIS
{"variant": "static", ...}
0
>>> main(["derive", "--variant", "dynamic"])
2
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from typing import Sequence

from .params import VARIANTS, _Range, load_config, load_preset, preset_names

__all__ = ["main", "build_parser"]


class UsageError(Exception):
    """Bad command-line input: reported as one line with exit status 2."""


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # Let "-1e-6" reach the flag's validator instead of being taken for an option.
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|nan)$")

    def error(self, message: str):  # one line, no usage block
        raise UsageError(f"{self.prog}: {message}")


def _number(rule: _Range, unit: str = ""):
    """An argparse type: a finite number in the rule's range (the flag name is added by argparse)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {rule.describe()}{unit}, found {text!r}") from None
        try:
            return rule.check("value", value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {rule.describe()}{unit}, found {text!r}") from None

    return parse


_POSITIVE = _number(_Range(low=0.0))
_NONNEGATIVE = _number(_Range(low=0.0, low_inclusive=True))
_PHASE = _number(_Range(low=0.0, high=90.0), " deg")


def _add_config_flags(p: argparse.ArgumentParser, *, default_preset: str) -> None:
    group = p.add_mutually_exclusive_group()
    group.add_argument("--preset", choices=preset_names(), help=f"shipped preset (default: {default_preset})")
    group.add_argument("--config", metavar="FILE", help="TOML config file")
    p.set_defaults(default_preset=default_preset)


def _add_design_flags(p: argparse.ArgumentParser, *, json_flag: str | None = "print one JSON object") -> None:
    """The observer overrides shared by check, noise and simulate (and --json)."""
    p.add_argument("--variant", choices=VARIANTS, help="override the config's model variant")
    p.add_argument("--rho", type=_POSITIVE, help="override the gain parameter rho (> 0)")
    p.add_argument("--kappa", type=_POSITIVE, help="override the stiffness bound kappa [N/m] (> 0)")
    if json_flag:
        p.add_argument("--json", action="store_true", help=json_flag)


def _load(args: argparse.Namespace):
    if getattr(args, "config", None):
        return load_config(args.config)
    return load_preset(args.preset or args.default_preset)


def _jsonable(value):
    """Strict JSON: non-finite floats become null, NumPy scalars plain numbers."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _emit(args: argparse.Namespace, result, payload: dict) -> None:
    if args.json:
        print(json.dumps(_jsonable(payload), allow_nan=False))
    else:
        print(result)


def _cmd_check(args: argparse.Namespace) -> int:
    import warnings

    from .design import check_stability

    cfg = _load(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # reported in the output instead
        report = check_stability(cfg, rho=args.rho, kappa=args.kappa, variant=args.variant)
    _emit(args, report, report.to_dict())
    if not args.json:
        for note in report.warnings:
            print(f"warning: {note}")
    return 0 if report.all_hold else 1


def _cmd_pid(args: argparse.Namespace) -> int:
    from .design import design_pid

    cfg = _load(args)
    pid = design_pid(
        phi=args.phi if args.phi is not None else (cfg.phi if args.tau is None else cfg.plant.K * args.tau / cfg.plant.m),
        tau=args.tau if args.tau is not None else cfg.pid.tau,
        max_S=args.max_s if args.max_s is not None else cfg.pid.max_S,
        phase_margin_deg=args.phase_margin if args.phase_margin is not None else cfg.pid.phase_margin_deg,
    )
    _emit(args, pid, pid.to_dict())
    return 0


def _cmd_noise(args: argparse.Namespace) -> int:
    from .design import noise_analysis

    cfg = _load(args)
    na = noise_analysis(cfg, rho=args.rho, kappa=args.kappa, variant=args.variant,
                        noise_rms=args.noise_rms, noise_bandwidth=args.noise_bandwidth,
                        stiffness=args.stiffness)
    _emit(args, na, na.to_dict())
    return 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .sim import simulate

    for flag, path, exts in (("--out", args.out, (".csv", ".npz")), ("--plot", args.plot, (".svg", ".png"))):
        if path is not None:
            p = Path(path)
            if p.suffix.lower() not in exts:
                raise UsageError(f"obsdesign simulate: argument {flag}: expected a file ending in "
                                 f"{' or '.join(exts)}, found {path!r}")
            if not p.parent.is_dir():
                raise UsageError(f"obsdesign simulate: argument {flag}: directory {str(p.parent)!r} does not exist")
    if args.config is None and args.preset is None:
        args.preset = "table1" if args.scenario in ("excitation", "constant") else "vcm"
    cfg = _load(args)
    res = simulate(
        cfg, args.scenario, controller=args.controller, variant=args.variant, rho=args.rho, kappa=args.kappa,
        stiffness=args.stiffness, plant=args.plant, noise_rms=args.noise_rms, noise_bandwidth=args.noise_bandwidth,
        quantization=args.quantization, input_force=args.input_force, duration=args.duration, dt=args.dt,
        seed=args.seed, step_size=args.step_size, step_up=args.step_up, step_down=args.step_down,
        excitation_bandwidth=args.excitation_bandwidth,
        settle_tol=args.settle_tol, keep_trace=bool(args.out or args.plot),
    )
    if args.out:
        (res.to_npz if args.out.lower().endswith(".npz") else res.to_csv)(args.out)
    if args.plot:
        from .report.figures import save_trace_figure

        save_trace_figure(res, args.plot)
    _emit(args, res, res.metrics)
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from .export import export

    paths = export(_load(args), args.format, args.output, variant=args.variant, rho=args.rho, dt=args.dt)
    for path in paths:
        print(path)
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .report.html import write_report

    out = Path(args.output)
    if not out.parent.is_dir():
        raise UsageError(f"obsdesign report: argument -o/--output: directory {str(out.parent)!r} does not exist")
    cfg = _load(args)
    label = f"config file {args.config}" if args.config else f"preset {cfg.name}"
    write_report(cfg, out, source_label=label, progress=not args.quiet, sweep_dir=args.sweep)
    print(args.output)
    return 0


def _cmd_sweep(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from .report.figures import save_figure
    from .report.sweep_figures import sweep_distribution_figure, sweep_map_figure
    from .sim.sweep import parse_uncertain, parse_vary, sweep

    vary = parse_vary(args.vary or [])
    uncertain = parse_uncertain(args.uncertain or [])
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"obsdesign sweep: argument --out: expected a directory, found the file {args.out!r}")
    if args.resume and not (out / "results.csv").exists():
        raise UsageError(f"obsdesign sweep: argument --resume: no results.csv in {args.out!r} to resume")
    cfg = _load(args)
    client = None
    if args.scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise UsageError("obsdesign sweep: argument --scheduler: needs dask[distributed] "
                             "(pip install 'obsdesign[distributed]')") from None
        try:
            client = Client(args.scheduler, timeout="10s")
        except OSError as e:
            raise UsageError(f"obsdesign sweep: argument --scheduler: cannot reach {args.scheduler!r} ({e})") from None
    try:
        res = sweep(cfg, args.scenario, vary=vary, uncertain=uncertain, samples=args.samples, seed=args.seed,
                    executor=client, workers=args.workers, out_dir=out, resume=args.resume,
                    progress=sys.stderr.isatty(), duration=args.duration, variant=args.variant)
    except KeyboardInterrupt:
        print(f"obsdesign sweep: interrupted; finished runs are in {str(out / 'results.csv')!r}, "
              "continue with --resume", file=sys.stderr)
        return 130
    except Exception as e:  # a worker process died (BrokenProcessPool, dask KilledWorker, lost connection)
        if not _is_worker_failure(e):
            raise
        print(f"obsdesign sweep: a worker failed ({type(e).__name__}); finished runs are in "
              f"{str(out / 'results.csv')!r}, continue with --resume", file=sys.stderr)
        return 1
    finally:
        if client is not None:
            client.close()
    counts = {s: sum(r["status"] == s for r in res.rows) for s in ("ok", "diverged", "failed")}
    summary = {"runs": len(res.rows), **counts, "resumed_runs": res.skipped, "wall_s": res.wall_s,
               "metric": args.metric, "best": {}}
    if res.rows and args.metric not in res.columns:
        raise UsageError(f"obsdesign sweep: argument --metric: expected one of "
                         f"{', '.join(c for c in res.columns if c not in ('status', 'error'))}, found {args.metric!r}")
    for name in vary:
        value, score = res.best(name, args.metric)
        summary["best"][name] = {"value": value, "mean_metric": score if math.isfinite(score) else None}
    save_figure(sweep_map_figure(res, list(vary), args.metric), out / "summary_map.svg")
    save_figure(sweep_distribution_figure(res, args.metric), out / "summary_distributions.svg")
    from ._io import atomic_write

    atomic_write(out / "summary.json", json.dumps(summary, indent=1))
    print(json.dumps(summary))
    return 0


def _is_worker_failure(e: BaseException) -> bool:
    import concurrent.futures

    if isinstance(e, concurrent.futures.BrokenExecutor):
        return True
    return type(e).__module__.startswith("distributed") or type(e).__name__ in ("KilledWorker", "CommClosedError")


def _integer(minimum: int):
    """An argparse type: an integer >= minimum."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = minimum - 1
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, found {text!r}")
        return value

    return parse


_seed = _integer(0)
_count = _integer(1)


def _cmd_derive(args: argparse.Namespace) -> int:
    from .symbolic import derive
    from .symbolic.printing import derivation_json, derivation_latex, derivation_text

    d = derive(args.variant)
    if args.format == "json":
        print(json.dumps(derivation_json(d)))
    elif args.format == "latex":
        print(derivation_latex(d, standalone=True), end="")
    else:
        print(derivation_text(d), end="")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``obsdesign`` command."""
    parser = _Parser(prog="obsdesign", description="Design and verify reduced-order friction observers.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    p = sub.add_parser("derive", help="symbolic derivation of the observer")
    p.add_argument("--variant", choices=VARIANTS, default="lag", help="model variant (default: lag)")
    p.add_argument("--format", choices=("text", "latex", "json"), default="text")
    p.set_defaults(run=_cmd_derive)

    p = sub.add_parser("check", help="stability verdicts of an observer design (exit 1 if one fails)")
    _add_config_flags(p, default_preset="table1")
    _add_design_flags(p)
    p.set_defaults(run=_cmd_check)

    p = sub.add_parser("pid", help="sensitivity-based PID design (section 4.1)")
    _add_config_flags(p, default_preset="vcm")
    p.add_argument("--phi", type=_POSITIVE, help="plant gain phi [m/(V s)] (default: K tau / m)")
    p.add_argument("--tau", type=_POSITIVE, help="plant time constant tau [s]")
    p.add_argument("--max-s", type=_POSITIVE, help="bound of |S| [m/V]; k = 1/max|S|")
    p.add_argument("--phase-margin", type=_PHASE, help="phase margin [deg], in (0, 90)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=_cmd_pid)

    p = sub.add_parser("noise", help="measurement noise in the friction estimate (section 3.4)")
    _add_config_flags(p, default_preset="vcm")
    _add_design_flags(p)
    p.add_argument("--noise-rms", type=_NONNEGATIVE, help="noise RMS [m] (>= 0)")
    p.add_argument("--noise-bandwidth", type=_POSITIVE, help="noise bandwidth [Hz] (> 0)")
    p.add_argument("--stiffness", type=_NONNEGATIVE, default=0.0, help="constant stiffness k [N/m] (default 0)")
    p.set_defaults(run=_cmd_noise)

    from .sim.scenarios import SCENARIOS

    p = sub.add_parser("simulate", help="closed-loop simulation of a scenario")
    p.add_argument("scenario", choices=SCENARIOS)
    _add_config_flags(p, default_preset="table1 for excitation/constant, vcm otherwise")
    p.add_argument("--controller", choices=("open-loop", "pid", "pid+observer"))
    _add_design_flags(p, json_flag="print the metrics as one JSON object")
    p.add_argument("--stiffness", choices=("estimated", "true", "constant"), default="estimated",
                   help="observer stiffness schedule (default: estimated)")
    p.add_argument("--plant", choices=("physical", "model"), default="physical")
    p.add_argument("--noise-rms", type=_NONNEGATIVE, help="measurement noise RMS [m]")
    p.add_argument("--noise-bandwidth", type=_POSITIVE, help="measurement noise bandwidth [Hz]")
    p.add_argument("--quantization", type=_NONNEGATIVE, help="encoder resolution [m] (0: none)")
    p.add_argument("--input-force", type=_number(_Range()), help="open-loop force [N] (constant, or RMS of the excitation)")
    p.add_argument("--duration", type=_POSITIVE, help="length [s]")
    p.add_argument("--dt", type=_POSITIVE, help="sample time [s]")
    p.add_argument("--seed", type=_seed, default=0, help="noise seed (integer >= 0)")
    p.add_argument("--step-size", type=_number(_Range()), help="positioning step [m] (default 1e-3)")
    p.add_argument("--step-up", type=_NONNEGATIVE, help="time of the step up [s] (default 0.5)")
    p.add_argument("--step-down", type=_NONNEGATIVE, help="time of the step back [s] (default 3.0)")
    p.add_argument("--excitation-bandwidth", type=_POSITIVE, help="bandwidth of the excitation force [Hz] (default 5)")
    p.add_argument("--settle-tol", type=_POSITIVE, default=2e-6, help="settling band [m] (default 2e-6)")
    p.add_argument("--out", metavar="FILE", help="write the trace to FILE.csv or FILE.npz")
    p.add_argument("--plot", metavar="FILE", help="write a figure to FILE.svg or FILE.png")
    p.set_defaults(run=_cmd_simulate)

    p = sub.add_parser("sweep", help="design sweep with Monte-Carlo draws, locally or on Dask")
    _add_config_flags(p, default_preset="vcm")
    p.add_argument("--scenario", required=True, choices=SCENARIOS)
    p.add_argument("--vary", action="append", metavar="NAME=LO:HI:N", help="grid axis (repeatable)")
    p.add_argument("--uncertain", action="append", metavar="NAME=LO:HI", help="uniform draw (repeatable)")
    p.add_argument("--samples", type=_count, default=1, help="draws per grid point (default 1)")
    p.add_argument("--duration", type=_POSITIVE, help="simulated time per run [s]")
    p.add_argument("--variant", choices=VARIANTS)
    p.add_argument("--seed", type=_seed, default=0)
    p.add_argument("--out", required=True, metavar="DIR", help="folder for results.csv and the summary")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://127.0.0.1:8786")
    p.add_argument("--workers", type=_count, help="local processes (default: all cores)")
    p.add_argument("--resume", action="store_true", help="finish an interrupted sweep in --out")
    p.add_argument("--metric", default="rms_error", help="metric for the best design (default rms_error)")
    p.set_defaults(run=_cmd_sweep)

    p = sub.add_parser("export", help="export the derivation or the designed observer as code")
    p.add_argument("--format", required=True, choices=("latex", "python", "c", "octave", "js"))
    _add_config_flags(p, default_preset="vcm")
    p.add_argument("--variant", choices=VARIANTS, help="override the config's model variant")
    p.add_argument("--rho", type=_POSITIVE, help="gain parameter rho (> 0)")
    p.add_argument("--dt", type=_POSITIVE, help="sample time [s] of the discrete observer")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    p.set_defaults(run=_cmd_export)

    p = sub.add_parser("report", help="self-contained HTML design report")
    _add_config_flags(p, default_preset="vcm")
    p.add_argument("-o", "--output", default="report.html", metavar="FILE", help="output file (default report.html)")
    p.add_argument("--sweep", metavar="DIR", help="add the summary of an 'obsdesign sweep' folder")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(run=_cmd_report)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    Exit status: 0 success, 1 a check failed, 2 bad input.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        return args.run(args)
    except UsageError as e:
        print(str(e), file=sys.stderr)
        return 2
    except (ValueError, TypeError) as e:
        print(f"obsdesign: error: {e}".splitlines()[0], file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
