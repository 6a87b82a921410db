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
import re
import sys
from pathlib import Path

import matplotlib  # noqa: E402

from .._io import atomic_path

matplotlib.use("Agg")
matplotlib.rcParams["svg.hashsalt"] = "obsdesign"  # the same figure gives the same SVG, byte for byte
# pyplot is not imported here: the trace figure of ``simulate --plot`` is a plain Figure; the modules that
# draw with pyplot import it as ``from .figures import plt`` (module ``__getattr__`` below)


def __getattr__(name: str):
    if name == "plt":  # matplotlib.pyplot, with the Agg backend and the salt set above
        import matplotlib.pyplot as plt

        return plt
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _close(fig) -> None:
    """Close a figure in pyplot's registry (a figure made with pyplot); a plain Figure is left to Python."""
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close(fig)

#: No creation date in the files, so that identical figures are identical files.
_METADATA = {"svg": {"Date": None}, "png": {}, "pdf": {"CreationDate": None}}

__all__ = ["trace_figure", "save_figure", "save_trace_figure", "trace_figure_svg", "figure_svg", "inline_svg",
           "envelope", "relabel", "legible", "regrid", "prefix_ids", "PAGE_WIDTH_PX", "MIN_TEXT_PX"]

#: Width [CSS px] of the report's content column (its ``max-width``): a figure wider than this is drawn smaller.
PAGE_WIDTH_PX = 1050.0
#: Smallest text [CSS px] of a report figure on screen at that width (the page's small print is 13 px).
MIN_TEXT_PX = 10.0
#: CSS pixels per inch (an SVG width of ``w`` pt shows as ``w * 96 / 72`` px at zoom 1).
_CSS_PX_PER_IN = 96.0
#: Fraction of the font size matplotlib draws an exponent at (the ``10^{-3}`` tick labels of a log axis).
_SUPERSCRIPT = 0.7

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


def trace_figure(res, *, pyplot: bool = True):
    """Displacement, error, friction and force of a :class:`~obsdesign.sim.SimResult`.

    Parameters
    ----------
    res : SimResult
        A run with its trace.
    pyplot : bool
        Make the figure with pyplot (default: a notebook shows it, ``plt.show()`` too); False draws it on a
        plain :class:`matplotlib.figure.Figure` without importing pyplot (what ``simulate --plot`` writes:
        the same bytes).
    """
    if pyplot:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(8, 9), constrained_layout=True)
    else:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(8, 9), constrained_layout=True)
    t = res.t
    axes = fig.subplots(4, 1, sharex=True)
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
        _close(fig)


def save_trace_figure(res, path: str | os.PathLike) -> None:
    """Write :func:`trace_figure` of a result to an SVG or PNG file.

    Parameters
    ----------
    res : SimResult
        A run with its trace.
    path : str or os.PathLike
        Output file (.svg or .png).
    """
    save_figure(trace_figure(res, pyplot=False), path)


def figure_svg(fig) -> str:
    """A figure as an SVG string (for inline HTML), closing the figure.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    """
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata=_METADATA["svg"])
    _close(fig)
    return buf.getvalue()


def regrid(fig, cells, *, ncols: int, row_height: float, width: float | None = None):
    """Lay out a figure's axes again on a new grid (in place): ``cells[i]`` is the ``(row, column)`` of the
    ``i``-th axes (rows and columns may be slices); the figure becomes ``rows x row_height`` inches tall.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    cells : sequence of (int or slice, int or slice)
        One cell per axes of the figure, in the order of ``fig.axes``.
    ncols : int
        Columns of the grid.
    row_height : float
        Height [in] of one row.
    width : float, optional
        Width [in] of the figure (default: unchanged).

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``, with the constrained layout.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, axes = plt.subplots(1, 3, figsize=(15, 3))
    >>> _ = regrid(fig, [(0, 0), (0, 1), (1, slice(0, 2))], ncols=2, row_height=3.0, width=10.0)
    >>> [float(v) for v in fig.get_size_inches()], axes[2].get_subplotspec().colspan
    ([10.0, 6.0], range(0, 2))
    >>> plt.close(fig)
    """
    from matplotlib.gridspec import GridSpec

    axes = [ax for ax in fig.axes if ax.get_subplotspec() is not None]
    if len(cells) != len(axes):
        raise ValueError(f"cells: expected one cell per axes ({len(axes)}), found {len(cells)}")
    nrows = 1 + max(r.stop - 1 if isinstance(r, slice) else r for r, _ in cells)
    fig.set_size_inches(width if width is not None else fig.get_figwidth(), nrows * row_height)
    fig.set_layout_engine("constrained")
    grid = GridSpec(nrows, ncols, figure=fig)
    for ax, (r, c) in zip(axes, cells):
        ax.set_subplotspec(grid[r, c])
    return fig


