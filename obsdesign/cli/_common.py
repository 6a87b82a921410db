"""Shared pieces of the command line: the parser class, argument types, config flags, output."""

from __future__ import annotations

import argparse
import json
import re

from .._validate import FINITE, NONNEGATIVE, POSITIVE, Range, parse_number
from ..params import VARIANTS, load_config, load_preset, preset_names

__all__ = ["UsageError", "Parser", "number", "POSITIVE_ARG", "NONNEGATIVE_ARG", "FINITE_ARG", "PHASE_ARG",
           "integer", "add_config_flags", "add_design_flags", "load", "emit", "check_output_file"]


class UsageError(Exception):
    """Bad command-line input: reported as one line with exit status 2."""


class Parser(argparse.ArgumentParser):
    """``argparse`` that reports errors as one line (no usage block) through :class:`UsageError`."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # Let "-1e-6" reach the flag's validator instead of being taken for an option.
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|nan)$")

    def error(self, message: str):  # one line, no usage block
        raise UsageError(f"{self.prog}: {message}")


def number(rule: Range, unit: str = ""):
    """An argparse type: a finite number in the rule's range (the flag name is added by argparse)."""

    def parse(text: str) -> float:
        try:
            return parse_number(text, "value", rule, unit)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {rule.describe()}{unit}, found {text!r}") from None

    return parse


POSITIVE_ARG = number(POSITIVE)
NONNEGATIVE_ARG = number(NONNEGATIVE)
FINITE_ARG = number(FINITE)
PHASE_ARG = number(Range(low=0.0, high=90.0), " deg")


def integer(minimum: int):
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


def add_config_flags(p: argparse.ArgumentParser, *, default_preset: str) -> None:
    """``--preset NAME | --config FILE``."""
    group = p.add_mutually_exclusive_group()
    group.add_argument("--preset", choices=preset_names(), help=f"shipped preset (default: {default_preset})")
    group.add_argument("--config", metavar="FILE", help="TOML config file")
    p.set_defaults(default_preset=default_preset)


def add_design_flags(p: argparse.ArgumentParser, *, json_flag: str | None = "print one JSON object") -> None:
    """The observer overrides shared by check, noise and simulate (and --json)."""
    p.add_argument("--variant", choices=VARIANTS, help="override the config's model variant")
    p.add_argument("--rho", type=POSITIVE_ARG, help="override the gain parameter rho (> 0)")
    p.add_argument("--kappa", type=POSITIVE_ARG, help="override the stiffness bound kappa [N/m] (> 0)")
    if json_flag:
        p.add_argument("--json", action="store_true", help=json_flag)


def load(args: argparse.Namespace):
    """The config of ``--config`` or ``--preset`` (or the command's default preset)."""
    if getattr(args, "config", None):
        return load_config(args.config)
    return load_preset(args.preset or args.default_preset)


def emit(args: argparse.Namespace, result, payload: dict) -> None:
    """Print the result as text, or its payload as one strict JSON object with ``--json``."""
    if args.json:
        from .._format import jsonable  # numpy: loaded only when a command prints

        print(json.dumps(jsonable(payload), allow_nan=False))
    else:
        print(result)


def check_output_file(command: str, flag: str, path: str | None, exts: tuple[str, ...]) -> None:
    """An output file's suffix is one of ``exts`` and its folder exists (before any work)."""
    from pathlib import Path

    if path is None:
        return
    p = Path(path)
    if p.suffix.lower() not in exts:
        raise UsageError(f"obsdesign {command}: argument {flag}: expected a file ending in "
                         f"{' or '.join(exts)}, found {path!r}")
    if not p.parent.is_dir():
        raise UsageError(f"obsdesign {command}: argument {flag}: directory {str(p.parent)!r} does not exist")
