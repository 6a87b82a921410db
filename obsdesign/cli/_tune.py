"""The ``tune`` command: rho, omega_co and the compensation gain by a named objective (docs/tune.md)."""

from __future__ import annotations

import argparse

from ._common import POSITIVE_ARG, add_config_flags, check_output_file, emit, integer, load, number
from .._validate import MAX_DELAY_SAMPLES, Range
from ..design.objectives import OBJECTIVES, TRACKING_SCENARIOS

__all__ = ["add_commands"]



def _cmd_tune(args: argparse.Namespace) -> int:
    check_output_file("tune", "-o", args.output, (".toml",))
    cfg = load(args).override(delay_samples=args.delay_samples)
    from .._io import atomic_write
    from ..design.tune import Constraints, tune

    constraints = Constraints(min_phase_margin_deg=args.min_phase_margin, max_command_noise=args.max_command_noise)
    res = tune(cfg, objective=args.objective, constraints=constraints, scenario=args.scenario,
               reversal_rate=args.reversal_rate, tune_gain=not args.keep_gain)
    if args.output is not None:
        atomic_write(args.output, res.config.to_toml())
    emit(args, res, res.to_dict())
    return 0


def add_commands(sub) -> None:
    """Add ``tune`` to the subparsers ``sub``."""
    p = sub.add_parser("tune", help="choose rho, omega_co and the compensation gain by an objective (docs/tune.md)")
    add_config_flags(p, default_preset="vcm")
    p.add_argument("--objective", choices=OBJECTIVES.names(), default=OBJECTIVES.names()[0],
                   help="; ".join(f"{k}: {v}" for k, v in OBJECTIVES.describe().items()))
    p.add_argument("--scenario", choices=TRACKING_SCENARIOS, default=TRACKING_SCENARIOS[0],
                   help="scenario of the tracking objective (default tracking)")
    p.add_argument("--min-phase-margin", type=number(Range(low=0.0, high=180.0, low_inclusive=True), " deg"),
                   help="least phase margin [deg] of the sampled loop with the compensation (incl. the delay)")
    p.add_argument("--max-command-noise", type=POSITIVE_ARG, help="largest RMS [V] of the command from sensor noise")
    p.add_argument("--delay-samples", type=integer(0, MAX_DELAY_SAMPLES),
                   help="override the drive's delay [samples] from the sampled position to the applied command "
                        "([hardware] delay_samples, 0 to 10000)")
    p.add_argument("--reversal-rate", type=POSITIVE_ARG, help="reversals per second of the lag model (default 1)")
    p.add_argument("--keep-gain", action="store_true", help="keep the config's compensation gain")
    p.add_argument("-o", "--output", metavar="FILE", help="write the tuned config (.toml)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=_cmd_tune)
