"""Matplotlib figures of simulation results (non-interactive Agg backend).

Examples
--------
>>> import obsdesign as od, io
>>> res = od.simulate(od.load_preset("vcm"), od.sim.Positioning(step_down=0.8), duration=1.0)
>>> svg = trace_figure_svg(res)
>>> svg.startswith("<?xml") and "</svg>" in svg
True
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import matplotlib  # noqa: E402

from .._io import atomic_path

matplotlib.use("Agg")
matplotlib.rcParams["svg.hashsalt"] = "obsdesign"  # the same figure gives the same SVG, byte for byte
import matplotlib.pyplot as plt  # noqa: E402

#: No creation date in the files, so that identical figures are identical files.
_METADATA = {"svg": {"Date": None}, "png": {}, "pdf": {"CreationDate": None}}

__all__ = ["trace_figure", "save_figure", "save_trace_figure", "trace_figure_svg", "figure_svg", "inline_svg",
           "envelope", "relabel"]

#: Columns of :func:`envelope`: more than a figure's width in pixels (8 in at 100 dpi: 800).
ENVELOPE_COLUMNS = 2000


def envelope(t, y, columns: int = ENVELOPE_COLUMNS):
    """A long time series reduced to its extremes: per column the samples of its min and its max.

    Drawn as a line, the reduced series covers the pixels of the full one (a line plot of a series
    much longer than the figure is wide fills each pixel column from its minimum to its maximum,
    and the two extremes are kept in their order in time, so the line still follows the signal) at
    ``2 columns`` points instead of ``len(t)``: the SVG of a 200,000-sample trace is written in a
    fraction of the time. Shorter series (at most ``2 columns`` samples) and series with non-finite
    values (a diverged run) are returned as they are.

    Parameters
    ----------
    t, y : array_like
        Increasing abscissa and the values, of one length.
    columns : int
        Number of columns.

    Returns
    -------
    t, y : ndarray
        The samples kept (the min and the max of each column, in time order), or the input.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(10_000) * 1e-3
    >>> te, ye = envelope(t, np.sin(t), columns=100)
    >>> len(te), float(ye.max()) == float(np.sin(t).max()), bool(np.all(np.diff(te) >= 0))
    (200, True, True)
    """
    import numpy as np

    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    n = len(t)
    if n <= 2 * columns or not np.all(np.isfinite(y)):
        return t, y
    k = -(-n // columns)  # samples per column; the last one padded with its last value
    rows = np.concatenate([y, np.full(k * (-(-n // k)) - n, y[-1])]).reshape(-1, k)
    base = np.arange(rows.shape[0]) * k
    i_lo, i_hi = base + rows.argmin(axis=1), base + rows.argmax(axis=1)
    idx = np.minimum(np.column_stack([np.minimum(i_lo, i_hi), np.maximum(i_lo, i_hi)]).ravel(), n - 1)
    return t[idx], y[idx]


def relabel(fig, units):
    """Write the bracketed units of a figure's axis labels, titles and legends for ``units`` (in place).

    The figures label their axes for a linear axis driven in V (``'friction [N]'``); a rotary
    config's figure reads ``'friction [N m]'`` (:meth:`obsdesign.axis.AxisSpec.label`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    units : AxisSpec or None
        The config's axis (``Config.units``); None leaves the figure as it is.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``.
    """
    if units is None:
        return fig
    texts = [fig._suptitle] if getattr(fig, "_suptitle", None) is not None else []
    for ax in fig.axes:
        texts += [ax.xaxis.label, ax.yaxis.label, ax.title]
        legend = ax.get_legend()
        if legend is not None:
            texts += list(legend.get_texts())
    for text in texts:
        new = units.label(text.get_text())
        if new != text.get_text():
            text.set_text(new)
    return fig


def trace_figure(res):
    """Displacement, error, friction and force of a :class:`~obsdesign.sim.SimResult`.

    Parameters
    ----------
    res : SimResult
        A run with its trace.
    """
    t = res.t
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True, constrained_layout=True)
    ax = axes[0]
    ax.plot(t, res.x * 1e3, label="x")
    if res.scenario in ("positioning", "tracking"):
        ax.plot(t, res.x_ref * 1e3, "--", label="x_ref")
    ax.set_ylabel("displacement [mm]")
    ax.legend(loc="best")
    axes[1].plot(t, res.e * 1e6)
    axes[1].set_ylabel("error x_ref - x [um]")
    ax = axes[2]
    ax.plot(t, res.f_hat, lw=0.5, alpha=0.6, label="f_hat (raw)")
    ax.plot(t, res.f_hat_filtered, label="f_hat filtered")
    ax.plot(t, res.f, "k", lw=1, label="f (plant)")
    ax.set_ylabel("friction state [N]")
    ax.legend(loc="best")
    axes[3].plot(t, res.u)
    axes[3].set_ylabel("force u [N]")
    axes[3].set_xlabel("time [s]")
    fig.suptitle(f"{res.scenario}: {res.controller}, variant {res.config.observer.variant}, "
                 f"rho {res.config.observer.rho:g}")
    return relabel(fig, res.config.units)


def save_figure(fig, path: str | os.PathLike) -> None:
    """Save a figure atomically (format from the suffix) and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    path : str or os.PathLike
        Output file; the suffix gives the format.
    """
    try:
        with atomic_path(path) as tmp:
            fmt = Path(path).suffix.lstrip(".").lower()
            fig.savefig(tmp, format=fmt, metadata=_METADATA.get(fmt))
    finally:
        plt.close(fig)


def save_trace_figure(res, path: str | os.PathLike) -> None:
    """Write :func:`trace_figure` of a result to an SVG or PNG file.

    Parameters
    ----------
    res : SimResult
        A run with its trace.
    path : str or os.PathLike
        Output file (.svg or .png).
    """
    save_figure(trace_figure(res), path)


def figure_svg(fig) -> str:
    """A figure as an SVG string (for inline HTML), closing the figure.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    """
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata=_METADATA["svg"])
    plt.close(fig)
    return buf.getvalue()


def inline_svg(fig, units=None) -> str:
    """A figure as an ``<svg>`` element for an HTML page, closing the figure: its units those of
    ``units`` (an :class:`~obsdesign.axis.AxisSpec`, :func:`relabel`), no XML prolog, no RDF metadata.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    units : AxisSpec, optional
        The axis whose units the labels name (default SI).

    Examples
    --------
    >>> fig, ax = plt.subplots()
    >>> text = inline_svg(fig)
    >>> text.startswith("<svg") and "<metadata>" not in text
    True
    """
    import re

    text = figure_svg(relabel(fig, units))
    return re.sub(r"<metadata>.*?</metadata>", "", text[text.index("<svg"):], flags=re.S)


def trace_figure_svg(res) -> str:
    """:func:`trace_figure` as an SVG string.

    Parameters
    ----------
    res : SimResult
        A run with its trace.
    """
    return figure_svg(trace_figure(res))
