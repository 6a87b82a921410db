"""Intervals of an identification: a moving-block bootstrap over the record, widened by the
predicted errors-in-variables bias.

Why a block bootstrap: the rows of the fit are consecutive samples of one record. Their
residuals are correlated (the decimation filter, and friction or dynamics the model does not
hold, change slowly), and the regressors ``a`` and ``v`` are themselves computed from the noisy
position. The OLS covariance ``sigma_e^2 (X^T X)^-1`` assumes independent residuals and exact
regressors, and understates the spread of the estimates (on EMPS 3-10x the record-to-record
variation). Resampling blocks of consecutive rows (Kuensch 1989; the length is the first lag at
which the residual autocorrelation falls below :data:`ACF_CUTOFF`, at least ``n^(1/3)``) keeps
that correlation and the noise of the regressors within a block, so the replicates spread as
estimates from similar records would. Each replicate is one Gauss-Newton step from the estimate
on the resampled rows (exact for the linear models; the one-step bootstrap of the Stribeck fit),
clipped to the bounds; a replicate is a row-count-weighted normal-equation solve, all at once.

What a bootstrap cannot show is a bias. Noise ``eta`` on the position reaches the acceleration and
velocity columns through the filter and the differences (variance ``eta^2 sum h^2`` with ``h``
the chain's impulse response) and attenuates the estimates (errors in variables). The predicted
shift of the bias-compensated estimate, ``(J^T J - N Sigma)^-1 N Sigma theta``, is added to the
side of the interval it points to, and :func:`eiv_shift` reports it.

Examples
--------
>>> import numpy as np
>>> rng = np.random.default_rng(1)
>>> x = rng.normal(size=(400, 2)); y = x @ [1.0, 2.0] + rng.normal(0.0, 0.1, 400)
>>> theta = np.linalg.lstsq(x, y, rcond=None)[0]
>>> reps = bootstrap(x, x @ theta - y, theta, np.full(2, -np.inf), np.full(2, np.inf), n_boot=200, seed=0)
>>> reps.shape, bool(np.all(np.abs(reps.mean(axis=0) - theta) < 0.02))
((200, 2), True)
"""

from __future__ import annotations

import math

import numpy as np

from ._idim import second_difference

__all__ = ["block_length", "bootstrap", "column_noise", "correlation_time", "eiv_shift", "impulse_length",
           "white_variance", "ACF_CUTOFF", "N_BOOT", "LEVEL", "SOKAL_WINDOW"]

#: The residual autocorrelation below which rows count as independent (block length rule).
ACF_CUTOFF = 0.1
#: Sokal's window constant of :func:`correlation_time`.
SOKAL_WINDOW = 5.0
#: Default number of bootstrap replicates.
N_BOOT = 400
#: Two-sided interval level.
LEVEL = 0.95


