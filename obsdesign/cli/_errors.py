"""Exit statuses of the command line and the one-line message of every error.

=====  ==========================================================================
exit   meaning
=====  ==========================================================================
0      success
1      a check failed (``obsdesign check`` only)
2      bad input or an environment problem (unreadable or unwritable path, a path
       that is a folder, a full disk, more memory than available, ...)
3      an internal error (a bug: one line and a hint to report it; set
       ``OBSDESIGN_DEBUG=1`` for the traceback)
130    interrupted (Ctrl-C)
=====  ==========================================================================

Examples
--------
>>> exit_status(FileNotFoundError(2, "No such file or directory", "/proc/x.csv"))
2
>>> describe(FileNotFoundError(2, "No such file or directory", "/proc/x.csv"))
"obsdesign: error: cannot access '/proc/x.csv': No such file or directory"
>>> exit_status(KeyError("x"))
3
"""

from __future__ import annotations

import os
import re

__all__ = ["OK", "CHECK_FAILED", "BAD_INPUT", "INTERNAL", "INTERRUPTED", "exit_status", "describe", "plain"]

OK, CHECK_FAILED, BAD_INPUT, INTERNAL, INTERRUPTED = 0, 1, 2, 3, 130
_BAD_INPUT = (ValueError, TypeError, OSError, MemoryError, OverflowError, UnicodeError)


def _is_template_error(error: BaseException) -> bool:
    return any(t.__module__.startswith("jinja2") and t.__name__ == "TemplateError" for t in type(error).__mro__)


def exit_status(error: BaseException) -> int:
    """The exit status of an uncaught exception: 2 for bad input or the environment, else 3.

    Parameters
    ----------
    error : BaseException
        The exception that ended the command.
    """
    if isinstance(error, KeyboardInterrupt):
        return INTERRUPTED
    return BAD_INPUT if isinstance(error, _BAD_INPUT) or _is_template_error(error) else INTERNAL


#: A NumPy scalar's repr (``np.float64(3.998)``): a message shows the plain number.
_NUMPY_REPR = re.compile(r"\bnp\.(?:float|int|uint|complex|bool|str)\w*\(([^()]*)\)")


def plain(text: str) -> str:
    """``text`` with every NumPy scalar repr replaced by its plain value.

    Examples
    --------
    >>> plain("found np.float64(3.998) after np.float64(3.999), np.int64(7) rows, np.True_")
    'found 3.998 after 3.999, 7 rows, True'
    """
    return re.sub(r"\bnp\.(True|False)_\b", r"\1", _NUMPY_REPR.sub(r"\1", text))


def _first_line(text: str, limit: int = 500) -> str:
    line = plain((str(text).strip().splitlines() or [""])[0])
    return line if len(line) <= limit else line[:limit] + "..."


def describe(error: BaseException) -> str:
    """The one line printed on stderr for an exception (no traceback).

    Parameters
    ----------
    error : BaseException
        The exception that ended the command.
    """
    if isinstance(error, MemoryError):
        detail = _first_line(str(error))
        return ("obsdesign: error: not enough memory for this request" + (f" ({detail})" if detail else "")
                + "; reduce its size (duration/dt, grid, samples)")
    if isinstance(error, OSError):
        reason = error.strerror or _first_line(str(error)) or type(error).__name__
        if error.errno is not None and not error.strerror:
            reason = os.strerror(error.errno)
        where = error.filename if error.filename is not None else None
        if where is None:
            return _first_line(f"obsdesign: error: {reason}")
        return _first_line(f"obsdesign: error: cannot access {str(where)!r}: {reason}")
    if exit_status(error) == INTERNAL:
        return _first_line(f"obsdesign: internal error: {type(error).__name__}: {error}") + (
            " (this is a bug: please report it with the command line; OBSDESIGN_DEBUG=1 shows the traceback)")
    return _first_line(f"obsdesign: error: {error}")
