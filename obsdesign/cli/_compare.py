"""The ``compare`` command: every estimator on every plant friction model and scenario."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..estimators.registry import ESTIMATORS, RULE_FLAGS
from ..friction.registry import FRICTION_MODELS
from ._common import (FINITE_ARG, INPUT_FILE, POSITIVE_ARG, UsageError, add_config_flags, check_output_dir, integer,
                      load, workers_arg)

__all__ = ["add_commands", "parse_list", "summary_text"]


def _scenarios() -> tuple[str, ...]:
    """The comparison's scenarios (:data:`obsdesign.comparison.SCENARIOS`; heavy: read once the command runs)."""
    from ..comparison import SCENARIOS

    return tuple(SCENARIOS)


def parse_list(flag: str, text: str, choices: tuple[str, ...]) -> tuple[str, ...]:
    """A comma-separated list of names, each one of ``choices``.

    Parameters
    ----------
    flag : str
        The flag, for messages.
    text : str
        The list, e.g. ``'paper,lugre'``.
    choices : tuple of str
        The allowed names.

    >>> parse_list("--plants", "paper,gms", FRICTION_MODELS.names())
    ('paper', 'gms')
    >>> parse_list("--plants", "paper,coulomb", FRICTION_MODELS.names())
    Traceback (most recent call last):
    ...
    obsdesign.cli._common.UsageError: obsdesign compare: argument --plants: expected names from paper, lugre, dahl, gms, found 'coulomb'
    """
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise UsageError(f"obsdesign compare: argument {flag}: expected a comma-separated list, found {text!r}")
    for n in names:
        if n not in choices:
            raise UsageError(f"obsdesign compare: argument {flag}: expected names from {', '.join(choices)}, "
                             f"found {n!r}")
    if len(set(names)) != len(names):
        raise UsageError(f"obsdesign compare: argument {flag}: expected distinct names, found {text!r}")
    return names


def summary_text(summary: list[dict], seeds: int) -> str:
    """Plain sentences: which estimator is best where, with the spread over seeds.

    Parameters
    ----------
    summary : list of dict
        :func:`obsdesign.comparison.summarize`.
    seeds : int
        Seeds per case.
    """
    from .._format import short as fmt

    lines = [f"Comparison with standard estimators ({seeds} seed{'s' if seeds != 1 else ''} per case; "
             "'win' only where the spreads over seeds do not overlap and the means differ by more than 1 %)"]
    for s in summary:
        head = f"{s['plant']:6} {s['scenario']:12} {s['metric']:20}"
        if s.get("best") is None:
            lines.append(f"{head} {s['verdict']}")
            continue
        lo, hi = s["best_range"]
        text = f"{head} best {s['best']} {fmt(s['best_mean'])} [{fmt(lo)}, {fmt(hi)}]"
        if s.get("runner_up") is not None:
            lo2, hi2 = s["runner_up_range"]
            text += f", next {s['runner_up']} {fmt(s['runner_up_mean'])} [{fmt(lo2)}, {fmt(hi2)}]"
        lines.append(f"{text}: {s['verdict']}")
    return "\n".join(lines)


