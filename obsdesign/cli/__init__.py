"""The ``obsdesign`` command.

Every subcommand validates its input where it enters; bad input ends with one
line on stderr and exit status 2, never a traceback. One module per group of
commands: :mod:`~obsdesign.cli._design` (derive, check, pid, noise),
:mod:`~obsdesign.cli._sim` (simulate, sweep), :mod:`~obsdesign.cli._output`
(export, report), :mod:`~obsdesign.cli._compare` (compare); shared argument types in :mod:`~obsdesign.cli._common`.

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
import sys
from typing import Sequence

from . import _compare, _design, _output, _sim
from ._common import Parser, UsageError

__all__ = ["main", "build_parser", "UsageError"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``obsdesign`` command."""
    parser = Parser(prog="obsdesign", description="Design and verify reduced-order friction observers.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    _design.add_commands(sub)
    _sim.add_commands(sub)
    _output.add_commands(sub)
    _compare.add_commands(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 success, 1 a check failed, 2 bad input.
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
