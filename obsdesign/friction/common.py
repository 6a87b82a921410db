"""Parameter layout and helpers shared by the plant friction kernels (numba).

Every model is described by a flat ``float64`` parameter array ``p`` whose first
:data:`P_MODEL` entries are common to all models:

====================  =============  ==============================================
index                 symbol         meaning
====================  =============  ==============================================
``P_CF``  (0)         ``Cf``         Coulomb level, positive direction [N]
``P_CF_NEG`` (1)      ``Cf_neg``     Coulomb level, negative direction [N]
``P_SIGMA`` (2)       ``sigma``      viscous coefficient, positive direction [N s/m]
``P_SIGMA_NEG`` (3)   ``sigma_neg``  viscous coefficient, negative direction [N s/m]
``P_OFFSET`` (4)      ``offset``     constant force added to the friction [N]
====================  =============  ==============================================

The model's own parameters follow from index :data:`P_MODEL`. The arrays are
built and validated by :mod:`obsdesign.friction.registry`; the kernels trust them.

Examples
--------
>>> import numpy as np
>>> p = np.array([0.35, 0.25, 20.0, 10.0, 0.0])
>>> viscous(p, 0.01), viscous(p, -0.01)
(0.2, -0.1)
>>> coulomb_level(p, -1.0)
0.25
>>> round(stribeck_level(0.35, 0.525, 1e-3, 1e-3), 6)  # Cf + (Fs - Cf) / e
0.414379
>>> q = np.append(p, [0.525, 0.375, 1e-3])             # a Stribeck model: Fs, Fs_neg, vs
>>> round(stribeck_magnitude(q, -1.0, 1e-3), 6)          # Cf_neg + (Fs_neg - Cf_neg) / e
0.295985
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "P_CF", "P_CF_NEG", "P_SIGMA", "P_SIGMA_NEG", "P_OFFSET", "P_MODEL",
    "P_FS", "P_FS_NEG", "P_VS",
    "sign", "coulomb_level", "viscous", "stribeck_level", "stribeck_magnitude",
]

P_CF, P_CF_NEG, P_SIGMA, P_SIGMA_NEG, P_OFFSET = 0, 1, 2, 3, 4
#: Index of the first model-specific parameter.
P_MODEL = 5
#: The Stribeck models (lugre, gms) start their own parameters with ``Fs, Fs_neg, vs``.
P_FS, P_FS_NEG, P_VS = P_MODEL, P_MODEL + 1, P_MODEL + 2


@njit(cache=True, error_model="numpy")
def sign(a: float) -> float:
    """``+1``, ``-1`` or ``0`` (as float)."""
    if a > 0.0:
        return 1.0
    if a < 0.0:
        return -1.0
    return 0.0


@njit(cache=True, error_model="numpy")
def coulomb_level(p, direction: float) -> float:
    """Coulomb level [N] (>= 0) for a motion in ``direction`` (``-1`` selects ``Cf_neg``)."""
    if direction < 0.0:
        return p[P_CF_NEG]
    return p[P_CF]


@njit(cache=True, error_model="numpy")
def viscous(p, v: float) -> float:
    """Linear viscous force [N]: ``sigma v`` for ``v > 0``, ``sigma_neg v`` for ``v < 0``."""
    if v < 0.0:
        return p[P_SIGMA_NEG] * v
    return p[P_SIGMA] * v


@njit(cache=True, error_model="numpy")
def stribeck_level(coulomb: float, static: float, vs: float, speed: float) -> float:
    """Stribeck magnitude ``Fc + (Fs - Fc) exp(-(speed/vs)^2)`` [N] for ``speed = |v|``."""
    r = speed / vs
    q = r * r
    if q > 746.0:  # exp(-q) is 0.0 exactly (below half the smallest subnormal): skip libm's slow underflow path
        return coulomb + (static - coulomb) * 0.0
    return coulomb + (static - coulomb) * math.exp(-q)


@njit(cache=True, error_model="numpy")
def stribeck_magnitude(p, direction: float, speed: float) -> float:
    """Stribeck magnitude ``|s(v)|`` [N] (> 0) of a Stribeck model for a motion in ``direction``
    at ``speed = |v|``: :func:`stribeck_level` of ``Cf, Fs, vs`` (``Cf_neg, Fs_neg`` for ``direction < 0``)."""
    if direction < 0.0:
        return stribeck_level(p[P_CF_NEG], p[P_FS_NEG], p[P_VS], speed)
    return stribeck_level(p[P_CF], p[P_FS], p[P_VS], speed)
