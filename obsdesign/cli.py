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
import sys
from typing import Sequence

from .params import VARIANTS

__all__ = ["main", "build_parser"]


class UsageError(Exception):
    """Bad command-line input: reported as one line with exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, no usage block
        raise UsageError(f"{self.prog}: {message}")


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
