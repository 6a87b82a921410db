"""Step-response metrics of one positioning step: overshoot, rise, settling and peak time.

The settling time has the simulator's definition (:func:`obsdesign.sim.metrics.loop_metrics`):
over the samples from the step on, the last sample outside the band ``|y - y1| <= settle_band``
(a NaN counts as outside) is found; the step has settled at the next sample
(:func:`settling_sample`). No sample outside gives 0; a last sample outside, or (with ``dwell``)
fewer than that fraction of the samples inside at the end, gives ``None``: did not settle within
the trace. The simulator uses ``dwell`` :data:`obsdesign.loop.bands.SETTLE_DWELL` (the window of
the steady-state error) and counts ``(k + 1) dt`` from the first sample of the hold; here the time
is ``t[settled] - t_step``: the same sample, equal up to the rounding of the time stamps.

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0.0, 1.0, 10001)
>>> y = 1.0 - np.exp(-t / 0.05)                          # first order, tau = 50 ms
>>> m = step_metrics(t, y, t_step=0.0, y0=0.0, y1=1.0, settle_band=0.02)
>>> m["overshoot"], round(m["rise_time"], 4), round(m["settling_time"], 4)  # ln 9 tau, ln 50 tau
(0.0, 0.1099, 0.1957)
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["step_metrics", "last_outside", "settling_sample", "RISE_LIMITS"]

#: Fractions of the step between which the rise time is measured.
RISE_LIMITS = (0.1, 0.9)


def _finite(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a real number, found {type(value).__name__} {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, found {value!r}")
    return value


def _crossing(t: np.ndarray, r: np.ndarray, level: float) -> float | None:
    """First time ``r`` reaches ``level``, linearly interpolated between the two samples around it."""
    hits = r >= level
    i = int(np.argmax(hits))  # the first True (argmax of booleans stops there), or 0 if there is none
    if not hits[i]:
        return None
    if i == 0:
        return float(t[0])
    t0, t1, r0, r1 = t[i - 1], t[i], r[i - 1], r[i]
    return float(t0 + (level - r0) * (t1 - t0) / (r1 - r0))


def last_outside(y: np.ndarray, center: float, band: float, *, scratch: np.ndarray | None = None) -> int | None:
    """Index of the last sample of ``y`` outside ``|y - center| <= band`` (NaN counts as outside), or None.

    Parameters
    ----------
    y : ndarray, shape (n,)
        The samples.
    center, band : float
        Centre and half-width of the band.
    scratch : ndarray, shape (>= n,), optional
        A float buffer (not ``y``) for ``|y - center|``.

    Returns
    -------
    int or None

    Examples
    --------
    >>> last_outside(np.array([3.0, 0.5, np.nan, 0.2, -0.1]), 0.0, 1.0), last_outside(np.zeros(3), 0.0, 1.0)
    (2, None)
    """
    if scratch is None:
        dist = np.abs(y - center)
    else:
        dist = np.abs(np.subtract(y, center, out=scratch[:y.size]), out=scratch[:y.size])
    inside = dist <= band
    if not inside.size:
        return None
    j = int(np.argmin(inside[::-1]))  # the first False from the end, or 0 if there is none
    return None if inside[-1 - j] else inside.size - 1 - j


def settling_sample(y: np.ndarray, center: float, band: float, *, dwell: float = 0.0,
                    scratch: np.ndarray | None = None) -> int | None:
    """Index of the sample from which ``y`` stays within ``|y - center| <= band`` to its end, or None:
    did not settle (its last sample outside, or fewer than ``dwell`` x ``y.size`` samples inside at the end).

    Parameters
    ----------
    y : ndarray, shape (n,)
        The samples from the step on (NaN counts as outside).
    center, band : float
        Centre and half-width of the band.
    dwell : float
        Fraction of the samples, in [0, 1), that must lie within the band at the end: settled only if
        the last ``n - int((1 - dwell) n)`` samples are (at least one).
    scratch : ndarray, shape (>= n,), optional
        As :func:`last_outside`.

    Examples
    --------
    >>> y = np.array([3.0, 2.0, 0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0])
    >>> settling_sample(y, 0.0, 1.0), settling_sample(y, 0.0, 1.0, dwell=0.5)
    (2, 2)
    >>> settling_sample(y, 0.0, 1.0, dwell=0.9) is None                 # inside for 8 of the 9 it needs
    True
    >>> settling_sample(np.array([1.0, 0.0, 2.0]), 0.0, 0.5) is None    # ends outside: did not settle
    True
    """
    last = last_outside(y, center, band, scratch=scratch)
    first_inside = 0 if last is None else last + 1
    n = y.size
    tail = int((1.0 - dwell) * n)  # the first sample of the window that must be inside (the steady-state window)
    if first_inside >= n or first_inside > tail:
        return None
    return first_inside


def step_metrics(t, y, *, t_step: float, y0: float, y1: float, settle_band: float, dwell: float = 0.0,
                 scratch: np.ndarray | None = None) -> dict:
    """Overshoot, rise time, settling time and peak time of a step from ``y0`` to ``y1`` at ``t_step``.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s], strictly increasing.
    y : array_like, shape (n,)
        Response (for a positioning step the plant displacement [m]); NaN marks lost samples.
        Only the samples from ``t_step`` on (``t >= t_step`` up to half a sample period) count;
        pass the trace up to the end of the hold.
    t_step : float
        Time of the step [s]; the times below are measured from it.
    y0, y1 : float
        Value before and after the step (``y1 != y0``); steps down are handled by symmetry.
    settle_band : float
        Half-width of the settling band around ``y1``, in the units of ``y`` (absolute, > 0).
    dwell : float
        Fraction in [0, 1) of the samples from ``t_step`` on that must be within the band at the end
        (:func:`settling_sample`; the simulator's 0.1); 0 (default): the last sample, as python-control's
        ``step_info``.
    scratch : ndarray, shape (>= n,), optional
        A float buffer for the intermediate arrays (neither ``t`` nor ``y``): a caller that
        measures many traces spares the allocations (and on Linux the page faults of fresh
        memory, which cost more than the arithmetic here).

    Returns
    -------
    dict
        ``overshoot`` : float -- largest excursion beyond ``y1`` in the step direction, as a
        fraction of ``|y1 - y0|`` (0 if none);
        ``rise_time`` : float or None -- time from 10 % to 90 % of the step [s], each crossing
        interpolated linearly between samples (None if 90 % is never reached);
        ``settling_time`` : float or None -- as in the simulator, see the module notes [s]
        (None: did not settle);
        ``peak_time`` : float -- time of the largest value in the step direction [s].

    Raises
    ------
    ValueError
        Shapes differ, fewer than 2 samples, ``t`` not increasing, no sample at or after
        ``t_step``, ``y1 == y0``, ``settle_band <= 0``.
    TypeError
        A scalar argument is not a real number.

    Examples
    --------
    >>> t = np.arange(6) * 0.1
    >>> m = step_metrics(t, [0, 0.5, 1.2, 1.05, 1.0, 1.0], t_step=0.0, y0=0, y1=1, settle_band=0.1)
    >>> {key: round(value, 4) for key, value in m.items()}  # 10 % at 0.02 s, 90 % at 0.1571 s
    {'overshoot': 0.2, 'rise_time': 0.1371, 'settling_time': 0.3, 'peak_time': 0.2}
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or y.shape != t.shape:
        raise ValueError(f"t, y: expected two 1-D arrays of one length, found shapes {t.shape} and {y.shape}")
    if t.size < 2:
        raise ValueError(f"t: expected at least 2 samples, found {t.size}")
    if scratch is None or scratch.size < t.size or scratch.dtype != np.float64:
        scratch = np.empty(t.size)
    dt = np.subtract(t[1:], t[:-1], out=scratch[:t.size - 1])  # np.diff(t)
    if not np.all(dt > 0):
        raise ValueError("t: expected strictly increasing sample times")
    t_step, y0, y1 = _finite("t_step", t_step), _finite("y0", y0), _finite("y1", y1)
    settle_band = _finite("settle_band", settle_band)
    if settle_band <= 0:
        raise ValueError(f"settle_band: expected a number > 0, found {settle_band!r}")
    dwell = _finite("dwell", dwell)
    if not 0.0 <= dwell < 1.0:
        raise ValueError(f"dwell: expected a fraction in [0, 1), found {dwell!r}")
    if y1 == y0:
        raise ValueError(f"y1: expected a value different from y0 = {y0!r} (a step of nonzero size)")
    first = int(np.searchsorted(t, t_step - 0.5 * float(dt.min()), side="left"))  # t increases: a suffix
    if first == t.size:
        raise ValueError(f"t_step: expected a time within the trace (last sample at {t[-1]!r}), found {t_step!r}")
    ts, ys = t[first:], y[first:]
    r = scratch[:ys.size]
    np.divide(np.subtract(ys, y0, out=r), y1 - y0, out=r)  # normalized response: 0 before, 1 after the step
    t10 = _crossing(ts, r, RISE_LIMITS[0])
    t90 = _crossing(ts, r, RISE_LIMITS[1])
    r[np.isnan(r)] = -np.inf  # r_peak: a lost sample is no peak
    i_peak = int(np.argmax(r))
    overshoot = max(0.0, float(r[i_peak]) - 1.0)
    settled = settling_sample(ys, y1, settle_band, dwell=dwell, scratch=scratch)
    settling = None if settled is None else (0.0 if settled == 0 else float(ts[settled] - t_step))
    return {
        "overshoot": overshoot,
        "rise_time": None if t10 is None or t90 is None else t90 - t10,
        "settling_time": settling,
        "peak_time": float(ts[i_peak] - t_step),
    }
