"""The fit of :func:`obsdesign.data.identify` on a log read under one timing, and the spread over the timings
the data do not tell apart.

:func:`fit_aligned` runs the filtered, differentiated and decimated rows and the fit of
:mod:`obsdesign.data.stribeck_rows` on position and force paired by :func:`obsdesign.data.timing.aligned`.
:func:`timing_spread` fits again under each other reading of the log's timing (input as logged or held, the
position's delay) that :func:`~obsdesign.data.timing.find_timing` did not reject, the model's structure and rows
as chosen, and widens each 95 % interval by the change of its estimate
(:func:`obsdesign.data.estimate.widened`, the model-error shifts' rule): the union of the chosen interval and
the chosen interval moved to each competing estimate. A log whose timing is resolved keeps its intervals.
On a simulated 4 kHz rotary axis run on the plan of ``obsdesign experiment`` (constant speeds and ramps, held
current, position one sample late: all eight readings within BIC 0.2), the reading kept (as logged, no delay)
gave sigma -1.9 % and Cf +0.24 % with intervals that missed the truth; the held, one-sample-late reading moves
them onto it, and the widened intervals hold it.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from ._idim import quantization, second_difference
from ._ident_rows import FILTER_ORDER
from .estimate import MODEL_SHIFT_FACTOR, STRIBECK_INTERVAL, widened
from .presliding import fit_presliding
from .stribeck_rows import fit_rows, row_maker, stribeck_floor
from .timing import aligned
from .trace import REVERSAL_THRESHOLD
from .uncertainty import column_noise, white_variance

__all__ = ["fit_aligned", "timing_spread", "settled_rows", "presliding_scale", "past_presliding", "presliding_notice",
           "interval_method", "TIMING_SHIFTED"]

#: The parameters whose intervals the competing timings widen (those the shift is reported for).
TIMING_SHIFTED = ("m", "sigma", "Cf", "offset", "sigma_pos", "sigma_neg", "Cf_pos", "Cf_neg", "Fs", "vs")


def fit_aligned(position: np.ndarray, force: np.ndarray, *, dt: float, filter_hz: float, q: int, model: str,
                stribeck: str, fix: dict, bounds: dict, min_speed: float | None, stribeck_min_speed: float | None,
                n_boot: int, seed: int, speed: str, travel_floor: float = 0.0) -> dict:
    """The rows and the fit of :func:`obsdesign.data.identify` on aligned position and force.

    Parameters
    ----------
    position, force : ndarray
        Paired at the same instant (:func:`~obsdesign.data.timing.aligned`).
    dt, filter_hz, q :
        Sample time [s], cut-off [Hz], decimation factor.
    model, stribeck, fix, bounds, min_speed, stribeck_min_speed, n_boot, seed :
        As for :func:`~obsdesign.data.identify` (checked).
    speed : str
        The speed's unit (messages).
    travel_floor : float
        Rows within this travel of the last velocity reversal are left out [m, rad] (:func:`settled_rows`; 0:
        none).

    Returns
    -------
    dict
        The keys of :data:`~obsdesign.data.stribeck_rows.FITTED` and ``base_threshold`` (the rows' min speed
        without the Stribeck rows), ``floor`` (the Stribeck rows' min speed), ``x_f, v, a, u_f`` (filtered, full
        rate), ``keep`` (the slice past the filter's transients), ``white`` (mean square of the position less its
        low-pass), ``quantum`` (the encoder step), ``noise_var`` (of the ``a`` and ``v`` columns) and
        ``noise_rms`` (the position's white noise less the encoder's share, :func:`noise_rms`).
    """
    from scipy import signal

    n = position.size
    fs = 1.0 / dt
    border = int(math.ceil(5.0 * fs / filter_hz))
    sos = signal.butter(FILTER_ORDER, filter_hz, fs=fs, output="sos")
    x_f = signal.sosfiltfilt(sos, position)
    u_f = signal.sosfiltfilt(sos, force)
    v = np.gradient(x_f, dt)
    a = second_difference(x_f, dt)
    keep = slice(border, n - border)

    dec_sos = signal.cheby1(8, 0.05, 0.8 / q, output="sos") if q > 1 else None

    def dec(col: np.ndarray) -> np.ndarray:  # scipy.signal.decimate(col, q, ftype="iir", zero_phase=True), rows at once
        return signal.sosfiltfilt(dec_sos, col, axis=-1)[..., ::q] if q > 1 else col

    pos, neg = (v > 0).astype(float), (v < 0).astype(float)
    names = ("a", "v", "sign", "one", "v_pos", "v_neg", "pos", "neg", "y")
    stacked = dict(zip(names, dec(np.stack([a, v, np.sign(v), np.ones(n), v * pos, v * neg, pos, neg, u_f])[:, keep])))
    peak = float(np.max(np.abs(stacked["v"])))
    threshold = REVERSAL_THRESHOLD * peak if min_speed is None else min_speed
    moving = np.count_nonzero(np.abs(stacked["v"]) > threshold)
    if moving < 10:
        raise ValueError(f"trace: expected motion in at least 10 rows of the fit, found {moving} (|v| > "
                         f"{threshold:.3g} {speed}; the position barely changes, or min_speed is too high)")
    quantum = quantization(position)
    white = float(np.mean((position - x_f)[keep] ** 2))
    noise_var = column_noise(white, sos, dec_sos, q, dt)
    floor, rule = stribeck_floor(threshold=threshold, min_speed=min_speed, stribeck_min_speed=stribeck_min_speed,
                                 stribeck=stribeck, white=white, sos=sos, dt=dt, q=q, quantum=quantum,
                                 filter_hz=filter_hz, speed=speed)
    settled = settled_rows(x_f, v, travel_floor, lambda c: dec(signal.sosfiltfilt(sos, c)[keep]))
    if settled is not None:
        left = np.count_nonzero(settled & (np.abs(stacked["v"]) > threshold))
        if left < MIN_SETTLED_ROWS:
            raise ValueError(f"{left} rows are left, expected at least {MIN_SETTLED_ROWS}")
    fitted = fit_rows(row_maker(stacked, v[keep], dec, settled), threshold=threshold, floor=floor, floor_rule=rule,
                      peak=peak, speed=speed, model=model, stribeck=stribeck, fix=fix, bounds=bounds,
                      noise_var=noise_var, n_boot=n_boot, seed=seed)
    return dict(fitted, base_threshold=threshold, floor=floor, x_f=x_f, v=v, a=a, u_f=u_f, keep=keep, white=white,
                quantum=quantum, noise_var=noise_var, noise_rms=noise_rms(white, quantum, sos, q))


#: Rows a fit without the pre-sliding rows needs (:func:`settled_rows`); fewer, and identify keeps them.
MIN_SETTLED_ROWS = 20
#: A decimated row is within the pre-sliding travel when the decimated indicator of its samples exceeds this.
NEAR_SHARE = 0.02


def settled_rows(x_f: np.ndarray, v: np.ndarray, travel_floor: float, rows: Callable) -> np.ndarray | None:
    """Which decimated rows are at least ``travel_floor`` of travel past the last velocity reversal.

    After a reversal the friction is in pre-sliding until the axis has travelled ``1/s`` (the paper's map,
    eq:2:3:3-2:3:4; LuGre's bristles a few ``Cf/sigma0``): there it is below the Coulomb level the gross-sliding
    model assumes, at speeds above any min speed on a fast reversal. Every sign change of ``v`` counts (a slow
    reversal turns the friction too; at a standstill the travel is small and the rows are below the min speed
    anyway). The indicator of the samples within the floor is low-passed and decimated like the force
    (``rows``); a row where it exceeds :data:`NEAR_SHARE` is left out.

    Parameters
    ----------
    x_f, v : ndarray
        Filtered position and its velocity, full rate.
    travel_floor : float
        The travel [m, rad]; 0 or less: every row (``None``).
    rows : callable
        A full-rate column to the fit's rows (the low-pass, the transients cut, the decimation).

    Returns
    -------
    ndarray of bool or None
        Per decimated row, True where it may be used; ``None`` when ``travel_floor`` is 0.

    Examples
    --------
    >>> t = np.arange(4000) * 1e-3
    >>> x = 0.01 * np.sin(2 * np.pi * t)           # reversals at 0.25, 0.75, ... s
    >>> ok = settled_rows(x, np.gradient(x, 1e-3), 1e-3, lambda c: c)
    >>> bool(ok[300]), bool(ok[500]), round(float(np.mean(ok)), 2)   # 1 mm of 20 mm: cos(phi) = 0.9
    (False, True, 0.86)
    """
    if not travel_floor > 0.0:
        return None
    moving = np.flatnonzero(v != 0.0)
    sign = np.sign(v[moving])
    revs = moving[1:][sign[1:] != sign[:-1]]   # every sign change (zeros skipped): a slow one turns the friction too
    last = np.full(v.size, -1)
    last[revs] = revs
    last = np.maximum.accumulate(last)
    near = (last >= 0) & (np.abs(x_f - x_f[np.maximum(last, 0)]) < travel_floor)
    return np.abs(rows(near.astype(float))) <= NEAR_SHARE


def presliding_scale(fitted: dict, position: np.ndarray, *, dt: float, rows: int, window: float,
                     length_unit: str) -> tuple[float | None, str]:
    """``s`` and its note (:func:`~obsdesign.data.presliding.fit_presliding`) from :func:`fit_aligned`'s result.

    ``position``: the aligned position the fit was made on; ``rows``: the samples a row of the dwell
    test stands for; ``window``: the pre-sliding window; ``length_unit``: the note's.
    """
    keep, x_f, v, a, u_f = (fitted[k] for k in ("keep", "x_f", "v", "a", "u_f"))
    values = fitted["est"]["values"]
    return fit_presliding(x=position[keep], x_f=x_f[keep], v=v[keep], a=a[keep], u_f=u_f[keep], dt=dt,
                          m=float(values["m"]), sigma=float(values["sigma"]), Cf=float(values["Cf"]),
                          offset=float(values["offset"]), rows=rows, window=window, length_unit=length_unit)


def past_presliding(fitted: dict, position: np.ndarray, *, dt: float, rows: int, window: float,
                    steps: int, travel: float, length_unit: str,
                    refit: Callable[..., dict]) -> tuple[dict, float | None, str, float, dict]:
    """The fit again without the rows within ``travel / s`` past each reversal (:func:`settled_rows`).

    ``s`` comes from the dwell test in ``window`` (:func:`presliding_scale`); where no reversal dwells there, the
    floor alone comes from ``10^k window``, ``0 < k < steps`` (a fast reversal reads the filter's smear of the
    Coulomb jump as a pre-sliding scale: 7.5e5 1/m on a noise-free record with none, harmless as a floor of
    1.3 um, not a scale to design with, so ``s`` stays ``None``). A floor that leaves too few rows keeps them.
    Where no scale is found at all, the rows within ``window`` (the travel still called pre-sliding) are left out
    of a point fit only (``refit(window, n_boot=0, ...)``, the model's structure and rows as chosen), and the
    change of each estimate is returned: the caller widens the intervals by it
    (:func:`~obsdesign.data.estimate.widened`). Measured on the closed-loop staircase
    of ``obsdesign experiment`` (docs/experiment.md): the rows within 0.1 mm of its reversals, 27 of 839, moved
    the mass from -9.7 % to +0.6 % and the Coulomb level from -1.1 % to -0.07 % of the truth; the intervals with
    them missed the Coulomb level. EMPS keeps its estimates and its intervals grow (Cf +1.8 %).

    Returns
    -------
    fitted, s, s_note, travel_floor, shift
        ``refit(floor)``'s result (or ``fitted``), the reported ``s`` and its note, the floor used (0: none),
        and ``name -> change`` without the rows within ``window`` (empty where a floor is used or none is left).
    """
    s, note = presliding_scale(fitted, position, dt=dt, rows=rows, window=window, length_unit=length_unit)
    scale, wide = s, ""
    for k in range(1, steps if s is None else 1):
        scale, _ = presliding_scale(fitted, position, dt=dt, rows=rows, window=window * 10.0**k,
                                    length_unit=length_unit)
        if scale is not None:
            wide = (f"; the rows within 1/s = {1.0 / scale:.3g} {length_unit} of each reversal are left out all the same "
                    f"(s of the reversals in {window * 10.0**k:g} {length_unit}, no scale to design with)")
            break
    if not travel > 0.0:
        return fitted, s, note, 0.0, {}
    if scale is None:
        try:
            alt = refit(window, n_boot=0, stribeck="on" if fitted["est"]["stribeck"] else "off",
                        min_speed=fitted["base_threshold"], stribeck_min_speed=fitted["floor"])["est"]["values"]
        except ValueError:
            return fitted, s, note, 0.0, {}
        values = fitted["est"]["values"]
        return fitted, s, note, 0.0, {k: float(alt[k] - values[k]) for k in values if k in TIMING_SHIFTED and k in alt}
    try:
        return refit(travel / scale), s, note + wide, travel / scale, {}
    except ValueError as exc:  # the first fit ran on the same columns: only the rows can be missing
        return fitted, s, note + f"; the fit keeps the rows within 1/s of the reversals: without them {exc}", 0.0, {}


def presliding_notice(shift: dict, est: dict, window: float, length_unit: str, unit: Callable[[str], str]) -> str:
    """One line: the intervals widened by the change without the rows near the reversals (:func:`past_presliding`),
    naming the changes beyond two standard errors and 0.1 % of the estimate (``est``: ``values``, ``std``; an
    exact synthetic log moved its Coulomb level by 0.02 %, beyond its standard error); else empty."""
    values = est["values"]
    moved = ", ".join(f"{k} {_percent(v, values[k], unit(k.split('_')[0]))}" for k, v in shift.items()
                      if abs(v) > max(2.0 * est["std"].get(k, 0.0), 1e-3 * abs(values[k])))
    return (f"s not resolved: without the rows within {window:g} {length_unit} of travel past each reversal (pre-sliding "
            f"there would bias the gross-sliding fit) the estimates move by {moved}; the 95 % intervals are widened "
            "to hold both fits") if moved else ""


def noise_rms(white: float, quantum: float, sos: np.ndarray, q: int) -> float:
    """The RMS of the position's white noise, less the encoder's share ``quantum^2 / 12`` [m or rad].

    ``white`` is the mean square of the position less its low-pass ``sos``: the noise above the cut-off only.
    Divided by the share of a white noise's variance the low-pass leaves
    (:func:`~obsdesign.data.uncertainty.white_variance`), it is the whole band's; the encoder's rounding
    (white, ``quantum^2 / 12``) is taken out of that. Without the division the estimate was the noise above
    the cut-off alone, 16 % low at a tenth of the sampling rate (2.50e-6 for 3e-6 rad on a simulated 4 kHz
    rotary axis).

    Parameters
    ----------
    white : float
        Mean square of the position minus its low-passed version.
    quantum : float
        Encoder step (0: not quantized).
    sos : ndarray
        The low-pass (``sosfiltfilt``).
    q : int
        Decimation factor (the length of the impulse responses).

    Examples
    --------
    >>> from scipy import signal
    >>> sos = signal.butter(4, 100.0, fs=1000.0, output="sos")
    >>> e = np.random.default_rng(0).normal(0.0, 2e-7, 200_000)
    >>> rest = e - signal.sosfiltfilt(sos, e)
    >>> round(noise_rms(float(np.mean(rest**2)), 0.0, sos, 10) / 2e-7, 2)
    1.0
    """
    return math.sqrt(max(0.0, white_variance(white, sos, q) - quantum**2 / 12.0))


def timing_spread(position: np.ndarray, force: np.ndarray, found, fitted: dict, intervals: dict, values: dict, *,
                  dt: float, filter_hz: float, q: int, model: str, fix: dict, bounds: dict, speed: str,
                  unit: Callable[[str], str], travel_floor: float = 0.0) -> tuple[dict, dict, str]:
    """Intervals widened to the fits under the timings the data do not reject (module docstring).

    Parameters
    ----------
    position, force : ndarray
        The logged columns (not aligned).
    found : Timing
        :func:`~obsdesign.data.timing.find_timing`'s result (its ``candidates``).
    fitted : dict
        :func:`fit_aligned`'s result under the chosen timing.
    intervals, values : dict
        Its intervals and estimates.
    dt, filter_hz, q, model, fix, bounds, speed, travel_floor :
        As for :func:`fit_aligned`.
    unit : callable
        A parameter's unit by name (:meth:`obsdesign.data.units.Units.si`), for a shift larger than its estimate.

    Returns
    -------
    intervals : dict
        Widened (unchanged when no other reading is left).
    shift : dict
        ``name -> (low, high)``: the most negative and most positive change of the estimate over the other
        readings (empty when none is left).
    note : str
        One line: which readings widened which intervals, by how much; empty when none is left.
    """
    others = [c for c in found.candidates if c != (found.timing, found.delay)]
    if not others:
        return intervals, {}, ""
    kept = fitted["est"]["stribeck"]
    moves: dict[str, list[float]] = {}
    failed = []
    for timing, delay in others:
        try:
            alt = fit_aligned(*aligned(position, force, timing, delay), dt=dt, filter_hz=filter_hz, q=q, model=model,
                              stribeck="on" if kept else "off", fix=fix, bounds=bounds,
                              min_speed=fitted["base_threshold"], stribeck_min_speed=fitted["floor"], n_boot=0, seed=0,
                              speed=speed, travel_floor=travel_floor)
        except ValueError:
            failed.append(f"{timing}/{delay}")
            continue
        for name in intervals:
            if name in TIMING_SHIFTED and name in alt["est"]["values"] and name not in fix:
                moves.setdefault(name, []).append(float(alt["est"]["values"][name] - values[name]))
    low = {k: min(0.0, min(s)) for k, s in moves.items()}
    high = {k: max(0.0, max(s)) for k, s in moves.items()}
    out = widened(widened(intervals, values, low), values, high)
    shift = {k: (low[k], high[k]) for k in moves}
    names = ", ".join(f"{k} {_percent(low[k], values[k], unit(k.split('_')[0]))} to "
                      f"{_percent(high[k], values[k], unit(k.split('_')[0]))}"
                      for k in moves)
    read = ", ".join(f"{t}/{d}" for t, d in others if f"{t}/{d}" not in failed)
    note = (f"timing not resolved: the 95 % intervals are widened to the fits under the {len(others) - len(failed)} "
            f"other reading{'s' if len(others) - len(failed) != 1 else ''} the data do not reject ({read}): {names}"
            + (f"; no fit under {', '.join(failed)}" if failed else ""))
    return out, shift, note


def _percent(shift: float, value: float, unit: str) -> str:
    """The shift relative to the estimate, or in its unit where it is larger than the estimate (an offset near 0)."""
    return f"{100.0 * shift / abs(value):+.2g} %" if 0.0 < abs(value) and abs(shift) <= abs(value) else f"{shift:+.3g} {unit}"


def interval_method(est: dict, n_boot: int, model_shift: dict, fix: dict, timing_shift: dict, pre_shift: dict) -> str:
    """How :func:`~obsdesign.data.identify` made its intervals, in words (its ``interval_method``)."""
    return ((f"moving-block bootstrap, {n_boot} replicates, blocks of {est['block_length']} rows, " if n_boot
             else "1.96 standard errors, ") + "widened by the errors-in-variables shift"
            + (f" and by the model-error shift ({MODEL_SHIFT_FACTOR:g} x the min speed)" if model_shift else "")
            + (" and by the shift without the rows near reversals (s not resolved)" if pre_shift else "")
            + (" and by the shift under the timings the data do not reject" if timing_shift else "")
            + (f"; {STRIBECK_INTERVAL}" if est["stribeck"] and n_boot and not {"Fs", "vs"} <= set(fix) else ""))
