"""Commands that simulate: ``simulate`` and ``sweep``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .._validate import parse_number
from ..params import VARIANTS
from ..sampled.choices import CONTROLLERS, ESTIMATORS, PLANTS, SCHEDULES
from ..loop.scenarios import DEFAULT_DURATION, SCENARIOS
from ._common import (FINITE_ARG, INPUT_FILE, NONNEGATIVE_ARG, POSITIVE_ARG, UsageError, add_config_flags,
                      add_design_flags, check_output_dir, check_output_file, check_runs, check_samples, emit, integer,
                      load, nonempty, print_warnings, workers_arg)

__all__ = ["add_commands", "parse_vary", "parse_uncertain"]

#: Scenario flags of ``simulate`` -> the fields of the scenario specs they set.
_SPEC_FLAGS = {
    "excitation": {"input_force": "force_rms", "excitation_bandwidth": "bandwidth"},
    "constant": {"input_force": "force"},
    "positioning": {"step_size": "step_size", "step_up": "step_up", "step_down": "step_down"},
    "tracking": {},
}


def _cmd_simulate(args: argparse.Namespace) -> int:
    from ..design import design_warnings
    from ..sim import prepare, run
    from ..loop.numerics import saturation_warning
    from ..loop.scenarios import scenario_spec

    check_output_file("simulate", "--out", args.out, (".csv", ".npz"))
    check_output_file("simulate", "--plot", args.plot, (".svg", ".png"))
    if args.scenario == "circle":  # the two-axis contour test: its own command module
        from ._circle import cmd_circle

        return cmd_circle(args)
    if args.config is None and args.preset is None:
        args.preset = "table1" if args.scenario in ("excitation", "constant") else "vcm"
    cfg = load(args).override(noise_rms=args.noise_rms, noise_bandwidth=args.noise_bandwidth,
                              quantization=args.quantization, dt=args.dt)
    plant = args.plant or ("model" if cfg.observer.variant == "lag" else "physical")
    if plant == "physical":
        _warn_lag_on_physical("simulate", cfg, "--plant model or --variant static")
    check_samples(args.duration or DEFAULT_DURATION[args.scenario], cfg.observer.dt)
    options = {field: getattr(args, flag) for flag, field in _SPEC_FLAGS[args.scenario].items()
               if getattr(args, flag) is not None}
    spec = type(scenario_spec(args.scenario))(**options)
    substeps = 10  # prepare's default; raised below for a stiffer --plant-config
    if args.plant_config is not None:
        if plant != "physical":
            raise UsageError("obsdesign simulate: argument --plant-config: needs --plant physical, "
                             f"found --plant {plant}")
        from ..provenance import load_config
        from ..loop.numerics import substeps_for

        plant = load_config(args.plant_config)
        try:  # the simulated plant is this config's: its substeps rule, as for --config (review xe20)
            substeps = substeps_for(plant, cfg.observer.dt, substeps)
        except ValueError as e:
            raise UsageError(f"obsdesign simulate: argument --plant-config: {args.plant_config!r}: {e}") from None
    loop = prepare(cfg, spec, controller=args.controller, stiffness=args.stiffness, plant=plant,
                   estimator=args.estimator, duration=args.duration, seed=args.seed, settle_tol=args.settle_tol,
                   substeps=substeps)
    clipped = saturation_warning(loop)
    print_warnings((*design_warnings(cfg), *([clipped] if clipped else [])))  # after prepare's refusals, before the run
    res = run(loop, keep_trace=bool(args.out or args.plot))
    if args.out:
        (res.to_npz if args.out.lower().endswith(".npz") else res.to_csv)(args.out)
    if args.plot:
        from ..report.figures import save_trace_figure

        save_trace_figure(res, args.plot)
    emit(args, res, res.metrics)
    return 0


def _split(item: str, flag: str, syntax: str, n_parts: int) -> tuple[str, list[str]]:
    name, sep, rest = item.partition("=")
    parts = rest.split(":")
    if not sep or not name or len(parts) != n_parts:
        raise ValueError(f"{flag}: expected {syntax}, found {item!r}")
    return name, parts


def _warn_lag_on_physical(command: str, cfg, cure: str) -> None:
    """The one-line warning of a 'lag' design simulated on the physical plant (its estimate biased)."""
    if cfg.observer.variant == "lag" and cfg.friction.beta is not None:
        print(f"obsdesign {command}: warning: the 'lag' observer follows eq:3:1, which drops the -Fv/beta term of "
              "the physical lag plant, so its friction estimate is biased here (docs/simulation.md); use "
              f"{cure} for a meaningful estimate", file=sys.stderr)


def parse_vary(items: list[str]) -> dict[str, tuple[float, float, int]]:
    """Parse ``NAME=LO:HI:N`` items.

    >>> parse_vary(["rho=1.5:4:6"])
    {'rho': (1.5, 4.0, 6)}
    >>> parse_vary(["rho=1.5:4"])
    Traceback (most recent call last):
    ...
    ValueError: --vary: expected NAME=LO:HI:N, found 'rho=1.5:4'
    """
    from ..sweeps.plan import check_names

    out = {}
    for item in items:
        name, parts = _split(item, "--vary", "NAME=LO:HI:N", 3)
        lo, hi = (parse_number(p, f"--vary {name}") for p in parts[:2])
        digits = parts[2].strip()
        n = int(digits) if digits.isascii() and digits.isdigit() else 0
        if n < 1:
            raise ValueError(f"--vary {name}: expected an integer N >= 1, found {parts[2]!r}")
        if name in out:
            raise ValueError(f"--vary {name}: expected each parameter once, found it twice")
        out[name] = (lo, hi, n)
    return check_names("--vary", out)


def parse_uncertain(items: list[str]) -> dict[str, tuple[float, float]]:
    """Parse ``NAME=LO:HI`` items.

    >>> parse_uncertain(["Cf=0.3:0.4"])
    {'Cf': (0.3, 0.4)}
    """
    from ..sweeps.plan import check_names

    out = {}
    for item in items:
        name, parts = _split(item, "--uncertain", "NAME=LO:HI", 2)
        lo, hi = (parse_number(p, f"--uncertain {name}") for p in parts)
        if hi < lo:
            raise ValueError(f"--uncertain {name}: expected LO <= HI, found {lo:g} > {hi:g}")
        if name in out:
            raise ValueError(f"--uncertain {name}: expected each parameter once, found it twice")
        out[name] = (lo, hi)
    return check_names("--uncertain", out)


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .._io import atomic_write
    from ..sweeps import make_summary, sweep
    from ..sweeps.run import metric_columns

    vary = parse_vary(args.vary or [])
    uncertain = parse_uncertain(args.uncertain or [])
    for name in uncertain:
        if name in vary:
            raise UsageError(f"obsdesign sweep: argument --uncertain: {name!r} is given with --vary too; "
                             "expected each parameter in one of them")
    metrics = metric_columns(args.scenario)
    if args.metric not in metrics:
        raise UsageError(f"obsdesign sweep: argument --metric: expected one of {', '.join(metrics)}, "
                         f"found {args.metric!r}")
    runs = check_runs(vary, args.samples)
    check_output_dir("sweep", "--out", args.out)
    out = Path(args.out)
    stream = args.stream or (not vary and runs > STREAM_ABOVE)
    if not stream and (args.criterion or args.batch is not None or args.worst is not None):
        flag = "--criterion" if args.criterion else "--batch" if args.batch is not None else "--worst"
        raise UsageError(f"obsdesign sweep: argument {flag}: only for a streamed Monte-Carlo study "
                         f"(--stream, or no --vary and more than {STREAM_ABOVE} samples)")
    if stream:
        return _monte_carlo(args, vary, uncertain, runs, out)
    if args.resume and not (out / "results.csv").exists():
        raise UsageError(f"obsdesign sweep: argument --resume: no results.csv in {args.out!r} to resume")
    cfg = load(args)
    _warn_lag_on_physical("sweep", cfg, "--variant static")  # a sweep simulates the physical plant
    res, status = _on_workers(args, f"runs are in {str(out / 'results.csv')!r}", lambda client: sweep(
        cfg, args.scenario, vary=vary, uncertain=uncertain, samples=args.samples, seed=args.seed, executor=client,
        workers=args.workers, out_dir=out, resume=args.resume, force=args.force, progress=_progress(runs),
        duration=args.duration))
    if status is not None:
        return status
    failed = [row for row in res.rows if row.get("status") == "failed"]
    if res.rows and len(failed) == len(res.rows):  # nothing to summarise: say why, exit 2 (bad input)
        raise UsageError(f"obsdesign sweep: all {len(failed)} runs failed; the first (run {failed[0]['run']}): "
                         f"{failed[0]['error']} (rows in {str(out / 'results.csv')!r})")
    from ..report.figures import save_figure  # matplotlib: only once there is something to draw
    from ..report.sweep_figures import sweep_distribution_figure, sweep_map_figure

    summary = make_summary(res.rows, list(vary), metric=args.metric, resumed_runs=res.skipped, wall_s=res.wall_s)
    save_figure(sweep_map_figure(res, list(vary), args.metric), out / "summary_map.svg")
    save_figure(sweep_distribution_figure(res, args.metric), out / "summary_distributions.svg")
    atomic_write(out / "summary.json", json.dumps(summary, indent=1))
    print(json.dumps(summary))
    return 0


#: A sweep without --vary of more samples than this is streamed (obsdesign.sweeps.montecarlo).
STREAM_ABOVE = 20_000


def _on_workers(args, kept: str, run):
    """``(run(client), None)``, the client that of ``--scheduler`` (or None); on Ctrl-C ``(None, 130)`` and on a
    worker that died (BrokenProcessPool, dask KilledWorker, lost connection) ``(None, 1)``, each after one line
    saying where the finished work is (``kept``: "runs are in ...")."""
    client = _connect(args.scheduler) if args.scheduler else None
    try:
        return run(client), None
    except KeyboardInterrupt:
        print(f"obsdesign sweep: interrupted; finished {kept}, continue with --resume", file=sys.stderr)
        return None, 130
    except Exception as e:
        if not _is_worker_failure(e):
            raise
        print(f"obsdesign sweep: a worker failed ({type(e).__name__}); finished {kept}, continue with --resume",
              file=sys.stderr)
        return None, 1
    finally:
        if client is not None:
            client.close()


def _monte_carlo(args: argparse.Namespace, vary: dict, uncertain: dict, runs: int, out: Path) -> int:
    """``sweep --stream``: a Monte-Carlo study of one design, streamed to ``out`` in batches."""
    from .._io import atomic_write
    from ..sweeps.montecarlo import monte_carlo, parse_criterion
    from ..sweeps.summary import make_summary

    if vary:
        raise UsageError("obsdesign sweep: argument --vary: a streamed Monte-Carlo study is of one design; "
                         "drop --vary (or --stream for a grid sweep with results.csv)")
    if not uncertain:
        raise UsageError("obsdesign sweep: argument --uncertain: a Monte-Carlo study needs at least one "
                         "--uncertain NAME=LO:HI")
    try:
        criteria = [parse_criterion(c, args.scenario) for c in args.criterion or []]
    except ValueError as e:
        raise UsageError(f"obsdesign sweep: argument --criterion: {str(e).removeprefix('criteria: ')}") from None
    if args.resume and not (out / "sweep.json").exists():
        raise UsageError(f"obsdesign sweep: argument --resume: no sweep.json in {str(out)!r} to resume")
    cfg = load(args)
    _warn_lag_on_physical("sweep", cfg, "--variant static")
    res, status = _on_workers(args, f"batches are in {str(out / 'batches')!r}", lambda client: monte_carlo(
        cfg, args.scenario, uncertain=uncertain, samples=args.samples, seed=args.seed, criteria=criteria,
        metric=args.metric, worst=args.worst or 10, batch=args.batch or 200, executor=client, workers=args.workers,
        out_dir=out, resume=args.resume, force=args.force, progress=_progress(runs), duration=args.duration))
    if status is not None:
        return status
    if res.counts["failed"] == res.runs:
        first = res.worst[0]
        raise UsageError(f"obsdesign sweep: all {res.runs} runs failed; the first (run {first['run']}): "
                         f"{first['error']} ({str(out / 'montecarlo.json')!r})")
    summary = make_summary([], [], metric=args.metric, resumed_runs=res.resumed_runs, wall_s=res.wall_s)
    summary.update({"runs": res.runs, **res.counts})
    atomic_write(out / "summary.json", json.dumps(summary, indent=1))
    lo, hi = res.interval
    print(json.dumps({**summary, "failures": res.failures, "failure_probability": res.failure_probability,
                      "interval": [lo, hi], "confidence": res.confidence, "criteria": list(res.criteria)}))
    return 0


def _connect(address: str):
    """A ``distributed.Client`` of ``address``, or one line (``UsageError``) within about 15 s."""
    import importlib.util

    from ..sweeps.scheduler import probe_scheduler

    if importlib.util.find_spec("distributed") is None:
        raise UsageError("obsdesign sweep: argument --scheduler: needs dask[distributed] "
                         "(pip install 'obsdesign[distributed]')")
    try:
        probe_scheduler(address, timeout=5.0)  # before the (slow) import of distributed
    except ValueError as e:
        raise UsageError(f"obsdesign sweep: argument --{e}") from None
    from distributed import Client
    import logging

    logging.getLogger("distributed").setLevel(logging.CRITICAL)  # failures are reported in one line
    try:
        return Client(address, timeout="10s")
    except (OSError, ValueError, TypeError, MemoryError) as e:
        raise UsageError(f"obsdesign sweep: argument --scheduler: cannot reach {address!r} "
                         f"({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})") from None


def _progress(runs: int) -> bool | int:
    """A tqdm bar on a terminal; otherwise a line on stderr every tenth of the ``runs``
    (counted by :func:`~obsdesign.cli._common.check_runs`)."""
    if sys.stderr.isatty():
        return True
    return max(1, runs // 10)


def _is_worker_failure(e: BaseException) -> bool:
    import concurrent.futures

    from ..sweeps.pool import NoWorkersError

    if isinstance(e, (concurrent.futures.BrokenExecutor, NoWorkersError)):
        return True
    return type(e).__module__.startswith("distributed") or type(e).__name__ in ("KilledWorker", "CommClosedError")


def add_commands(sub) -> None:
    """Add ``simulate`` and ``sweep`` to the subparsers ``sub``."""
    p = sub.add_parser("simulate", help="closed-loop simulation of a scenario")
    p.add_argument("scenario", choices=(*SCENARIOS, "circle"))
    add_config_flags(p, default_preset="table1 for excitation/constant, vcm otherwise")
    p.add_argument("--controller", choices=CONTROLLERS.names())
    add_design_flags(p, json_flag="print the metrics as one JSON object")
    p.add_argument("--stiffness", choices=SCHEDULES.names(), default="estimated",
                   help="observer stiffness schedule (default: estimated)")
    p.add_argument("--plant", choices=PLANTS.names(),
                   help="physical (Coulomb with pre-sliding memory + viscous friction) or model (the LTV model "
                        "eq:3:1 of the variant); default: model for variant lag, physical for static")
    p.add_argument("--plant-config", metavar="FILE", type=INPUT_FILE,
                   help="simulate the plant of this TOML config (mass, gain, load, friction, [plant_friction]); "
                        "observer and controller stay designed from --preset/--config")
    p.add_argument("--estimator", choices=ESTIMATORS.names(), default="paper",
                   help="estimator in the loop (default paper; baselines tuned by the fair noise rule)")
    p.add_argument("--noise-rms", type=NONNEGATIVE_ARG, help="measurement noise RMS [m]")
    p.add_argument("--noise-bandwidth", type=POSITIVE_ARG, help="measurement noise bandwidth [Hz]")
    p.add_argument("--quantization", type=NONNEGATIVE_ARG, help="encoder resolution [m] (0: none)")
    p.add_argument("--input-force", type=FINITE_ARG, help="open-loop force [N] (constant, or RMS of the excitation)")
    p.add_argument("--duration", type=POSITIVE_ARG, help="length [s]")
    p.add_argument("--dt", type=POSITIVE_ARG, help="sample time [s]")
    p.add_argument("--seed", type=integer(0), default=0, help="noise seed (integer >= 0)")
    p.add_argument("--step-size", type=FINITE_ARG, help="positioning step [m] (default 1e-3)")
    p.add_argument("--step-up", type=NONNEGATIVE_ARG, help="time of the step up [s] (default 0.5)")
    p.add_argument("--step-down", type=NONNEGATIVE_ARG, help="time of the step back [s] (default 3.0)")
    p.add_argument("--excitation-bandwidth", type=POSITIVE_ARG, help="bandwidth of the excitation force [Hz] (default 5)")
    p.add_argument("--settle-tol", type=POSITIVE_ARG,
                   help="settling band [m] (default: max(2 x quantization, 3 x noise RMS), 0.1 %% of the step for an "
                        "ideal sensor; stated in the output)")
    p.add_argument("--out", metavar="FILE", help="write the trace to FILE.csv or FILE.npz")
    p.add_argument("--plot", metavar="FILE", help="write a figure to FILE.svg or FILE.png")
    from ._circle import add_circle_flags

    add_circle_flags(p)
    p.set_defaults(run=_cmd_simulate)

    p = sub.add_parser("sweep", help="design sweep with Monte-Carlo draws, locally or on Dask")
    add_config_flags(p, default_preset="vcm")
    p.add_argument("--scenario", required=True, choices=SCENARIOS)
    p.add_argument("--vary", action="append", metavar="NAME=LO:HI:N", help="grid axis (repeatable)")
    p.add_argument("--uncertain", action="append", metavar="NAME=LO:HI", help="uniform draw (repeatable)")
    p.add_argument("--samples", type=integer(1), default=1, help="draws per grid point (default 1)")
    p.add_argument("--duration", type=POSITIVE_ARG, help="simulated time per run [s]")
    p.add_argument("--variant", choices=VARIANTS)
    p.add_argument("--seed", type=integer(0), default=0)
    p.add_argument("--out", required=True, metavar="DIR", help="folder for results.csv and the summary")
    p.add_argument("--scheduler", metavar="ADDRESS", type=nonempty("scheduler address"), help="Dask scheduler, e.g. tcp://127.0.0.1:8786")
    p.add_argument("--workers", type=workers_arg, help="local processes (default: all cores)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="finish an interrupted sweep in --out")
    again.add_argument("--force", action="store_true", help="replace the results of another sweep in --out")
    p.add_argument("--metric", default="rms_error",
                   help="metric for the best design, or of the worst runs of a streamed study (default rms_error)")
    p.add_argument("--stream", action="store_true",
                   help=f"a Monte-Carlo study streamed to DIR/batches (default above {STREAM_ABOVE} samples "
                        "without --vary): quantiles, failure probability, worst runs in DIR/montecarlo.json")
    p.add_argument("--criterion", action="append", metavar="NAME<=LIMIT",
                   help="pass criterion of a run in a streamed study, quoted for the shell (repeatable; also NAME>=LIMIT)")
    p.add_argument("--batch", type=integer(1), help="runs per batch of a streamed study (default 200)")
    p.add_argument("--worst", type=integer(1), help="worst runs kept by a streamed study (default 10)")
    p.set_defaults(run=_cmd_sweep)