def _renderer(fig):
    if not hasattr(fig.canvas, "get_renderer"):  # a Figure made without pyplot has the base canvas
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    return fig.canvas.get_renderer()


def _wrap(label: str, chars: int) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(label, max(chars, 12), break_long_words=False, break_on_hyphens=False)) or label


def legible(fig, *, width_px: float = PAGE_WIDTH_PX, min_px: float = MIN_TEXT_PX):
    """Make a figure readable on the report's page (in place): no wider than the page, no text smaller than
    ``min_px`` on screen, every legend below its axes (outside the data).

    A figure wider than ``width_px`` is made that wide (its height scaled alike), so the browser shows it at
    its own size; every text is raised to ``min_px`` (an exponent of a log axis's tick label to
    ``min_px`` as well, its base to ``min_px / 0.7``); each axes' legend is drawn again under the axes'
    tick labels and x label, in up to three columns that fit the axes' width, long entries wrapped at spaces.
    The layout engine is the constrained layout (it makes room for the legends).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    width_px : float
        Width [CSS px] of the page's content column.
    min_px : float
        Smallest text [CSS px].

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots(figsize=(14, 4))
    >>> _ = ax.plot([0, 1], [0, 1], label="a line")
    >>> _ = ax.legend(fontsize=6)
    >>> _ = legible(fig)
    >>> round(float(fig.get_figwidth()), 3), ax.get_legend().get_texts()[0].get_fontsize()
    (10.938, 7.5)
    >>> plt.close(fig)
    """
    from matplotlib.text import Text
    from matplotlib.transforms import ScaledTranslation

    width_in = width_px / _CSS_PX_PER_IN
    if fig.get_figwidth() > width_in:
        w, h = fig.get_size_inches()
        fig.set_size_inches(width_in, h * width_in / w)
    fig.set_layout_engine("constrained")
    min_pt = min_px * 72.0 / _CSS_PX_PER_IN
    for ax in fig.axes:
        for name in ("x", "y"):
            axis = getattr(ax, f"{name}axis")
            floor = min_pt / _SUPERSCRIPT if axis.get_scale() == "log" else min_pt
            labels = axis.get_ticklabels(which="both")
            current = max((t.get_fontsize() for t in labels), default=0.0)
            if current < floor:
                ax.tick_params(axis=name, which="both", labelsize=floor)
    for text in fig.findobj(Text):
        if text.get_fontsize() < min_pt:
            text.set_fontsize(min_pt)
    renderer = _renderer(fig)
    legends = []
    for ax in fig.axes:  # all removed first: each is placed in the layout the others leave
        legend = ax.get_legend()
        if legend is not None:
            labels = [t.get_text() for t in legend.get_texts()]
            size = max(legend.get_texts()[0].get_fontsize(), min_pt) if labels else min_pt
            legends.append((ax, legend.legend_handles, labels, size))
            legend.remove()
    fig.draw_without_rendering()
    fig_pt = fig.get_figwidth() * 72.0
    for ax, handles, labels, size in legends:
        below = (ax.bbox.y0 - ax.get_tightbbox(renderer).y0) * 72.0 / fig.dpi + 2.0  # ticks and x label [pt]
        anchor = ax.transAxes + ScaledTranslation(0.0, -below / 72.0, fig.dpi_scale_trans)
        spec = ax.get_subplotspec()
        room = 0.92 * fig_pt * (spec.get_position(fig).width if spec is not None else ax.get_position().width)
        best = None  # (height, ncol, wrapped labels): the lowest legend that fits its room, fewer columns on a tie
        for ncol in range(1, min(3, max(1, len(labels))) + 1):
            chars = int(room / ncol / (0.6 * size)) - 5  # a DejaVu character is about 0.6 em; the handle 5
            wrapped = [_wrap(lb, chars) for lb in labels]
            trial = ax.legend(handles, wrapped, loc="upper center", ncols=ncol, fontsize=size, frameon=False)
            trial.set_in_layout(False)  # measured only: a trial wider than its room must not squeeze the layout
            box = trial.get_window_extent(renderer)
            trial.remove()
            if best is None or (box.width * 72.0 / fig.dpi <= room and box.height < best[0]):
                best = (box.height, ncol, wrapped)
        if best is not None:
            ax.legend(handles, best[2], loc="upper center", ncols=best[1], bbox_to_anchor=(0.5, 0.0),
                      bbox_transform=anchor, fontsize=size, frameon=False)
    return fig


