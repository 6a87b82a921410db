"""The ballbar picture of the circle test: polar plots of the radial deviation, one per mode.

:func:`ballbar_figure` draws, for each :class:`~obsdesign.sim.circle.CircleResult` (with its trace),
the measured contour as ``R_plot + magnification (r - R)`` around the nominal circle (dashed) over the
evaluated revolution, with the four quadrant glitches marked at their peaks and labelled with their
heights; the panels share one magnification, so they compare. ``obsdesign simulate circle --plot FILE``
writes it. :func:`circle_section` is the report's section "Circle (ballbar) test of the compensation
modes": the glitch peaks of :func:`~obsdesign.sim.circle.circle_modes` per mode and feed (mean and
min-max over the seeds and both directions) and the ballbar picture at one feed. Render only: the
numbers come from :mod:`obsdesign.sim.circle`.

Examples
--------
>>> import obsdesign as od
>>> res = od.sim.simulate_circle(od.load_preset("vcm"), radius=5e-3, feed=2e-2, keep_trace=True)
>>> fig = ballbar_figure({"observer": res})
>>> len(fig.axes)
1
"""

from __future__ import annotations

import numpy as np

__all__ = ["ballbar_figure", "save_ballbar_figure", "circle_section", "FEEDS", "RADIUS", "SEEDS", "FIGURE_FEED"]

#: Feeds [m/s] of the circle test of issue 20's contract (2 to 20 mm/s), for the report and analysis/circle_modes.py.
FEEDS = (2e-3, 6.32e-3, 2e-2)
#: Radius [m] of the report's circle test.
RADIUS = 5e-3
#: Noise seeds of the report's circle test: one, in both directions, so that a report with sensor noise
#: stays a few seconds (24 contours); analysis/circle_modes.py and docs/compensation-modes.md carry the
#: spread over five seeds.
SEEDS = (0,)
#: The feed [m/s] of the report's ballbar picture (the shortest run, the largest PID glitch).
FIGURE_FEED = 2e-2


