"""The ``obsdesign`` command.

Every subcommand validates its input where it enters; bad input ends with one
line on stderr and exit status 2, never a traceback. One module per group of
commands: :mod:`~obsdesign.cli._design` (derive, check, pid, noise),
:mod:`~obsdesign.cli._sim` (simulate, sweep), :mod:`~obsdesign.cli._output`
(export, report), :mod:`~obsdesign.cli._data` (identify, observe), :mod:`~obsdesign.cli._loop` (loop),
:mod:`~obsdesign.cli._config` (config),
:mod:`~obsdesign.cli._compare` (compare), :mod:`~obsdesign.cli._tune` (tune); shared argument types in :mod:`~obsdesign.cli._common`. Building the
parser imports no numerical library: the heavy modules load inside the commands.

Exit statuses: 0 success, 1 a check failed (``check`` only), 2 bad input or an
environment problem, 3 an internal error (see :mod:`~obsdesign.cli._errors`).

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
import errno
import gc
import io
import os
import sys
import traceback
import warnings
from typing import Sequence

from .. import __version__
from . import _compare, _config, _data, _design, _dynamic, _loop, _output, _sim, _tune
from ._common import Parser, UsageError
from ._errors import BAD_INPUT, describe, exit_status, plain

__all__ = ["main", "run", "build_parser", "UsageError"]


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``obsdesign`` command.

    Parameters
    ----------
    command : str, optional
        Build only this subcommand's parser (what ``main`` parses with: the other fifteen are not
        needed to parse one command's arguments, and building them is a third of a quick command's
        start-up). A name that is not a command builds the whole parser, so its error message is
        the whole parser's.

    Examples
    --------
    >>> sorted(build_parser("check")._subparsers._group_actions[0].choices)
    ['check']
    >>> len(build_parser("walk")._subparsers._group_actions[0].choices) > 10
    True
    """
    parser = Parser(prog="obsdesign", description="Design and verify reduced-order friction observers.")
    parser.add_argument("--version", action="version", version=f"obsdesign {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    only = None if command is None else _OnlyCommand(sub, command)
    for module in (_design, _sim, _output, _data, _loop, _config, _compare, _dynamic, _tune):
        module.add_commands(sub if only is None else only)
    if only is not None and not only.found:
        return build_parser()
    return parser


class _Unused:
    """What the parser of a command that is not being run gets: every call is accepted and ignored."""

    def __getattr__(self, name):
        return lambda *args, **kwargs: self


class _OnlyCommand:
    """The subparsers action, adding only one command's parser (see :func:`build_parser`)."""

    def __init__(self, sub, command: str):
        self._sub, self._command, self.found = sub, command, False

    def add_parser(self, name: str, **kwargs):
        if name != self._command:
            return _Unused()
        self.found = True
        return self._sub.add_parser(name, **kwargs)

    def __getattr__(self, name):
        return getattr(self._sub, name)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    Every error ends as one line on stderr, never a traceback (``OBSDESIGN_DEBUG=1``
    adds it); see :mod:`obsdesign.cli._errors` for the statuses.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 success, 1 a check failed (``check`` only), 2 bad input or an environment
        problem, 3 an internal error, 130 interrupted.
    """
    stdout = sys.stdout
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            argv = list(sys.argv[1:] if argv is None else argv)
            parser = build_parser(argv[0] if argv and not argv[0].startswith("-") else None)
            args = parser.parse_args(argv)
            sys.stdout = _Output(stdout)
            try:
                status = args.run(args)
                sys.stdout.flush()
            finally:
                sys.stdout = stdout
    except SystemExit as e:  # --help, --version
        return e.code if isinstance(e.code, int) else (0 if e.code is None else 2)
    except UsageError as e:
        _say(str(e))
        return BAD_INPUT
    except BaseException as e:  # noqa: BLE001 (every error becomes one line)
        if os.environ.get("OBSDESIGN_DEBUG") == "1":
            traceback.print_exc()
        if isinstance(e, OutputError):
            _silence(stdout)
            _say(f"obsdesign: error: cannot write to standard output ({e.strerror or e})")
            return BAD_INPUT
        if isinstance(e, KeyboardInterrupt):
            _say("obsdesign: interrupted")
        else:
            _say(describe(e))
        return exit_status(e)
    for w in _unique(caught):
        _say(f"obsdesign: warning: {w}")
    return status


def run() -> None:
    """The ``obsdesign`` program: exit with the status of :func:`main`.

    Before the interpreter ends, every object the run created is frozen out of the garbage collector
    (:func:`gc.freeze`): the interpreter's last collections would walk all of them (numba's types and
    compiled functions, matplotlib's figures) only to free memory the process gives back anyway, 0.1 to
    0.5 s of a command (``benchmarks/RESULTS.md``). Files are closed, streams flushed and exit handlers run
    as usual.
    """
    status = main()
    gc.freeze()
    sys.exit(status)


def _unique(caught) -> list[str]:
    seen: list[str] = []
    for w in caught:
        text = plain(str(w.message).strip().splitlines()[0]) if str(w.message).strip() else w.category.__name__
        if text not in seen:
            seen.append(text)
    return seen


class OutputError(OSError):
    """Writing to standard output failed (a full disk, a closed pipe)."""


class _Output:
    """Standard output that tags its write errors as :class:`OutputError`.

    A closed standard output (``>&-``: Python sets ``sys.stdout`` to None) raises the same error
    on the first write, so a command that prints ends with one line and exit status 2.
    """

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        if self._stream is None:
            raise OutputError(errno.EBADF, "closed")
        try:
            return self._stream.write(text)
        except OSError as e:
            raise OutputError(e.errno, e.strerror) from e

    def flush(self):
        if self._stream is None:
            return
        try:
            self._stream.flush()
        except OSError as e:
            raise OutputError(e.errno, e.strerror) from e

    def isatty(self):
        return self._stream is not None and self._stream.isatty()

    def __getattr__(self, name):
        if self._stream is None:
            raise OutputError(errno.EBADF, "closed")
        return getattr(self._stream, name)


def _silence(stream) -> None:
    """Point a broken standard output at the null device, so the exit flush raises nothing."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        pass


def _say(line: str) -> None:
    try:
        print(line, file=sys.stderr)
    except (OSError, ValueError):
        pass
