"""The low-pass eq:3:4:5 discretized by the bilinear transform and run as a recursive filter (numba).

The paper filters the velocity estimate with the same second-order low-pass as the friction estimate
before it drives the friction model (Fig. frictionloops, :func:`obsdesign.studies.friction_loops_study`):
``F(p) = omega_co^2 / (p + omega_co)^2`` discretized with Tustin's rule. :func:`bilinear_lowpass` gives
the coefficients of ``scipy.signal.cont2discrete(..., method="bilinear")``, computed once and kept in the
result memo (:mod:`obsdesign._memo`); :func:`iir_filter` runs them with the arithmetic of
``scipy.signal.lfilter`` (direct form II transposed, the same operations in the same order: the same
floats, ``tests/test_design.py``), so a warm report imports no ``scipy.signal`` (0.7-0.9 s with the
``scipy.stats`` it imports).

Examples
--------
>>> import math, numpy as np
>>> b, a = bilinear_lowpass(2 * math.pi * 40, 1e-4)
>>> round(float(sum(b) / sum(a)), 12)  # unit gain at DC
1.0
>>> y = iir_filter(b, a, np.ones(20000))
>>> round(float(y[-1]), 9)
1.0
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._memo import memo

__all__ = ["bilinear_lowpass", "iir_filter"]


def _is_coefficients(value) -> bool:
    return (isinstance(value, list) and len(value) == 2
            and all(isinstance(c, list) and len(c) == 3 and all(isinstance(x, float) and math.isfinite(x) for x in c)
                    for c in value))


def bilinear_lowpass(omega_co: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator ``(b, a)`` of eq:3:4:5 discretized by Tustin's rule at sample time ``dt``.

    Parameters
    ----------
    omega_co : float
        Cutoff [rad/s].
    dt : float
        Sample time [s].

    Returns
    -------
    b, a : ndarray, shape (3,)
        ``scipy.signal.cont2discrete(([w^2], [1, 2 w, w^2]), dt, method="bilinear")``, kept on disk.
    """
    w, h = float(omega_co), float(dt)

    def compute() -> list:
        import scipy.signal

        b, a = scipy.signal.cont2discrete(([w * w], [1, 2 * w, w * w]), h, method="bilinear")[:2]
        return [np.ravel(b).astype(float).tolist(), np.ravel(a).astype(float).tolist()]

    b, a = memo("bilinear_lowpass", (w, h), compute, valid=_is_coefficients)
    return np.array(b), np.array(a)


@njit(cache=True, error_model="numpy")
def iir_filter(b, a, x):
    """``scipy.signal.lfilter(b, a, x)`` for a second-order filter from rest: direct form II transposed.

    Parameters
    ----------
    b, a : ndarray, shape (3,)
        Numerator and denominator (normalized by ``a[0]`` as ``lfilter`` does).
    x : ndarray, shape (n,)
        Input.

    Returns
    -------
    ndarray, shape (n,)
    """
    b0, b1, b2 = b[0] / a[0], b[1] / a[0], b[2] / a[0]
    a1, a2 = a[1] / a[0], a[2] / a[0]
    y = np.empty(x.shape[0])
    z0 = 0.0
    z1 = 0.0
    for n in range(x.shape[0]):
        xn = x[n]
        yn = z0 + b0 * xn
        z0 = z1 + xn * b1 - yn * a1
        z1 = xn * b2 - yn * a2
        y[n] = yn
    return y