def block_length(resid: np.ndarray) -> int:
    """First lag with residual autocorrelation < :data:`ACF_CUTOFF`, at least ``ceil(n^(1/3))``, at most ``n/5``.

    Parameters
    ----------
    resid : ndarray
        The residuals in row order.
    """
    n = resid.size
    r = resid - resid.mean()
    spec = np.fft.rfft(r, 2 * n)
    acf = np.fft.irfft(spec * np.conj(spec))[:n]
    acf = acf / acf[0] if acf[0] > 0 else acf
    below = np.flatnonzero(acf < ACF_CUTOFF)
    lag = int(below[0]) if below.size else n
    return int(max(1, min(max(math.ceil(n ** (1.0 / 3.0)), lag), n // 5)))


def correlation_time(resid: np.ndarray, window: float = SOKAL_WINDOW) -> float:
    """Integrated autocorrelation time ``tau = 1 + 2 sum_k rho_k`` of the residuals, at least 1.

    The sum runs to the first lag ``k >= window * tau(k)`` (Sokal's automatic window). ``n / tau``
    rows carry the information of that many independent ones; anti-correlated residuals
    (``tau < 1``) are not credited with more.

    Parameters
    ----------
    resid : ndarray
        The residuals in row order.
    window : float
        Sokal's ``c``.

    Examples
    --------
    >>> from scipy.signal import lfilter
    >>> e = np.random.default_rng(0).normal(size=200_000)
    >>> ar = lfilter([1.0], [1.0, -0.8], e)  # AR(1): tau = (1 + 0.8) / (1 - 0.8) = 9
    >>> bool(abs(correlation_time(ar) - 9.0) < 0.8), correlation_time(e)
    (True, 1.0)
    """
    n = resid.size
    r = resid - resid.mean()
    spec = np.fft.rfft(r, 2 * n)
    acf = np.fft.irfft(spec * np.conj(spec))[:n]
    if not acf[0] > 0:
        return 1.0
    acf = acf / acf[0]
    tau = 1.0
    for k in range(1, n):
        tau += 2.0 * float(acf[k])
        if k >= window * tau:
            break
    return float(min(max(tau, 1.0), n))


def _indices(n: int, block: int, rng: np.random.Generator) -> np.ndarray:
    starts = rng.integers(0, n - block + 1, size=math.ceil(n / block))
    return (starts[:, None] + np.arange(block)[None, :]).ravel()[:n]


def bootstrap(jac: np.ndarray, resid: np.ndarray, theta: np.ndarray, lo: np.ndarray, hi: np.ndarray, *,
              n_boot: int = N_BOOT, seed: int = 0, block: int | None = None,
              index_sets: np.ndarray | None = None) -> np.ndarray:
    """Replicates ``(n_boot, p)``: one Gauss-Newton step of ``resid + jac d = 0`` on resampled rows.

    Parameters
    ----------
    jac, resid : ndarray
        Jacobian ``(n, p)`` and residual ``model - y`` at ``theta``.
    theta, lo, hi : ndarray
        The estimate and its bounds (replicates are clipped to them).
    n_boot, seed : int
    block : int, optional
        Block length; default :func:`block_length` of ``resid``.
    index_sets : ndarray, optional
        ``(n_boot, n)`` row indices to reuse (so two fits resample the same blocks).
    """
    idx = index_sets if index_sets is not None else make_index_sets(resid, n_boot=n_boot, seed=seed, block=block)
    n, p = jac.shape
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0] = 1.0
    js = jac / scale
    counts = np.stack([np.bincount(rows, minlength=n) for rows in idx]).astype(float)
    outer = (js[:, :, None] * js[:, None, :]).reshape(n, p * p)
    grams = (counts @ outer).reshape(-1, p, p)
    rhs = counts @ (js * -resid[:, None])
    steps = np.linalg.solve(grams, rhs[:, :, None])[:, :, 0] / scale
    return np.clip(theta[None, :] + steps, lo, hi)


def make_index_sets(resid: np.ndarray, *, n_boot: int = N_BOOT, seed: int = 0, block: int | None = None) -> np.ndarray:
    """``(n_boot, n)`` moving-block row indices (block length :func:`block_length` unless given)."""
    n = resid.size
    b = block_length(resid) if block is None else block
    rng = np.random.default_rng(seed)
    return np.stack([_indices(n, b, rng) for _ in range(n_boot)])


def noise_variance(chain, length: int) -> float:
    """``sum h^2`` of the linear ``chain`` (a callable on a 1-D array): the variance it gives unit white noise."""
    impulse = np.zeros(length)
    impulse[length // 2] = 1.0
    h = chain(impulse)
    return float(h @ h)


def impulse_length(q: int) -> int:
    """Length of the impulse responses of :func:`noise_variance` for the decimation factor ``q``.

    Parameters
    ----------
    q : int
        Decimation factor.

    Examples
    --------
    >>> impulse_length(1), impulse_length(20)
    (4096, 8000)
    """
    return max(4096, 400 * q)


def white_variance(white: float, sos: np.ndarray, q: int) -> float:
    """The variance ``eta^2`` of a white noise whose part above the low-pass ``sos`` has mean square ``white``.

    ``white / sum (delta - h_lp)^2``, ``h_lp`` the impulse response of ``sosfiltfilt(sos, .)``.

    Parameters
    ----------
    white : float
        Mean square of the position minus its low-passed version.
    sos : ndarray
        The zero-phase low-pass (``sosfiltfilt``).
    q : int
        Decimation factor (sets the length of the impulse response).

    Examples
    --------
    >>> from scipy import signal
    >>> sos = signal.butter(4, 100.0, fs=1000.0, output="sos")
    >>> share = white_variance(1.0, sos, 10)  # 1 / the share of the variance above 100 Hz of 500
    >>> bool(1.0 / 0.8 < share < 1.0 / 0.7)
    True
    """
    from scipy import signal

    return white / noise_variance(lambda h: h - signal.sosfiltfilt(sos, h), impulse_length(q))


def column_noise(white: float, sos: np.ndarray, dec_sos: np.ndarray | None, q: int, dt: float) -> dict[str, float]:
    """Noise variance of the ``v`` and ``a`` columns of the fit from white position noise.

    Parameters
    ----------
    white : float
        Mean square of the position minus its filtered version [m^2].
    sos : ndarray
        The zero-phase Butterworth low-pass of the fit (``sosfiltfilt``).
    dec_sos : ndarray or None
        The decimation filter (``None`` without decimation); the subsampling keeps the variance.
    q : int
        Decimation factor.
    dt : float
        Sample time [s].

    Returns
    -------
    dict
        ``{"v": var, "a": var}``: ``eta^2 sum h^2`` with ``eta^2 = white / sum (delta - h_lp)^2``.
    """
    from scipy import signal

    length = impulse_length(q)
    eta2 = white_variance(white, sos, q)

    def smooth(h: np.ndarray) -> np.ndarray:
        return signal.sosfiltfilt(dec_sos, h) if q > 1 else h

    def vel(h: np.ndarray) -> np.ndarray:
        return np.gradient(signal.sosfiltfilt(sos, h), dt)

    return {"v": eta2 * noise_variance(lambda h: smooth(vel(h)), length),
            "a": eta2 * noise_variance(lambda h: smooth(second_difference(signal.sosfiltfilt(sos, h), dt)), length)}


def eiv_shift(jac: np.ndarray, theta: np.ndarray, noisy: dict[int, float]) -> np.ndarray:
    """Predicted bias-compensation shift ``(J^T J - N Sigma)^-1 N Sigma theta``.

    ``noisy`` maps a column of ``jac`` to the summed noise variance of that column over the rows
    (``rows x variance``). Returns NaN where ``J^T J - N Sigma`` is not positive definite (the noise
    is as large as the signal: no correction can be trusted).

    Parameters
    ----------
    jac : ndarray
        Jacobian (regressors) ``(n, p)``.
    theta : ndarray
        The estimate.
    noisy : dict
        Column index -> summed noise variance.
    """
    p = theta.size
    ns = np.zeros((p, p))
    for j, total in noisy.items():
        ns[j, j] = total
    if not ns.any():
        return np.zeros(p)
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0] = 1.0
    jtj = (jac / scale).T @ (jac / scale)
    nss = ns / scale[:, None] / scale[None, :]
    corrected = jtj - nss
    if np.min(np.linalg.eigvalsh(corrected)) <= 0:
        return np.full(p, np.nan)
    return np.linalg.solve(corrected, nss @ (theta * scale)) / scale


def intervals(replicates: np.ndarray, shift: np.ndarray, level: float = LEVEL) -> tuple[np.ndarray, np.ndarray]:
    """Percentile interval of the replicates, each side widened by the part of ``shift`` pointing to it."""
    tail = 50.0 * (1.0 - level)
    lo, hi = np.percentile(replicates, [tail, 100.0 - tail], axis=0)
    shift = np.where(np.isfinite(shift), shift, 0.0)
    return lo + np.minimum(shift, 0.0), hi + np.maximum(shift, 0.0)
