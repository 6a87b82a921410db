"""The log's timing, found from the data: input timing (as logged / held) and the position's delay.

A drive's log pairs each input sample with a position sample, but not always at the same instant:

* the input may be a sampled controller's output, **held** until the next sample (a zero-order hold),
  so that the second difference of the position at ``n`` answers to ``(u[n-1] + u[n]) / 2``; or a
  signal logged **as** it acted (the EMPS benchmark's reading);
* the position may be read ``d`` samples **late** (an encoder read one cycle late, a fieldbus
  frame): the position logged at ``n`` is the axis's position at ``n - d``, and pairs with the input
  logged at ``n - d``.

Each candidate ``(timing, d)`` changes only the force column of the inverse model
``u = m a + sigma v + Cf sign(v) + offset``: the rows (from the position) are the same for all of
them when the position is cut by the largest delay tried. Two criteria rank the candidates on those
rows (filtered an octave below the fit's cut-off, rows near reversals left out): the equation-error
residual of the least-squares fit, and the output error of the same model integrated over short
segments from their own starts (the position's noise is in its output only, so a closed loop that feeds
it back into the force does not rank the candidates). Each gives a BIC difference to its best over the
effective rows (``n_eff ln(RSS_i / RSS_best)``, ``n_eff`` the rows over the residual's correlation time,
as in the Stribeck selection of :mod:`obsdesign.data.estimate`). A candidate is rejected when every
criterion puts it more than :data:`TIMING_MARGIN` above its best; of the others the simplest is kept
(the smallest delay, as logged before held), and the note says whether the data resolved it.

Examples
--------
A rigid mass under a held force, its position logged two samples late:

>>> import numpy as np
>>> rng = np.random.default_rng(1)
>>> dt, m = 1e-3, 0.5
>>> u = np.repeat(rng.normal(0.0, 1.0, 600), 20)           # held steps of 20 ms
>>> v = np.concatenate([[0.0], np.cumsum(u) * dt / m])       # exact under the hold
>>> x = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1])) * dt])[:-1]
>>> x_log = np.concatenate([np.zeros(2), x[:-2]]) + rng.normal(0.0, 1e-9, x.size)
>>> found = find_timing(x_log, u, dt=dt, filter_hz=100.0, decimation=10)
>>> found.timing, found.delay
('hold', 2)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .choices import INPUT_TIMINGS, MAX_DELAY, MAX_GIVEN_DELAY
from .trace import REVERSAL_THRESHOLD
from .uncertainty import correlation_time

__all__ = ["find_timing", "check_delay", "Timing", "MAX_DELAY", "TIMING_MARGIN", "held", "aligned", "describe"]

#: The BIC decrease another candidate must bring over the plain reading (as logged, no delay): that of the
#: Stribeck selection (:data:`obsdesign.data.estimate.BIC_MARGIN`).
TIMING_MARGIN = 10.0
#: The ranking's low-pass cut-off as a fraction of the fit's: an octave below it, where the signal stands
#: clear of the position noise. With the fit's own cut-off a closed-loop record with noise fed back (the force
#: answers to the noise the acceleration column carries) chose a 2-sample delay that was not there, with BIC
#: +53 over the truth; an octave lower the same records do not resolve a delay (the plain reading is kept),
#: while simulated held or delayed logs still do (by 29 to 1600).
RANKING_CUTOFF = 0.5
#: Rows within this many periods of the cut-off of a reversal are left out of the ranking.
REVERSAL_REACH = 8.0
#: Length of the output-error segments, in periods of the ranking's cut-off.
SEGMENT_PERIODS = 4.0
#: The order of the zero-phase Butterworth low-pass (that of identify).
_ORDER = 4


@dataclass(frozen=True)
class Timing:
    """The timing :func:`find_timing` chose and the evidence.

    Attributes
    ----------
    timing : str
        ``'sample'`` (as logged) or ``'hold'``.
    delay : int
        Samples the position is logged late.
    note : str
        One sentence: what was chosen, how, and how sure.
    evidence : dict
        ``'timing/delay' -> BIC difference`` to the best candidate (0 for the best).
    resolved : bool
        Whether the chosen candidate beats every other by more than :data:`TIMING_MARGIN`.
    given : str
        Which of the two was given rather than found: ``''``, ``'timing'``, ``'delay'`` or ``'both'``.
    candidates : tuple of (str, int)
        The readings the data do not reject (within :data:`TIMING_MARGIN` of the best by some criterion), the
        chosen one first; only it when resolved or given.
    """

    timing: str
    delay: int
    note: str
    evidence: dict = field(default_factory=dict)
    resolved: bool = False
    given: str = ""
    candidates: tuple = ()


def describe(timing: str, delay: int) -> str:
    """``'held input, position 1 sample late'`` and the like.

    Parameters
    ----------
    timing : {'sample', 'hold'}
    delay : int
        Samples the position is late.

    >>> describe("sample", 0), describe("hold", 2)
    ('input as logged, no delay', 'held input, position 2 samples late')
    """
    head = "held input" if timing == "hold" else "input as logged"
    tail = "no delay" if delay == 0 else f"position {delay} sample{'s' if delay != 1 else ''} late"
    return f"{head}, {tail}"


def held(force: np.ndarray) -> np.ndarray:
    """The force a held input gives the second difference at ``n``: ``(u[n-1] + u[n]) / 2`` (first sample kept).

    Parameters
    ----------
    force : ndarray

    >>> held(np.array([0.0, 2.0, 4.0])).tolist()
    [0.0, 1.0, 3.0]
    """
    return np.concatenate([force[:1], 0.5 * (force[1:] + force[:-1])])


def aligned(position: np.ndarray, force: np.ndarray, timing: str, delay: int) -> tuple[np.ndarray, np.ndarray]:
    """Position and force paired at the same instant: ``position[n + d]`` with the (held) ``force[n]``.

    Parameters
    ----------
    position, force : ndarray
        The logged columns.
    timing : {'sample', 'hold'}
    delay : int
        Samples the position is late.

    >>> aligned(np.arange(5.0), np.arange(5.0) * 10, "sample", 2)
    (array([2., 3., 4.]), array([ 0., 10., 20.]))
    """
    f = held(force) if timing == "hold" else force
    n = position.size
    return position[delay:], f[:n - delay]


def _scores(resid: dict) -> dict:
    """``n_eff ln(RSS_k / RSS_best)`` of each candidate, ``n_eff`` the best's rows over its correlation time."""
    rss = {k: float(r @ r) for k, r in resid.items()}
    best = min(rss, key=rss.get)
    if not math.isfinite(rss[best]):
        return {k: 0.0 for k in rss}
    n_eff = resid[best].size / correlation_time(resid[best])
    floor = max(rss[best], 1e-300)
    return {k: n_eff * math.log(max(r, 1e-300) / floor) if math.isfinite(r) else math.inf for k, r in rss.items()}


