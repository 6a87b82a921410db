"""Summary figures of a sweep: performance/stability map and metric distributions."""

from __future__ import annotations

import math

import numpy as np

from .figures import plt

__all__ = ["sweep_map_figure", "sweep_distribution_figure"]


def _label(metric: str) -> str:
    """Axis label of a metric column with its unit (``settling_time_1`` -> ``settling_time_1 [s]``)."""
    from ..sim.metrics import METRIC_UNITS

    base = metric.rstrip("0123456789").rstrip("_")
    unit = METRIC_UNITS.get(base) or ("m" if metric.startswith("rms_error_") else "")
    return f"{metric} [{unit}]" if unit else metric


def _values(result, metric: str):
    return np.array([float(r[metric]) if r["status"] == "ok" and r.get(metric) is not None else np.nan
                     for r in result.rows])


def sweep_map_figure(result, varied: list[str], metric: str = "rms_error"):
    """Mean ``metric`` over the draws at each grid point; failed/diverged/unstable points marked.

    Parameters
    ----------
    result : SweepResult
        A finished sweep.
    varied : list of str
        The varied parameters (the first two are drawn).
    metric : str
        A metric column.
    """
    vals = _values(result, metric)
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    if len(varied) == 1:
        p = varied[0]
        xs = sorted({r[p] for r in result.rows})
        groups = [np.array([v for v, r in zip(vals, result.rows) if r[p] == x and np.isfinite(v)]) for x in xs]
        mean = [g.mean() if g.size else np.nan for g in groups]
        spread = [g.std(ddof=1) if g.size > 1 else 0.0 for g in groups]
        bad = [sum(r["status"] != "ok" for r in result.rows if r[p] == x) for x in xs]
        unstable = [sum(r.get("stable") is False for r in result.rows if r[p] == x) for x in xs]
        finite = np.array([m for m in mean if np.isfinite(m)])
        ax.errorbar(xs, mean, yerr=spread, fmt="o-", capsize=3,
                    label="mean over the samples, bars: standard deviation" if max(spread) > 0 else "value (one sample)")
        if finite.size and finite.min() > 0 and finite.max() / finite.min() > 10:
            ax.set_yscale("log")
        for x, b, u in zip(xs, bad, unstable):
            if b or u:
                ax.annotate(f"{b} failed/diverged, {u} unstable", (x, np.nanmin(vals) if np.isfinite(np.nanmin(vals)) else 1),
                            fontsize=7, rotation=90, color="r")
        ax.set_xlabel(p)
        ax.set_ylabel(_label(metric))
        ax.legend(loc="best")
    elif len(varied) >= 2:
        p, q = varied[:2]
        xs, ys = sorted({r[p] for r in result.rows}), sorted({r[q] for r in result.rows})
        grid = np.full((len(ys), len(xs)), np.nan)
        for i, y in enumerate(ys):
            for j, x in enumerate(xs):
                sel = [v for v, r in zip(vals, result.rows) if r[p] == x and r[q] == y]
                grid[i, j] = np.nanmean(sel) if sel and np.any(np.isfinite(sel)) else np.nan
        im = ax.pcolormesh(xs, ys, np.log10(grid), shading="nearest")
        fig.colorbar(im, ax=ax, label=f"log10 of the mean {_label(metric)}")
        ax.set_xlabel(p)
        ax.set_ylabel(q)
    else:
        ax.text(0.5, 0.5, "no varied parameter", ha="center")
    ax.set_title(f"sweep: {len(result.rows)} runs")
    return fig


def sweep_distribution_figure(result, metric: str = "rms_error"):
    """Histogram of ``metric`` over all runs that finished (uncertainty spread).

    Parameters
    ----------
    result : SweepResult
        A finished sweep.
    metric : str
        A metric column.
    """
    vals = _values(result, metric)
    vals = vals[np.isfinite(vals)]
    fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    if vals.size:
        bins = np.logspace(math.log10(vals.min()), math.log10(vals.max()) + 1e-9, 25) if vals.min() > 0 else 25
        ax.hist(vals, bins=bins)
        if vals.min() > 0:
            ax.set_xscale("log")
    from matplotlib.ticker import MaxNLocator

    ax.set_xlabel(_label(metric))
    ax.set_ylabel("runs")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_title(f"{vals.size} of {len(result.rows)} runs ok")
    return fig
