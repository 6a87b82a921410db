"""The ballbar picture of the circle test: polar plots of the radial deviation, one per mode.

:func:`ballbar_figure` draws, for each :class:`~obsdesign.sim.circle.CircleResult` (with its trace),
the measured contour as ``R_plot + magnification (r - R)`` around the nominal circle (dashed) over the
evaluated revolution, with the four quadrant glitches marked at their peaks and labelled with their
heights; the panels share one magnification, so they compare. ``obsdesign simulate circle --plot FILE``
writes it. Render only: the numbers come from :mod:`obsdesign.sim.circle`.

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

__all__ = ["ballbar_figure", "save_ballbar_figure"]


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
