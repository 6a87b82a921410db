"""The report's figures kept in the result memo (issue 37): drawn once per data, code and matplotlib set-up.

A warm report draws no figure and imports no matplotlib: :func:`kept_svg` keys a figure by what decides
its bytes, all known without importing matplotlib, and reads the SVG back when nothing changed.

Examples
--------
>>> import numpy as np
>>> key = figure_key("obsdesign.report.study_figures:experiments_figure", (np.arange(3.0),), {})
>>> key[0], len(key[1])
('obsdesign.report.study_figures:experiments_figure', 64)
"""

from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path
from typing import Any, Callable

__all__ = ["kept_svg", "figure_key", "VOLATILE"]

#: Dictionary entries left out of a figure's key: a run's wall time is not data (no figure shows it).
VOLATILE = ("sim_wall_s",)


def _function(make: str | Callable) -> Callable:
    if callable(make):
        return make
    module, _, name = make.partition(":")
    return getattr(importlib.import_module(module), name)


def _name(make: str | Callable) -> str:
    if isinstance(make, str):
        if ":" not in make:
            raise TypeError(f"kept_svg: make must be 'module:function' or a function, found {make!r}")
        return make
    name = f"{getattr(make, '__module__', '')}:{getattr(make, '__qualname__', '')}"
    if "<" in name:  # a lambda or a local function: its name does not say which one
        raise TypeError(f"kept_svg: make must be a module-level function, found {name}")
    return name


def _matplotlib_setup() -> str:
    """What decides matplotlib's rcParams in a fresh process, read without importing it: its version (the
    distribution folder's name beside it) and every matplotlibrc it may read (``./matplotlibrc``,
    ``$MATPLOTLIBRC``, ``$MPLCONFIGDIR``, ``$XDG_CONFIG_HOME/matplotlib``, ``~/.config/matplotlib``),
    with the variables themselves."""
    import importlib.util

    from .._digest import data_digest

    spec = importlib.util.find_spec("matplotlib")
    if spec is None or not spec.origin:
        raise TypeError("kept_svg: matplotlib is not installed")
    site = Path(spec.origin).parent.parent
    try:
        infos = sorted(e for e in os.listdir(site) if e.endswith(".dist-info") and e.lower().startswith("matplotlib-"))
    except OSError:
        infos = []
    env = {k: os.environ.get(k) for k in ("MATPLOTLIBRC", "MPLCONFIGDIR", "XDG_CONFIG_HOME", "HOME")}
    config = Path(env["XDG_CONFIG_HOME"] or Path.home() / ".config") / "matplotlib"
    candidates = [Path("matplotlibrc").resolve(), config / "matplotlibrc"]
    for var in ("MATPLOTLIBRC", "MPLCONFIGDIR"):
        if env[var]:
            candidates += [Path(env[var]), Path(env[var]) / "matplotlibrc"]
    files: list[tuple[str, bytes | str | None]] = []
    for path in candidates:
        try:
            files.append((str(path), path.read_bytes() if path.is_file() else None))
        except OSError as e:
            files.append((str(path), type(e).__name__))
    return data_digest((spec.origin, infos, env, files))


def _rc_as_read() -> bool:
    """Whether this process's rcParams are those its matplotlibrc files give (with the package's own
    ``svg.hashsalt``): False when a caller changed them (a notebook's style), so its figures are drawn."""
    if "matplotlib" not in sys.modules:
        return True
    import matplotlib

    pristine = matplotlib.rc_params()
    pristine["svg.hashsalt"] = "obsdesign"
    skip = ("backend", "backend_fallback")
    return all(repr(v) == repr(pristine.get(k)) for k, v in matplotlib.rcParams.items() if k not in skip)


def figure_key(make: str | Callable, args: tuple, kwargs: dict, units: Any = None) -> tuple[str, str, str]:
    """The memo key of :func:`kept_svg`: the figure function's qualified name, the digest of its arguments
    and ``units`` (:func:`obsdesign._digest.data_digest`; the runs' wall times left out) and of matplotlib's
    set-up (:func:`_matplotlib_setup`). The package's code is in every memo key.

    Parameters
    ----------
    make : callable or str
        The figure function, or ``"module:function"``.
    args : tuple
        Its positional arguments.
    kwargs : dict
        Its keyword arguments.
    units : AxisSpec, optional
        The units the figure's labels name.

    Raises
    ------
    TypeError
        An argument cannot be digested, or ``make`` is a lambda or a local function.
    """
    from .._digest import data_digest

    return _name(make), data_digest((args, kwargs, units), VOLATILE), _matplotlib_setup()


def kept_svg(make: str | Callable, *args, units=None, **kwargs) -> str:
    """:func:`obsdesign.report.figures.inline_svg` of ``make(*args, **kwargs)``, kept in the result memo.

    A figure function is a pure function of its arguments, the package's code and matplotlib's set-up
    (version and rc files), so a kept figure is the same bytes as a drawn one
    (tests/test_report_memo.py). Drawn every time: arguments that cannot be digested, and a process
    whose rcParams were changed from what its files say. A kept figure is put on the page only if
    :func:`obsdesign.report.markup.is_figure_svg` holds (matplotlib's SVG elements only, no script, event
    handler or outside link); else it is drawn again, with a :class:`~obsdesign._memo.MemoWarning`.

    Parameters
    ----------
    make : callable or str
        Returns a :class:`matplotlib.figure.Figure` from the arguments; a string ``"module:function"``
        is imported only when the figure is drawn (a warm report imports no matplotlib).
    *args, **kwargs
        Its arguments (data: numbers, arrays, results).
    units : AxisSpec, optional
        As for :func:`~obsdesign.report.figures.inline_svg`.

    Examples
    --------
    >>> import numpy as np
    >>> from obsdesign.report.figures import inline_svg
    >>> def line(y):
    ...     import matplotlib.pyplot as plt
    ...     fig, ax = plt.subplots()
    ...     ax.plot(y)
    ...     return fig
    >>> kept_svg(line, np.arange(3.0)) == inline_svg(line(np.arange(3.0)))
    True
    """
    from .._memo import memo
    from .markup import is_figure_svg

    def draw() -> str:
        from .figures import inline_svg

        return inline_svg(_function(make)(*args, **kwargs), units)

    try:
        key = figure_key(make, args, kwargs, units)
    except TypeError:
        return draw()
    if not _rc_as_read():
        return draw()
    return memo("report_figure", key, draw, valid=is_figure_svg)