_ID = re.compile(r'\bid="([^"]+)"')


def prefix_ids(svg: str, prefix: str) -> str:
    """``svg`` with every ``id`` and every reference to one (``href="#.."``, ``xlink:href="#.."``,
    ``url(#..)``) prefixed, so that several figures can share one page (matplotlib numbers ``figure_1``,
    ``axes_1``, ... from 1 in every figure, and its marker and clip-path ids repeat across figures).

    Parameters
    ----------
    svg : str
        An SVG document or element.
    prefix : str
        Letters, digits, ``-`` or ``_``, starting with a letter.

    Examples
    --------
    >>> prefix_ids('<g id="a"><use xlink:href="#a"/><path clip-path="url(#a)"/></g>', "f1-")
    '<g id="f1-a"><use xlink:href="#f1-a"/><path clip-path="url(#f1-a)"/></g>'
    """
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_-]*", prefix):
        raise ValueError(f"prefix: expected letters, digits, '-' or '_' starting with a letter, found {prefix!r}")
    ids = set(_ID.findall(svg))
    svg = _ID.sub(lambda m: f'id="{prefix}{m.group(1)}"', svg)
    svg = re.sub(r'(href=")#([^"]+)"', lambda m: f'{m.group(1)}#{prefix}{m.group(2)}"' if m.group(2) in ids
                 else m.group(0), svg)
    return re.sub(r"url\(#([^)]+)\)", lambda m: f"url(#{prefix}{m.group(1)})" if m.group(1) in ids else m.group(0),
                  svg)


def inline_svg(fig, units=None) -> str:
    """A figure as an ``<svg>`` element for an HTML page, closing the figure: its units those of
    ``units`` (an :class:`~obsdesign.axis.AxisSpec`, :func:`relabel`), no XML prolog, no RDF metadata.

    The figure is made :func:`legible` at the page's width; its text stays text (``svg.fonttype`` ``none``:
    selectable, searchable, and printed as text), and its ids carry a prefix of its own, the first hex
    digits of the SHA-256 of its bytes (:func:`prefix_ids`), so that the figures of one page share no id
    and the same figure still gives the same bytes.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    units : AxisSpec, optional
        The axis whose units the labels name (default SI).

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> text = inline_svg(fig)
    >>> text.startswith("<svg") and "<metadata>" not in text
    True
    """
    import hashlib

    with matplotlib.rc_context({"svg.fonttype": "none"}):
        text = figure_svg(legible(relabel(fig, units)))
    text = re.sub(r"<metadata>.*?</metadata>", "", text[text.index("<svg"):], flags=re.S)
    return prefix_ids(text, "f" + hashlib.sha256(text.encode("utf-8")).hexdigest()[:10] + "-")


def trace_figure_svg(res) -> str:
    """:func:`trace_figure` as an SVG string.

    Parameters
    ----------
    res : SimResult
        A run with its trace.
    """
    return figure_svg(trace_figure(res, pyplot=False))
