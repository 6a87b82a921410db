"""Pre-sliding scaling factor ``s`` from post-reversal segments (eq:2:3:1-2:3:5).

After a reversal at ``x_r`` following gross sliding, the normalised friction memory is
``f_r = -dir`` and the paper's map gives, for ``|z| <= 1`` with ``z = s (x - x_r)``,

    F_c = Cf (|dir - f_r| z (1 - ln|z|) + f_r) = Cf dir (2 zeta (1 - ln zeta) - 1),  zeta = s |x - x_r|,

saturating at ``Cf dir`` for ``zeta >= 1``. ``s`` is fitted by least squares of this map
against the friction force left after subtracting ``m a + sigma v + offset`` from the
filtered actuator force, on samples within ``window`` of each reversal.

Examples
--------
>>> import numpy as np
>>> presliding_map(np.array([0.0, 0.5e-4, 1e-4, 2e-4]), s=1e4, Cf=2.0, direction=1.0).round(3).tolist()
[-2.0, 1.386, 2.0, 2.0]
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["fit_presliding", "presliding_map"]

MIN_REVERSALS = 5
MIN_ROWS = 5
MIN_DISTINCT = 5


def presliding_map(travel: np.ndarray, *, s: float, Cf: float, direction: float) -> np.ndarray:
    """Coulomb force [N] after a reversal from gross sliding, along ``|x - x_r|`` = ``travel`` [m].

    Parameters
    ----------
    travel : ndarray
        Displacement since the reversal [m].
    s : float
        Pre-sliding scale [1/m].
    Cf : float
        Coulomb level [N].
    direction : float
        +1 or -1, the direction of the new motion.

    eq:2:3:3 with ``f_r = -direction`` and eq:2:3:4; ``z ln|z|`` is taken as 0 at ``z = 0``.
    """
    zeta = np.minimum(s * np.abs(travel), 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        shape = np.where(zeta > 0, 2.0 * zeta * (1.0 - np.log(np.where(zeta > 0, zeta, 1.0))), 0.0)
    return Cf * direction * (shape - 1.0)


def _reversals(v: np.ndarray, threshold: float) -> np.ndarray:
    idx = np.flatnonzero(np.abs(v) > threshold)
    if idx.size < 2:
        return np.empty(0, dtype=int)
    signs = np.sign(v[idx])
    change = np.flatnonzero(signs[1:] != signs[:-1])
    return np.array([idx[c] + int(np.argmin(np.abs(v[idx[c]:idx[c + 1] + 1]))) for c in change], dtype=int)


def fit_presliding(*, x: np.ndarray, x_f: np.ndarray, v: np.ndarray, a: np.ndarray, u_f: np.ndarray, dt: float,
                   m: float, sigma: float, Cf: float, offset: float, rows: int,
                   window: float, length_unit: str = "m") -> tuple[float | None, str]:
    """``(s, note)``: ``s`` [1/m] fitted from post-reversal segments, or ``None`` and the reason.

    Parameters
    ----------
    x, x_f, v, a, u_f : ndarray
        Raw and filtered position [m], velocity [m/s], acceleration [m/s^2] and filtered force [N], per sample.
    dt : float
        Sample time [s].
    m, sigma, Cf, offset : float
        The rigid-body and gross-sliding fit.
    rows : ndarray
        Indices of the samples the fit may use.
    window : float
        Travel after a reversal [m] that counts as pre-sliding.
    length_unit : str
        The axis's length unit in the note (``rad`` on a rotary axis).

    A reversal resolves pre-sliding when the filtered position stays within ``window`` [m]
    of the reversal point for at least ``MIN_ROWS`` rows of the identification grid
    (``MIN_ROWS * rows`` samples: the fit cannot resolve anything shorter) and the raw
    encoder ``x`` takes at least ``MIN_DISTINCT`` distinct values there. ``s`` is fitted
    only when at least ``MIN_REVERSALS`` reversals do.

    Examples
    --------
    >>> t = np.arange(5000) * 1e-3
    >>> x = 0.01 * np.sin(2 * np.pi * 0.2 * t)
    >>> v = np.gradient(x, 1e-3)
    >>> s, note = fit_presliding(x=x, x_f=x, v=v, a=np.gradient(v, 1e-3), u_f=np.sign(v), dt=1e-3, m=1.0,
    ...                          sigma=0.0, Cf=1.0, offset=0.0, rows=10, window=1e-4)
    >>> s is None, note.startswith("not identifiable from these data: 2 velocity reversals")
    (True, True)
    """
    peak = float(np.max(np.abs(v)))
    revs = _reversals(v, 0.01 * peak) if peak > 0 else np.empty(0, dtype=int)
    need = MIN_ROWS * rows
    segments, longest = [], 0
    for r in revs:
        out = np.flatnonzero(np.abs(x_f[r:] - x_f[r]) > window)
        end = r + (int(out[0]) if out.size else x_f.size - r)
        longest = max(longest, end - r)
        if end - r >= need and np.unique(x[r:end]).size >= MIN_DISTINCT:
            segments.append((r, end))
    n_rev = int(revs.size)
    plural = "reversal" if n_rev == 1 else "reversals"
    if n_rev < MIN_REVERSALS or len(segments) < MIN_REVERSALS:
        return None, (
            f"not identifiable from these data: {n_rev} velocity {plural}, {len(segments)} of them dwelling in "
            f"the pre-sliding window (|x - x_r| <= {window:g} {length_unit} for at least {need} samples = {need * dt:g} s, "
            f"{MIN_ROWS} rows of the fit; the longest stays {longest} samples); at least {MIN_REVERSALS} are "
            f"needed, so the record shows gross sliding, not pre-sliding")
    from scipy.optimize import minimize_scalar

    friction = u_f - m * a - sigma * v - offset
    data = []
    for r, end in segments:
        direction = float(np.sign(v[min(end, v.size - 1)]) or np.sign(x_f[end - 1] - x_f[r]))
        data.append((np.abs(x_f[r:end] - x_f[r]), friction[r:end], direction))

    def cost(log_s: float) -> float:
        s = math.exp(log_s)
        return sum(float(np.sum((f - presliding_map(d, s=s, Cf=Cf, direction=k)) ** 2)) for d, f, k in data)

    lo, hi = math.log(0.1 / window), math.log(1e3 / window)
    best = minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": 1e-4})
    s = math.exp(best.x)
    if best.x - lo < 1e-2 or hi - best.x < 1e-2:
        return None, (f"not identifiable from these data: the fit over {len(segments)} post-reversal segments "
                      f"ends at the search bound s = {s:.3g} 1/m (search {math.exp(lo):.3g} to {math.exp(hi):.3g})")
    return s, (f"fitted from {len(segments)} post-reversal segments of {n_rev} {plural} (window {window:g} "
               f"{length_unit}); no interval here (the map fitted to filtered segments: -13 % to +34 % on simulated logs): "
               f"refine gives one (identify --refine s)")