def ballbar_figure(results: dict, *, magnification: float | None = None):
    """Polar plots of the radial deviation of circle runs, side by side.

    Parameters
    ----------
    results : dict of str to CircleResult
        Panel title -> a run with its trace (``keep_trace=True``).
    magnification : float, optional
        Plotted deviation per metre of radial error; default: the largest deviation of the runs
        drawn at a third of the radius.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .figures import plt

    if not results:
        raise ValueError("results: expected at least one circle run, found none")
    devs = {}
    for name, res in results.items():
        if len(res.theta) == 0:
            raise ValueError(f"results: run {name!r} has no trace; simulate it with keep_trace=True")
        w = res.window
        radius = res.metrics["radius"]
        r = np.hypot(res.x[w] + radius, res.y[w])
        sign = 1.0 if res.metrics["direction"] == "ccw" else -1.0
        devs[name] = (sign * res.theta[w], r - radius - res.metrics["radial_error"]["median"])
    peak = max(float(np.max(np.abs(d))) for _, d in devs.values()) or 1.0
    mag = magnification if magnification is not None else 1.0 / (3.0 * peak)
    fig, axes = plt.subplots(1, len(results), subplot_kw={"projection": "polar"}, figsize=(4.2 * len(results), 4.6),
                             squeeze=False)
    for ax, (name, res) in zip(axes[0], results.items()):
        th, d = devs[name]
        phase = np.mod(res.theta[res.window], 2 * np.pi)  # the path angle within the revolution
        ax.plot(th, 1.0 + mag * d, lw=0.9)
        ax.plot(np.linspace(0, 2 * np.pi, 361), np.ones(361), "k--", lw=0.6)
        for g in res.metrics["glitches"]:
            a0 = np.radians(g["angle_deg"])
            sel = (phase >= a0) & (phase < a0 + np.pi / 4)
            if np.any(sel):
                i = np.flatnonzero(sel)[np.argmax(np.abs(d[sel]))]
                ax.plot(th[i], 1.0 + mag * d[i], "o", ms=4, color="C3")
                ax.annotate(f"{g['height'] * 1e6:.1f}", (th[i], 1.0 + mag * d[i]), fontsize=7, color="C3")
        ax.set_ylim(0, 1.0 + mag * peak * 1.3)
        ax.set_yticklabels([])
        m = res.metrics
        ax.set_title(f"{name}\npeak {m['glitch_peak'] * 1e6:.1f} um, circularity {m['circularity'] * 1e6:.1f} um",
                     fontsize=9)
    fig.suptitle(f"ballbar: radial deviation x {mag * next(iter(results.values())).metrics['radius']:.3g} "
                 f"(relative to R), glitch heights in um", fontsize=9)
    return fig


def save_ballbar_figure(results: dict, path) -> None:
    """Write :func:`ballbar_figure` to an SVG or PNG file (atomically).

    Parameters
    ----------
    results : dict of str to CircleResult
    path : str or os.PathLike
    """
    from .figures import save_figure

    save_figure(ballbar_figure(results), path)


def _run_seeds(cfg, seeds) -> tuple:
    """The seeds that run: all of them with random sensor noise, else the first (every seed gives the same run)."""
    return tuple(seeds) if cfg.sensor.noise_rms > 0 else tuple(seeds)[:1]


def feed_runs(cfg, feed: float, *, feeds=FEEDS, seeds=SEEDS, radius: float = RADIUS,
              figure_feed: float = FIGURE_FEED):
    """The runs of :func:`circle_section` at one feed: its rows, or the message why the axis cannot drive it.

    Parameters
    ----------
    cfg : Config
    feed : float
        The path velocity [m/s].
    feeds, seeds, radius, figure_feed
        As for :func:`circle_section` (they decide the directions, seeds and traces of this feed).

    Returns
    -------
    list of dict or str
        :func:`~obsdesign.sim.circle.circle_modes` rows, or the refusal's message.
    """
    from ..sim.circle import DIRECTIONS, circle_modes

    seeds = _run_seeds(cfg, seeds)

    def compute():
        try:
            return circle_modes(cfg, feeds=(feed,), directions=DIRECTIONS if feed in feeds else DIRECTIONS[:1],
                                seeds=seeds if feed in feeds else seeds[:1], radius=radius,
                                keep_trace=feed == figure_feed)
        except ValueError as err:
            return str(err)

    if feed == figure_feed:  # its runs carry their traces (the figure's): computed
        return compute()
    from .._memo import config_key, memo

    # the other feeds' rows are numbers: kept in the result memo, keyed by everything they depend on
    return memo("report_circle_feed", (config_key(cfg), feed, tuple(feeds), tuple(seeds), radius, figure_feed),
                compute, valid=_is_feed_rows)


#: The fields of a kept circle row and their types.
_ROW_TYPES = {"mode": str, "feed": float, "direction": str, "seed": int, "glitch_peak": float,
              "circularity": float, "radial_rms": float}


def _is_feed_rows(value) -> bool:
    """The schema of :func:`feed_runs`'s kept value: a refusal's message or rows of :data:`_ROW_TYPES`."""
    if isinstance(value, str):
        return True
    return isinstance(value, list) and all(
        isinstance(r, dict) and set(r) == set(_ROW_TYPES)
        and all(isinstance(r[k], t) and not isinstance(r[k], bool) for k, t in _ROW_TYPES.items()) for r in value)


def circle_section(cfg, *, feeds=FEEDS, seeds=SEEDS, radius: float = RADIUS, figure_feed: float = FIGURE_FEED,
                   runs=None, figure: bool = True) -> dict:
    """The report's circle test of the compensation modes on the axis of ``cfg``.

    Runs :func:`~obsdesign.sim.circle.circle_modes` (every mode, both directions) per feed; a feed the
    axis cannot drive, or a run that diverges, gives a note instead of numbers. With no random noise
    (``sensor.noise_rms = 0``) every seed gives the same run, so only the first seed runs.

    Parameters
    ----------
    cfg : Config
        The design of both axes.
    feeds, seeds : sequence
        Path velocities [m/s] and noise seeds.
    radius : float
        Radius [m].
    figure_feed : float
        Feed [m/s] of the ballbar picture (ccw, the first seed; all modes); the runs of the table
        when it is one of ``feeds``.
    runs : mapping, optional
        Feed -> :func:`feed_runs` of the same arguments, computed elsewhere (the report's helper
        process); the other feeds run here.
    figure : bool
        Draw the ballbar figure (``figure``); False leaves it ``None`` and returns its runs instead
        (``pictured``: mode -> result, for :func:`ballbar_figure`; the report keeps the drawn figure).

    Returns
    -------
    dict
        ``radius, feeds, seeds, directions, noisy``; ``rows``: per mode ``mode`` and ``cells`` (per feed
        ``mean, min, max`` of the glitch peak [m] over seeds and directions, or ``None``); ``notes``: the
        refused feeds' messages; ``figure``: the ballbar figure (``None`` if its feed was refused).

    Examples
    --------
    >>> import obsdesign as od
    >>> sec = circle_section(od.load_preset("vcm"), feeds=(2e-2,))
    >>> sec["seeds"], [r["mode"] for r in sec["rows"]][:2], sec["figure"] is not None
    ((0,), ['pid', 'observer'], True)
    """
    from ..sim.circle import DIRECTIONS

    noisy = cfg.sensor.noise_rms > 0
    seeds = _run_seeds(cfg, seeds)
    runs = dict(runs or {})
    peaks: dict = {}
    notes = []
    pictured: dict = {}
    for feed in (*feeds, *(() if figure_feed in feeds else (figure_feed,))):
        rows = runs[feed] if feed in runs else feed_runs(cfg, feed, feeds=feeds, seeds=seeds, radius=radius,
                                                         figure_feed=figure_feed)
        if isinstance(rows, str):
            notes.append(f"{feed * 1e3:g} mm/s: {rows}")
            continue
        for r in rows:
            if feed in feeds:
                peaks.setdefault(r["mode"], {}).setdefault(feed, []).append(r["glitch_peak"])
            if feed == figure_feed and r["direction"] == DIRECTIONS[0] and r["seed"] == seeds[0]:
                pictured[r["mode"]] = r["result"]
    table = []
    for mode, by_feed in peaks.items():
        cells = []
        for feed in feeds:
            g = np.asarray(by_feed.get(feed, []))
            cells.append({"mean": float(g.mean()), "min": float(g.min()), "max": float(g.max())} if g.size else None)
        table.append({"mode": mode, "cells": cells})
    section = {"radius": radius, "feeds": tuple(feeds), "seeds": seeds, "directions": DIRECTIONS, "noisy": noisy,
               "rows": table, "notes": notes, "figure": ballbar_figure(pictured) if pictured and figure else None,
               "figure_feed": figure_feed}
    if not figure:
        section["pictured"] = pictured
    return section