def _segments(v: np.ndarray, keep: slice, near: np.ndarray, length: int) -> np.ndarray | None:
    """Start indices of the output-error segments: ``length`` samples inside ``keep``, away from reversals."""
    starts = np.arange(keep.start, keep.stop - length, length)
    clear = np.array([not near[s:s + length].any() for s in starts], dtype=bool)
    starts = starts[clear] if starts.size else starts
    return np.stack([starts, np.full(starts.size, length)]) if starts.size >= 8 else None


def _output_error(x: np.ndarray, v: np.ndarray, force: np.ndarray, theta: np.ndarray, dt: float, timing: str,
                  seg: np.ndarray) -> np.ndarray:
    """Position residual of the rigid-axis model over short segments, each from its own start.

    The model ``m a = u - sigma v - Cf sign(v) - offset`` (``theta``) is integrated over each segment
    from the filtered velocity at its start, under the force held over each sample (``hold``) or
    varying linearly between samples (``sample``); the segment's own position offset and a velocity error
    (a ramp) are projected out. The logged position's noise is in the output only, not in the input:
    a closed loop's feedback of that noise does not rank the candidates, as it does the equation error.
    """
    m, sigma, Cf, offset = theta
    if not m > 0:
        return np.full(seg.shape[1] * (seg[1, 0] - 2), np.inf)
    starts, length = seg[0], int(seg[1, 0])
    idx = starts[:, None] + np.arange(length)[None, :]
    u = force[idx]
    xs = np.zeros(idx.shape)
    vel = v[starts].copy()
    pos = np.zeros(starts.size)
    for k in range(length - 1):
        xs[:, k] = pos
        acc = (u[:, k] - sigma * vel - Cf * np.sign(vel) - offset) / m
        if timing == "hold":
            pos = pos + dt * vel + 0.5 * dt**2 * acc
            vel = vel + dt * acc
        else:
            nxt = (u[:, k + 1] - sigma * vel - Cf * np.sign(vel) - offset) / m
            pos = pos + dt * vel + dt**2 * (2.0 * acc + nxt) / 6.0
            vel = vel + 0.5 * dt * (acc + nxt)
    xs[:, -1] = pos
    r = x[idx] - xs
    t = np.arange(length) * dt
    basis = np.stack([np.ones(length), t - t.mean()], axis=1)
    q, _ = np.linalg.qr(basis)
    r = r - (r @ q) @ q.T
    return r.ravel()


