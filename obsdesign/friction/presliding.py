"""Coulomb friction with pre-sliding memory (eq:2:3:1-2:3:5), compiled with numba.

A *branch* is the state of the pre-sliding memory: the current motion
``direction`` (+1, -1, or 0 before the first motion), the displacement ``x_r``
and the normalized friction ``f_r`` at the last reversal. On a branch,

* ``z = s (x - x_r)`` (eq:2:3:1);
* ``f_p = |direction - f_r| z (1 - ln|z|) + f_r`` for ``|z| <= 1`` (eq:2:3:3);
* ``Fc = Cf f_p`` in pre-sliding, ``Cf direction`` beyond (eq:2:3:4);
* ``k = dFc/dx = -s Cf |direction - f_r| ln|z|`` (eq:2:3:5 with the chain rule),
  which is infinite at ``z = 0`` and is bounded by ``kappa`` where a finite
  value is needed (section 3).

``z (1 - ln|z|)`` is continuous with limit 0 at ``z = 0``; that limit is used
exactly (no epsilon).

Examples
--------
>>> round(coulomb(1e-6, 1.0, 0.0, -1.0, 0.35, 3000.0), 6)  # 1 um (z = 0.003) after a reversal from -Cf
-0.335701
>>> coulomb(2 / 3000, 1.0, 0.0, -1.0, 0.35, 3000.0)  # saturated, |z| > 1
0.35
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["presliding_shape", "coulomb_normalized", "coulomb", "stiffness", "track_reversal", "track_reversal_hysteresis",
           "coulomb_along"]


@njit(cache=True, error_model="numpy")
def presliding_shape(z: float) -> float:
    """``z (1 - ln|z|)`` (eq:2:3:2) with its exact limit 0 at ``z = 0``."""
    if z == 0.0:
        return 0.0
    return z * (1.0 - math.log(abs(z)))


@njit(cache=True, error_model="numpy")
def coulomb_normalized(x: float, direction: float, x_r: float, f_r: float, s: float) -> float:
    """Normalized Coulomb friction ``Fc / Cf`` on a branch (eq:2:3:3-4)."""
    if direction == 0.0:
        return f_r
    z = s * (x - x_r)
    if direction * z >= 1.0:
        return direction
    fp = abs(direction - f_r) * presliding_shape(z) + f_r
    if fp > 1.0:
        return 1.0
    if fp < -1.0:
        return -1.0
    return fp


@njit(cache=True, error_model="numpy")
def coulomb(x: float, direction: float, x_r: float, f_r: float, Cf: float, s: float) -> float:
    """Coulomb friction force ``Fc`` [N] on a branch (eq:2:3:4)."""
    return Cf * coulomb_normalized(x, direction, x_r, f_r, s)


@njit(cache=True, error_model="numpy")
def stiffness(x: float, direction: float, x_r: float, f_r: float, Cf: float, s: float, kappa: float) -> float:
    """Pre-sliding stiffness ``dFc/dx`` [N/m], bounded by ``kappa`` (0 in gross sliding)."""
    if direction == 0.0:
        return kappa
    z = s * (x - x_r)
    if direction * z >= 1.0:
        return 0.0
    if z == 0.0:
        return kappa
    k = -s * Cf * abs(direction - f_r) * math.log(abs(z))
    if k > kappa:
        return kappa
    if k < 0.0:
        return 0.0
    return k


@njit(cache=True, error_model="numpy")
def track_reversal(v: float, x: float, direction: float, x_r: float, f_r: float, s: float):
    """Update a branch: a change of the sign of ``v`` starts a new branch at ``x``.

    Returns the new ``(direction, x_r, f_r)``; ``v == 0`` keeps the branch.
    """
    if (v > 0.0 and direction != 1.0) or (v < 0.0 and direction != -1.0):
        f_new = coulomb_normalized(x, direction, x_r, f_r, s)
        return (1.0 if v > 0.0 else -1.0), x, f_new
    return direction, x_r, f_r


@njit(cache=True, error_model="numpy")
def track_reversal_hysteresis(xm, direction, x_r, f_r, x_ext, s, threshold):
    """Branch update of the ``estimated`` schedule with a position hysteresis of ``threshold`` [m].

    A reversal is accepted once the measured displacement ``xm`` has come back from the
    branch's extreme ``x_ext`` by more than ``threshold``; the new branch starts at the
    extreme (where the motion reversed), not where the reversal was detected. The first
    motion leaves the start ``x_ext`` likewise. Returns ``(direction, x_r, f_r, x_ext)``.
    """
    if direction == 0.0:
        dx = xm - x_ext
        if abs(dx) > threshold:
            return (1.0 if dx > 0.0 else -1.0), x_ext, f_r, xm
        return direction, x_r, f_r, x_ext
    if direction * (xm - x_ext) > 0.0:
        return direction, x_r, f_r, xm
    if direction * (x_ext - xm) > threshold:
        f_new = coulomb_normalized(x_ext, direction, x_r, f_r, s)
        return -direction, x_ext, f_new, xm
    return direction, x_r, f_r, x_ext


@njit(cache=True, error_model="numpy")
def coulomb_along(x, v, Cf, s):
    """Coulomb friction [N] of the model driven by displacement and velocity traces.

    Reversals are taken from sign changes of ``v``; used to compute the
    model's friction from measured or estimated signals (Fig. frictionloops).
    """
    out = np.empty(x.shape[0])
    direction, x_r, f_r = 0.0, x[0], 0.0
    for i in range(x.shape[0]):
        direction, x_r, f_r = track_reversal(v[i], x[i], direction, x_r, f_r, s)
        out[i] = Cf * coulomb_normalized(x[i], direction, x_r, f_r, s)
    return out