def _cmd_compare(args: argparse.Namespace) -> int:
    check_output_dir("compare", "--out", args.out)
    out = Path(args.out)
    if not out.parent.is_dir():
        raise UsageError(f"obsdesign compare: argument --out: directory {str(out.parent)!r} does not exist")
    plants = parse_list("--plants", args.plants, FRICTION_MODELS.names())
    estimators = parse_list("--estimators", args.estimators, ESTIMATORS.names())
    scenarios = _scenarios()
    if args.scenarios is not None:
        scenarios = parse_list("--scenarios", args.scenarios, scenarios)
    from ..comparison import check_comparison_runs

    try:
        check_comparison_runs(len(plants) * len(estimators) * len(scenarios), args.seeds)
    except ValueError as e:
        raise UsageError(f"obsdesign compare: argument --{e}") from None
    if args.data is None and any(v is not None for v in (args.position, args.input, args.time, args.sample_time)):
        raise UsageError("obsdesign compare: the column flags (--position, --input, --time, --sample-time) need "
                         "--data FILE")
    cfg = load(args)
    trace = None
    if args.data is not None:
        if args.position is None or args.input is None:
            raise UsageError("obsdesign compare: argument --data: needs --position NAME and --input NAME")
        from ..data import load_trace

        trace = load_trace(args.data, position=args.position, input=args.input, time=args.time,
                           sample_time=args.sample_time, input_gain=args.input_gain)

    from .._format import jsonable
    from .._io import atomic_write
    from ..comparison import COLUMNS, compare, summarize
    from ..report.comparison_section import comparison_figure
    from ..report.figures import save_figure
    from ..sweeps.store import csv_text

    rule = RULE_FLAGS[args.rule]
    res = compare(cfg, plants=plants, estimators=estimators, scenarios=scenarios, seeds=args.seeds,
                  workers=args.workers, rule=rule)
    rows = list(res.rows)
    if trace is not None:
        from ..comparison_data import compare_data

        rows += compare_data(trace, estimators=estimators, rule=rule)
    skipped = _not_tuned_or_fail(rows)
    summary = summarize(rows)
    out.mkdir(exist_ok=True)
    atomic_write(out / "compare.csv", csv_text(list(COLUMNS), rows))
    payload = {"config": cfg.name, "seeds": res.seeds, "runs": len(rows), "wall_s": res.wall_s,
               "rule": args.rule, "summary": summary, "not_tuned": skipped}
    atomic_write(out / "summary.json", json.dumps(jsonable(payload), indent=1, allow_nan=False))
    save_figure(comparison_figure(rows), out / "compare.svg")
    if args.json:
        print(json.dumps(jsonable(payload), allow_nan=False))
    else:
        print(summary_text(summary, res.seeds))
        for name, reason in skipped.items():
            print(f"{name:6} not tuned, not run: {reason}")
    return 0


def _not_tuned_or_fail(rows: list[dict]) -> dict[str, str]:
    """The baselines the rule could not tune (estimator -> reason); exit status 2 when no row could run.

    The rule of ``compare``'s exit status: 0 when at least one row ran (whatever its status), 2 (one line
    naming each estimator and its reason, nothing written) when every estimator's tuning failed.
    """
    from ..comparison import NOT_TUNED, not_tuned

    skipped = not_tuned(rows)
    if all(str(r["status"]).startswith(NOT_TUNED) for r in rows):
        raise UsageError("obsdesign compare: argument --estimators: no estimator could be tuned, found "
                         + "; ".join(f"{name}: {reason}" for name, reason in skipped.items()))
    return skipped


def add_commands(sub) -> None:
    """Add ``compare`` to the subparsers ``sub``."""
    p = sub.add_parser("compare", help="estimators x plant friction models x scenarios (the shoot-out)")
    add_config_flags(p, default_preset="vcm")
    plants, estimators = ",".join(FRICTION_MODELS.names()), ",".join(ESTIMATORS.names())
    p.add_argument("--plants", default=plants, help=f"plant friction models (default {plants})")
    p.add_argument("--estimators", default=estimators,
                   help=f"estimators (default {estimators}); baselines tuned by the fair noise rule")
    p.add_argument("--scenarios", help="scenarios of obsdesign.comparison.SCENARIOS, comma-separated "
                   "(default: all of them; docs/comparison.md)")
    p.add_argument("--seeds", type=integer(1), default=2, help="seeds per case (default 2)")
    p.add_argument("--rule", choices=tuple(RULE_FLAGS), default="equal-noise",
                   help="how the estimators are tuned: the baselines to the paper observer's friction-noise RMS "
                        "(equal-noise, default) or slowest error pole (rate), or every estimator, the paper's rho and "
                        "omega_co included, for the least predicted friction-estimate error (min-error, docs/tune.md)")
    p.add_argument("--workers", type=workers_arg, help="local processes (default: all cores)")
    p.add_argument("--data", metavar="FILE", type=INPUT_FILE, help="measured trace (.csv/.mat): adds offline rows, friction error "
                   "against the model identified from it (docs/comparison.md)")
    p.add_argument("--position", metavar="NAME", help="--data: displacement column [m]")
    p.add_argument("--input", metavar="NAME", help="--data: actuator input column")
    p.add_argument("--time", metavar="NAME", help="--data: time column [s]")
    p.add_argument("--sample-time", type=POSITIVE_ARG, help="--data: sample time [s] (without --time)")
    p.add_argument("--input-gain", type=FINITE_ARG, default=1.0, help="--data: force per input unit [N/unit]")
    p.add_argument("--out", required=True, metavar="DIR", help="folder for compare.csv, summary.json, compare.svg")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.set_defaults(run=_cmd_compare)