def check_delay(delay: int, value: int) -> int:
    """``value`` (the checked integer ``delay``) if at most :data:`~obsdesign.data.choices.MAX_GIVEN_DELAY`.

    Parameters
    ----------
    delay : int
        The delay as given (for the message).
    value : int
        The delay as an integer >= 0.

    Examples
    --------
    >>> check_delay(2, 2)
    2
    """
    if value > MAX_GIVEN_DELAY:
        raise ValueError(f"delay_samples: expected an integer from 0 to {MAX_GIVEN_DELAY}, found {delay!r}")
    return value


def find_timing(position: np.ndarray, force: np.ndarray, *, dt: float, filter_hz: float, decimation: int,
                timing: str | None = None, delay: int | None = None, min_speed: float | None = None,
                max_delay: int = MAX_DELAY) -> Timing:
    """Choose the input timing and the position delay by the equation-error residual (module docstring).

    Parameters
    ----------
    position, force : ndarray
        The logged position and the force [SI], same length.
    dt : float
        Sample time [s].
    filter_hz : float
        Cut-off of the zero-phase Butterworth low-pass of the fit; the ranking filters at
        :data:`RANKING_CUTOFF` times it.
    decimation : int
        Decimation factor of the fit's rows; the ranking's is ``decimation / RANKING_CUTOFF``.
    timing : {'sample', 'hold'}, optional
        Given: only the delay is found.
    delay : int, optional
        Given: only the timing is found.
    min_speed : float, optional
        Rows at or below this speed are left out (default 1 % of the peak, as in identify).
    max_delay : int
        The largest delay tried.

    Returns
    -------
    Timing
    """
    from scipy import signal

    timings = INPUT_TIMINGS[1:] if timing is None else (timing,)
    delays = tuple(range(max_delay + 1)) if delay is None else (int(delay),)
    given = {(True, True): "both", (True, False): "timing", (False, True): "delay", (False, False): ""}[
        (timing is not None, delay is not None)]
    if len(timings) * len(delays) == 1:
        return Timing(timings[0], delays[0], f"{describe(timings[0], delays[0])} (given)", {}, False, given,
                      ((timings[0], delays[0]),))
    top = max(delays)
    n = position.size
    fs = 1.0 / dt
    filter_hz = RANKING_CUTOFF * filter_hz
    decimation = max(1, int(round(decimation / RANKING_CUTOFF)))
    x = position[top:]
    sos = signal.butter(_ORDER, filter_hz, fs=fs, output="sos")
    x_f = signal.sosfiltfilt(sos, x)
    v = np.gradient(x_f, dt)
    a = np.empty_like(x_f)
    a[1:-1] = (x_f[2:] - 2.0 * x_f[1:-1] + x_f[:-2]) / dt**2
    a[0], a[-1] = a[1], a[-2]
    border = int(math.ceil(5.0 * fs / filter_hz))
    keep = slice(border, x.size - border)
    q = decimation
    dec_sos = signal.cheby1(8, 0.05, 0.8 / q, output="sos") if q > 1 else None

    def dec(col):
        return signal.sosfiltfilt(dec_sos, col, axis=-1)[..., ::q] if q > 1 else col

    X = dec(np.stack([a, v, np.sign(v), np.ones_like(v)])[:, keep])
    peak = float(np.max(np.abs(X[1])))
    threshold = REVERSAL_THRESHOLD * peak if min_speed is None else min_speed
    # away from reversals: there the friction follows the position (pre-sliding), not sign(v), and that
    # misfit, not the timing, would rank the candidates
    flips = np.flatnonzero(np.diff(np.sign(v)) != 0)
    near = np.zeros(v.size, dtype=bool)
    reach = int(math.ceil(REVERSAL_REACH * fs / filter_hz))
    for i in flips:
        near[max(i - reach, 0):i + reach + 1] = True
    moving = (np.abs(X[1]) > threshold) & ~near[keep][::q]
    if np.count_nonzero(moving) < 20:
        moving = np.abs(X[1]) > threshold
    X = X[:, moving].T
    scale = np.max(np.abs(X), axis=0)
    scale[scale == 0] = 1.0
    pinv = np.linalg.pinv(X / scale)
    seg = _segments(v, keep, near, int(math.ceil(SEGMENT_PERIODS * fs / filter_hz)))
    errors: dict[str, dict] = {"equation error": {}, "output error": {}}
    for tm in timings:
        f = held(force) if tm == "hold" else force
        for d in delays:
            y = dec(signal.sosfiltfilt(sos, f[top - d:n - d])[keep])[moving]
            theta = (pinv @ y) / scale
            errors["equation error"][(tm, d)] = y - X @ theta
            if seg is not None:  # else too few segments away from reversals: the equation error alone ranks
                errors["output error"][(tm, d)] = _output_error(x, v, force[top - d:n - d], theta, dt, tm, seg)
    scores = {how: _scores(res) for how, res in errors.items() if res}
    # a candidate is rejected when every criterion puts it more than the margin above its best
    score = {k: min(sc[k] for sc in scores.values()) for k in errors["equation error"]}
    ranked = sorted(score, key=score.get)
    # the simplest candidate the data do not reject: the smallest delay, as logged before held
    close = sorted((k for k in ranked if score[k] <= TIMING_MARGIN), key=lambda k: (k[1], INPUT_TIMINGS.index(k[0])))
    chosen = close[0]
    resolved = len(close) == 1
    evidence = {f"{k[0]}/{k[1]}": round(score[k], 1) for k in ranked}
    how = (f"{' and '.join(scores)} over {len(score)} candidates; a candidate is rejected when each puts it more than "
           f"BIC {TIMING_MARGIN:g} above its best")
    if resolved:
        runner = min((k for k in ranked if k != chosen), key=score.get)
        note = (f"{describe(*chosen)}: found ({how}; the next, {describe(*runner)}, is +"
                + ", +".join(f"{sc[runner]:.1f}" for sc in scores.values()) + ")")
    else:
        others = ", ".join(f"{k[0]}/{k[1]}" for k in close[1:])
        note = (f"{describe(*chosen)}: not resolved by the data, the simplest of {len(close)} candidates not rejected "
                f"({how}; also {others}); give --input-timing and --delay-samples if the drive's timing is known")
    if given:
        note += f"; {'input timing' if given == 'timing' else 'delay'} given"
    return Timing(chosen[0], chosen[1], note, evidence, resolved, given, tuple(close))
