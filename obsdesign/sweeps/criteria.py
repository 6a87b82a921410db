"""Pass criteria of a run in a Monte-Carlo study: ``NAME<=LIMIT`` or ``NAME>=LIMIT`` on its metrics.

A run passes when it ended ``ok`` and every criterion holds; a non-finite value (a step that
never settles, a metric the run could not give) does not meet a criterion.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from .run import metric_columns

__all__ = ["Criterion", "parse_criterion", "numeric_metrics"]

_CRITERION = re.compile(r"^\s*([A-Za-z0-9_.]+)\s*(<=|>=)\s*(\S+)\s*$")


@dataclass(frozen=True)
class Criterion:
    """A pass criterion of one run: ``metric <= limit`` or ``metric >= limit``.

    Attributes
    ----------
    metric : str
        A metric column (:func:`obsdesign.sweeps.run.metric_columns`).
    op : str
        ``'<='`` or ``'>='``.
    limit : float
        The limit, in the metric's unit.
    """

    metric: str
    op: str
    limit: float

    def passes(self, values: np.ndarray) -> np.ndarray:
        """Whether each value meets the criterion (a non-finite value does not).

        Parameters
        ----------
        values : ndarray
            Values of the metric.
        """
        with np.errstate(invalid="ignore"):
            ok = values <= self.limit if self.op == "<=" else values >= self.limit
        return ok & np.isfinite(values)

    def __str__(self) -> str:
        return f"{self.metric}{self.op}{self.limit:g}"


def parse_criterion(text: str, scenario: str) -> Criterion:
    """``'NAME<=LIMIT'`` or ``'NAME>=LIMIT'`` with NAME a metric of ``scenario``.

    Parameters
    ----------
    text : str
        The criterion.
    scenario : str
        The scenario (its metric columns are the names allowed).

    Examples
    --------
    >>> parse_criterion("settling_time_1<=0.05", "positioning")
    Criterion(metric='settling_time_1', op='<=', limit=0.05)
    >>> parse_criterion("speed<=1", "positioning")
    Traceback (most recent call last):
    ...
    ValueError: criteria: unknown metric 'speed' in 'speed<=1'; expected one of rms_error, max_error, observer_rms_error_v, observer_rms_error_f, settle_band, settling_time_1, settling_time_2, steady_state_error_1, steady_state_error_2, overshoot_1, overshoot_2, rise_time_1, rise_time_2
    """
    if isinstance(text, Criterion):
        return text
    if not isinstance(text, str):
        raise TypeError(f"criteria: expected strings NAME<=LIMIT or NAME>=LIMIT, found {text!r}")
    match = _CRITERION.match(text)
    if match is None:
        raise ValueError(f"criteria: expected NAME<=LIMIT or NAME>=LIMIT, found {text!r}")
    name, op, limit_text = match.groups()
    names = numeric_metrics(scenario)
    if name not in names:
        raise ValueError(f"criteria: unknown metric {name!r} in {text!r}; expected one of {', '.join(names)}")
    try:
        limit = float(limit_text)
    except ValueError:
        limit = math.nan
    if not math.isfinite(limit):
        raise ValueError(f"criteria: expected a finite number as the limit in {text!r}, found {limit_text!r}")
    return Criterion(name, op, limit)


def numeric_metrics(scenario: str) -> list[str]:
    """The metric columns of ``scenario`` that are numbers (not the ``stable``/``diverged`` flags).

    Parameters
    ----------
    scenario : str
        Scenario name.

    >>> numeric_metrics("constant")
    ['rms_error', 'max_error', 'observer_rms_error_v', 'observer_rms_error_f']
    """
    return [c for c in metric_columns(scenario) if c not in ("stable", "diverged")]
