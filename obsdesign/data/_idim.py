"""Helpers of :func:`obsdesign.data.identify`: the IDIM-LS solve, the physical-sign check, the encoder step."""

from __future__ import annotations

import math

import numpy as np

from .._validate import MAX_BOOTSTRAP
from .trace import MIN_SAMPLES

__all__ = ["MAX_BOOTSTRAP", "check_int", "ols", "implausible", "quantization", "time_window", "positive_number", "second_difference"]


def second_difference(x: np.ndarray, dt: float) -> np.ndarray:
    """Acceleration ``(x[n+1] - 2 x[n] + x[n-1]) / dt^2`` (the two end samples repeat their neighbour).

    For a rigid mass under a zero-order-held force it is exact: ``m`` times it equals
    ``(u[n-1] + u[n]) / 2`` (``input_timing='hold'``). ``np.gradient`` applied twice is the same
    difference over ``2 dt``, i.e. this one smoothed by ``(1, 2, 1) / 4``, which the force is not:
    its gain ``(sin(w dt) / (w dt))^2`` against ``(sin(w dt/2) / (w dt/2))^2`` here under-reads the
    acceleration by ``(w dt)^2 / 4`` instead of ``(w dt)^2 / 12`` and biases the mass upwards.

    Parameters
    ----------
    x : ndarray
        Positions on a uniform grid (at least 3).
    dt : float
        Sample time.

    Examples
    --------
    >>> second_difference(np.array([0.0, 1.0, 4.0, 9.0, 16.0]), 1.0).tolist()
    [2.0, 2.0, 2.0, 2.0, 2.0]
    """
    a = np.empty_like(x, dtype=float)
    a[1:-1] = (x[2:] - 2.0 * x[1:-1] + x[:-2]) / dt**2
    a[0], a[-1] = a[1], a[-2]
    return a


def check_int(name: str, value: object, low: int, high: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low or (high and value > high):
        raise ValueError(f"{name}: expected an integer >= {low}{f' and <= {high}' if high else ''}, found {value!r}")
    return int(value)


def ols(X: np.ndarray, y: np.ndarray, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Estimates, covariance ``sigma_e^2 (X^T X)^-1``, residual, scaled condition number.

    The columns are scaled to a largest |value| of 1 before the solve, so LAPACK never sees an
    overflowing product (and never prints its own error text); a regressor that is non-finite,
    zero in every row or a combination of the others is refused naming it.
    """
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
        bad = [n for n, col in zip(names, X.T) if not np.all(np.isfinite(col))] or ["the force"]
        raise ValueError(f"trace: the regressor {', '.join(bad)} overflows to non-finite values (derivatives of the "
                         "position over the sample time); check the units of position and time")
    scale = np.max(np.abs(X), axis=0)
    zero = [n for n, sc in zip(names, scale) if not sc > 0]
    if zero:
        raise ValueError(f"trace: expected every regressor to vary, found {', '.join(zero)} zero in every row of "
                         "the fit: the record does not excite that term")
    Xs = X / scale
    y_scale = float(np.max(np.abs(y))) or 1.0
    theta_s, _, rank, _ = np.linalg.lstsq(Xs, y / y_scale, rcond=None)
    if rank < X.shape[1]:
        raise ValueError(f"trace: the regressors ({', '.join(names)}) are linearly dependent over the rows of the "
                         f"fit (rank {rank} of {X.shape[1]}): the record cannot separate these terms")
    theta = theta_s * y_scale / scale
    resid = y - X @ theta
    dof = X.shape[0] - X.shape[1]
    sigma2 = float(resid @ resid) / dof
    cov = sigma2 * np.linalg.inv(Xs.T @ Xs) / scale[:, None] / scale[None, :]  # no overflowing outer product
    cond = float(np.linalg.cond(Xs / np.linalg.norm(Xs, axis=0)))
    return theta, cov, resid, cond


def implausible(result: dict, trace) -> tuple[str, ...]:
    """Sentences naming each identified m, sigma, Cf (and per-direction level) <= 0 with its likely cause
    (in the words and units of the ``trace``'s axis)."""
    input_gain, units = trace.input_gain, trace.units
    M, F, L = units.mass_unit, units.force_unit, units.length_unit
    names = {"m": (units.mass_word, M), "sigma": ("viscous coefficient", f"{F} s/{L}"), "Cf": ("Coulomb level", F),
             "sigma_pos": ("viscous coefficient for v > 0", f"{F} s/{L}"),
             "sigma_neg": ("viscous coefficient for v < 0", f"{F} s/{L}"),
             "Cf_pos": ("Coulomb level for v > 0", F), "Cf_neg": ("Coulomb level for v < 0", F)}
    bad = [k for k in names if result.get(k) is not None and not result[k] > 0]
    if not bad:
        return ()
    if input_gain < 0:
        cause = (f"the input gain is negative (input_gain = {input_gain:g}): check its sign; a "
                 f"{units.force_word} that opposes the logged input gives a negative {units.mass_word}")
    elif result["m"] <= 0 and result["sigma"] <= 0 and result["Cf"] <= 0:
        cause = ("every term is negative: the input acts against the position, so check the sign of the input "
                 "gain (or of the position column)")
    else:
        cause = ("check that the position and input columns are not swapped, the sign of the input gain, and the "
                 f"units (position in {L}, time in s, input times the gain in {F})")
    found = ", ".join(f"{k} = {result[k]:.4g} {names[k][1]}" for k in bad)
    return (f"identify: not physical: expected a positive {names[bad[0]][0]}, found {found}; {cause}",)


def quantization(position: np.ndarray) -> float:
    """Smallest nonzero position increment if every increment is a multiple of it, else 0."""
    steps = np.abs(np.diff(position))
    steps = steps[steps > 0]
    if steps.size == 0:
        return 0.0
    q = float(steps.min())
    ratio = steps / q
    return q if bool(np.all(np.abs(ratio - np.round(ratio)) < 1e-3)) else 0.0


def time_window(trace, window) -> tuple[np.ndarray, np.ndarray, str]:
    """Position and force inside ``window = (t0, t1)`` [s] (the whole record for ``None``)."""
    if window is None:
        return trace.position, trace.force, ""
    try:
        t0, t1 = (float(w) for w in window)
    except (TypeError, ValueError):
        raise ValueError(f"window: expected (t0, t1) in seconds, found {window!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t0 < t1):
        raise ValueError(f"window: expected finite t0 < t1 [s], found ({t0:g}, {t1:g})")
    inside = (trace.t >= t0) & (trace.t <= t1)
    if np.count_nonzero(inside) < MIN_SAMPLES:
        raise ValueError(f"window: expected at least {MIN_SAMPLES} samples in [{t0:g}, {t1:g}] s, found "
                         f"{np.count_nonzero(inside)} (the record spans {trace.t[0]:g} to {trace.t[-1]:g} s)")
    return trace.position[inside], trace.force[inside], f"{t0:g} to {t1:g} s"


def positive_number(name: str, value, low: float, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > low):
        raise ValueError(f"{name}: expected a finite number > {low:g} [{unit}], found {value!r}")
    return float(value)
