"""The summary of a finished sweep: the one definition of the keys of ``summary.json``.

``obsdesign sweep`` writes it and ``obsdesign report --sweep DIR`` reads it; both go
through this module.

Examples
--------
>>> summary = {"runs": 2, "ok": 2, "diverged": 0, "failed": 0, "resumed_runs": 0, "wall_s": 1.0,
...            "metric": "rms_error", "best": {"rho": {"value": 2.0, "mean_metric": 1e-5}}}
>>> check_summary(summary, "summary.json") == summary
True
>>> check_summary([], "summary.json")
Traceback (most recent call last):
...
ValueError: summary.json: expected a JSON object with the keys runs, ok, diverged, failed, resumed_runs, wall_s, metric, best, found list
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["SUMMARY_KEYS", "STATUS_VALUES", "best_value", "best_with_spread", "make_summary", "check_summary"]

#: Keys of ``summary.json``, in order (a positioning sweep adds ``settle_band``: ``{"min", "max"}`` [m] of its
#: runs' settling bands, :mod:`obsdesign.loop.bands`).
SUMMARY_KEYS = ("runs", "ok", "diverged", "failed", "resumed_runs", "wall_s", "metric", "best")
#: Values of a row's ``status``.
STATUS_VALUES = ("ok", "diverged", "failed")


def _metric_groups(rows: list[dict], parameter: str, metric: str) -> tuple[dict, dict]:
    """The metric of every run grouped by the value of ``parameter`` (a run that failed or diverged
    counts as ``inf``), and the mean of each group."""
    groups: dict[float, list[float]] = {}
    for row in rows:
        value = row.get(metric)
        ok = row["status"] == "ok" and value not in (None, "")
        groups.setdefault(row[parameter], []).append(float(value) if ok else math.inf)
    means = {p: float(np.mean(v)) for p, v in groups.items()}
    return groups, means


def best_value(rows: list[dict], parameter: str, metric: str = "rms_error") -> tuple[float, float]:
    """The value of a varied ``parameter`` with the lowest mean ``metric`` over its runs
    (runs that failed or diverged count as infinitely bad).

    Parameters
    ----------
    rows : list of dict
        Typed rows of a sweep.
    parameter : str
        A varied parameter.
    metric : str
        A metric column.
    """
    groups, means = _metric_groups(rows, parameter, metric)
    best = min(means, key=means.get)
    return best, means[best]


def best_with_spread(rows: list[dict], parameter: str, metric: str = "rms_error") -> dict[str, Any]:
    """The best value of ``parameter``, the spread of the metric over the samples, and whether the best
    differs from the runner-up by more than that spread.

    Parameters
    ----------
    rows : list of dict
        Typed rows of a sweep.
    parameter : str
        A varied parameter.
    metric : str
        A metric column.

    Returns
    -------
    dict
        ``value``, ``mean_metric`` (as :func:`best_value`), ``spread`` (largest standard deviation of
        the metric over the samples of one value; ``None`` with one sample per value),
        ``runner_up`` (the second-best value), ``difference`` (its mean minus the best mean) and
        ``distinguishable``: the difference exceeds twice its standard error
        ``sqrt(s1^2/n1 + s2^2/n2)`` (``False`` when there is one sample per value, so no spread to
        compare with, or when a mean is not finite).

    Examples
    --------
    >>> rows = [{"rho": r, "rms_error": e, "status": "ok"} for r, e in
    ...         [(1, 1.0), (1, 1.2), (2, 1.05), (2, 1.15), (3, 2.0), (3, 2.2)]]
    >>> b = best_with_spread(rows, "rho")
    >>> b["value"], b["runner_up"], b["distinguishable"]
    (1, 2, False)
    """
    groups, means = _metric_groups(rows, parameter, metric)
    order = sorted(means, key=means.get)
    best = order[0]
    out: dict[str, Any] = {"value": best, "mean_metric": means[best] if math.isfinite(means[best]) else None,
                           "spread": None, "runner_up": None, "difference": None, "distinguishable": False}
    finite = [np.asarray(v) for v in groups.values() if len(v) > 1 and np.all(np.isfinite(v))]
    if finite:
        out["spread"] = float(max(np.std(v, ddof=1) for v in finite))
    if len(order) > 1:
        second = order[1]
        out["runner_up"] = second
        a, b = np.asarray(groups[best]), np.asarray(groups[second])
        if np.all(np.isfinite(a)) and np.all(np.isfinite(b)):
            out["difference"] = float(b.mean() - a.mean())
            if len(a) > 1 and len(b) > 1:
                stderr = math.sqrt(np.var(a, ddof=1) / len(a) + np.var(b, ddof=1) / len(b))
                out["distinguishable"] = bool(out["difference"] > 2.0 * stderr)
        elif np.all(np.isfinite(a)):
            out["distinguishable"] = True  # the runner-up fails or diverges in some runs
    return out


def make_summary(rows: list[dict], varied, *, metric: str, resumed_runs: int, wall_s: float) -> dict[str, Any]:
    """The ``summary.json`` of a sweep's rows (keys :data:`SUMMARY_KEYS`).

    Parameters
    ----------
    rows : list of dict
        Typed rows of a sweep.
    varied : iterable of str
        The varied parameters.
    metric : str
        The metric for the best design.
    resumed_runs : int
        Runs taken from an interrupted sweep.
    wall_s : float
        Wall time [s].
    """
    counts = {s: sum(r["status"] == s for r in rows) for s in STATUS_VALUES}
    summary: dict[str, Any] = {"runs": len(rows), **counts, "resumed_runs": resumed_runs, "wall_s": wall_s,
                               "metric": metric, "best": {}}
    for name in varied:
        summary["best"][name] = best_with_spread(rows, name, metric)
    bands = [r["settle_band"] for r in rows if isinstance(r.get("settle_band"), (int, float))]
    if bands:  # positioning: the settling band of the runs (obsdesign.loop.bands; it follows a varied sensor)
        summary["settle_band"] = {"min": min(bands), "max": max(bands)}
    return summary


def check_summary(data: Any, source: str) -> dict[str, Any]:
    """``data`` if it is a summary of the expected shape (``ValueError`` naming ``source`` otherwise).

    Parameters
    ----------
    data : object
        Parsed JSON.
    source : str
        Its file, for messages.
    """
    expected = f"a JSON object with the keys {', '.join(SUMMARY_KEYS)}"
    if not isinstance(data, dict):
        raise ValueError(f"{source}: expected {expected}, found {type(data).__name__}")
    missing = [k for k in SUMMARY_KEYS if k not in data]
    if missing:
        raise ValueError(f"{source}: expected {expected}, found no {missing[0]!r}")
    for key in ("runs", "ok", "diverged", "failed", "resumed_runs"):
        if isinstance(data[key], bool) or not isinstance(data[key], int):
            raise ValueError(f"{source}: {key}: expected an integer, found {data[key]!r}")
    if not isinstance(data["metric"], str) or not isinstance(data["best"], dict):
        raise ValueError(f"{source}: expected a metric name and a 'best' object, found {data['metric']!r}, "
                         f"{type(data['best']).__name__}")
    for name, best in data["best"].items():
        if not isinstance(best, dict) or not {"value", "mean_metric"} <= set(best):
            raise ValueError(f"{source}: best.{name}: expected an object with value and mean_metric, found {best!r}")
    return data
