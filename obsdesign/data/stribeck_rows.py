"""The rows of :func:`obsdesign.data.identify` and its Stribeck decision on them.

The Stribeck drop lives below ``vs``, which may be below the default min speed (1 % of the peak speed). The
decision (:func:`obsdesign.data.estimate.select_stribeck`) and a fit that keeps the term therefore look at the
rows down to the slowest speed the encoder and the noise make trustworthy
(:func:`~obsdesign.data.friction_fit.trusted_speed`); when the term is dropped the fit is the one on the rows
above the min speed, as without the slow rows. A kept ``vs`` below :data:`NEAR_FLOOR` times that speed whose
``Fs`` interval reaches ``Cf`` is not resolved (a LuGre axis without a drop bends its friction there after each
reversal): the term is then decided again on the rows above the min speed. With the term kept on the slow rows,
the change of ``m, sigma, Cf, offset`` without them (``Fs``, ``vs`` held) widens their intervals as a second
model-error shift.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from ._idim import positive_number
from .estimate import estimate, model_shift as _model_shift, select_stribeck, widened
from .friction_fit import trusted_speed
from .uncertainty import impulse_length, noise_variance, white_variance

__all__ = ["NEAR_FLOOR", "stribeck_floor", "row_maker", "fit_rows", "FITTED"]

#: The keys of :func:`fit_rows`'s result, in the order :func:`obsdesign.data.identify` unpacks them.
FITTED = ("est", "intervals", "model_shift", "cols", "y", "threshold")

#: A Stribeck speed below this many times the slowest trusted speed, with an Fs interval reaching Cf, is not
#: resolved (``auto``; decided again on the rows above the min speed): the rows there follow reversals, where
#: LuGre's bristle lag bends the friction like a small drop. Axes without a drop gave vs at 6 x that speed in 2
#: of 20 noise draws; true drops at 17 to 86 x it.
NEAR_FLOOR = 10.0


def stribeck_floor(*, threshold: float, min_speed: float | None, stribeck_min_speed: float | None, stribeck: str,
                   white: float, sos: np.ndarray, dt: float, q: int, quantum: float,
                   filter_hz: float, speed: str = "m/s") -> tuple[float, str]:
    """The threshold of the Stribeck rows and its rule (one phrase).

    Given (at most ``threshold``); the min speed when one was given or the term is off; else
    :func:`~obsdesign.data.friction_fit.trusted_speed` of the low-passed velocity's noise (white position noise of
    mean square ``white`` less the low-pass, through the low-pass ``sos`` and the derivative), at most ``threshold``.

    Parameters
    ----------
    threshold : float
        The rows' min speed.
    min_speed, stribeck_min_speed : float or None
        As given to :func:`obsdesign.data.identify`.
    stribeck : str
        The Stribeck choice.
    white : float
        Mean square of the position minus its low-passed version.
    sos : ndarray
        The low-pass (``sosfiltfilt``).
    dt : float
        Sample time [s].
    q : int
        Decimation factor.
    quantum : float
        Encoder step (0: not quantized).
    filter_hz : float
        The cut-off [Hz].
    speed : str
        The speed's unit (for the message of a bad ``stribeck_min_speed``).
    """
    from scipy import signal

    if stribeck_min_speed is not None:
        return min(positive_number("stribeck_min_speed", stribeck_min_speed, 0.0, speed), threshold), "given"
    if min_speed is not None or stribeck == "off":
        return threshold, "the min speed"
    eta2 = white_variance(white, sos, q)
    sigma_v = math.sqrt(eta2 * noise_variance(lambda h: np.gradient(signal.sosfiltfilt(sos, h), dt), impulse_length(q)))
    trusted, rule = trusted_speed(sigma_v, quantum, filter_hz)
    return min(trusted, threshold), f"trusted speed: {rule}" + ("" if trusted < threshold else ", at least the min speed")


def row_maker(stacked: dict, v_full: np.ndarray, dec: Callable,
              settled: np.ndarray | None = None) -> Callable[[float], tuple[dict, np.ndarray]]:
    """``rows_above(limit) -> (cols, y)``: the decimated columns of the rows with ``|v| > limit``.

    ``cols["shape"]`` computes the Stribeck columns at the full rate (``v_full``) and decimates them (``dec``)
    like the force.

    Parameters
    ----------
    stacked : dict
        The decimated columns and ``y`` (the force).
    v_full : ndarray
        The velocity at the full rate over the kept samples.
    dec : callable
        The decimation of a stack of columns.
    settled : ndarray of bool, optional
        Rows that may be used at all (past the pre-sliding travel, :func:`obsdesign.data._ident_fit.settled_rows`).
    """
    def rows_above(limit: float) -> tuple[dict, np.ndarray]:
        mask = np.abs(stacked["v"]) > limit
        if settled is not None:
            mask &= settled
        cols = {k: c[mask] for k, c in stacked.items() if k != "y"}

        def shape(vs: float, parts: tuple[str, ...]) -> dict:  # Stribeck columns at the full rate, decimated
            e = np.sign(v_full) * np.exp(-((v_full / vs) ** 2))
            full = {"S": e, "S_pos": e * (v_full > 0), "S_neg": e * (v_full < 0), "dS": e * 2.0 * v_full**2 / vs**3}
            wanted = ("S",) + parts
            return dict(zip(wanted, dec(np.stack([full[k] for k in wanted]))[:, mask]))

        cols["shape"] = shape
        return cols, stacked["y"][mask]

    return rows_above


def fit_rows(rows_above: Callable, *, threshold: float, floor: float, floor_rule: str, peak: float, speed: str,
             model: str, stribeck: str, fix: dict, bounds: dict, noise_var: dict, n_boot: int, seed: int) -> dict:
    """The decision and the fit of :func:`obsdesign.data.identify` (module docstring).

    Returns
    -------
    dict
        ``est`` (:func:`~obsdesign.data.estimate.estimate`'s result, its ``selection`` the decision in one
        line), ``intervals`` (widened by the model-error shifts), ``model_shift``, ``cols``, ``y`` (the rows of
        the fit) and ``threshold`` (their min speed).

    Parameters
    ----------
    rows_above : callable
        :func:`row_maker`'s.
    threshold, floor : float
        The min speed and the Stribeck rows' threshold.
    floor_rule : str
        How ``floor`` was found.
    peak : float
        The largest speed of the rows.
    speed : str
        The speed's unit.
    model, stribeck, fix, bounds, noise_var, n_boot, seed :
        As for :func:`~obsdesign.data.estimate.estimate`.
    """
    kw: dict[str, Any] = dict(model=model, fix=fix, bounds=bounds, noise_var=noise_var)
    cols, y = rows_above(threshold)
    vs_range = (max(threshold, 1e-12), max(0.5 * peak, 2.0 * max(threshold, 1e-12)))
    low_cols, low_y = (cols, y) if floor >= threshold else rows_above(floor)
    low_range = (max(floor, 1e-12), vs_range[1])
    kept, selection = select_stribeck(low_cols, low_y, stribeck=stribeck, fix=fix, bounds=bounds, vs_range=low_range)
    selection += f"; rows above {floor:.3g} {speed} ({low_y.size} rows; {floor_rule})" if floor < threshold else ""
    base_threshold, base_range = threshold, vs_range
    if kept:  # the fit with the term on the rows down to the trusted speed: the drop lives below vs
        cols, y, threshold, vs_range = low_cols, low_y, floor, low_range
    est = estimate(cols, y, stribeck="on" if kept else "off", vs_range=vs_range, n_boot=n_boot, seed=seed, **kw)
    if est["selection"].startswith(("Stribeck term fitted as asked", "Stribeck term not fitted")):
        est["selection"] = selection
    values = est["values"]
    shift = _model_shift(est, cols, y, threshold, vs_range=vs_range, **kw)
    intervals = widened(est["intervals"], values, shift)
    if est["stribeck"] and threshold < base_threshold:  # what the rows below the min speed moved: a second shift
        intervals = widened(intervals, values, _slow_rows_shift(est, rows_above(base_threshold), **kw))
    asked = stribeck == "on" or any(k in fix or k in bounds for k in ("Fs", "vs"))
    if (kept and not asked and "Fs" in intervals and intervals["Fs"][0] <= values["Cf"]
            and values["vs"] < NEAR_FLOOR * floor):
        # a drop the data do not resolve, near the slowest rows (on axes without one, a 1.08 Cf "drop" at 6 x the
        # trusted speed, where the bristles' lag after a reversal bends the friction): decided again on the rows
        # above the min speed alone
        lo_fs, hi_fs = intervals["Fs"]
        cols, y = rows_above(base_threshold)
        threshold, vs_range = base_threshold, base_range
        kept, again = select_stribeck(cols, y, stribeck=stribeck, fix=fix, bounds=bounds, vs_range=vs_range)
        selection = (f"Stribeck term not resolved on the rows down to {floor:.3g} {speed} (Fs = {values['Fs']:.4g}, "
                     f"95 % interval [{lo_fs:.4g}, {hi_fs:.4g}] reaching Cf = {values['Cf']:.4g}, vs = "
                     f"{values['vs']:.3g} within {NEAR_FLOOR:g} x that speed); on the rows above the min speed "
                     f"{base_threshold:.3g} {speed}: " + again)
        est = estimate(cols, y, stribeck="on" if kept else "off", vs_range=vs_range, n_boot=n_boot, seed=seed, **kw)
        est["selection"] = selection
        shift = _model_shift(est, cols, y, threshold, vs_range=vs_range, **kw)
        intervals = widened(est["intervals"], est["values"], shift)
    return dict(est=est, intervals=intervals, model_shift=shift, cols=cols, y=y, threshold=threshold)


def _slow_rows_shift(est: dict, rows: tuple, *, model: str, fix: dict, bounds: dict, noise_var: dict) -> dict:
    """The change of m, sigma, Cf, offset when the rows below the min speed (added for the Stribeck term) are left out.

    ``Fs`` and ``vs`` are held at their estimates (on the rows above the min speed a drop below it is not
    determined); a shift of the size of the interval says the slow rows pull the other parameters, by at least that.
    """
    cols, y = rows
    held = dict(fix, Fs=float(est["values"]["Fs"]), vs=float(est["values"]["vs"]))
    try:
        alt = estimate(cols, y, model=model, stribeck="on", fix=held, bounds=bounds, vs_range=(1e-12, 1.0),
                       noise_var=noise_var, n_boot=0, seed=0)
    except ValueError:
        return {}
    return {k: float(alt["values"][k] - est["values"][k]) for k in est["intervals"]
            if k in alt["values"] and k not in held}
