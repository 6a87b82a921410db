"""LuGre friction (Canudas de Wit et al. 1995) with a Stribeck curve, compiled with numba.

Model (per unit normal load, SI units)::

    z' = v - sigma0 |v| z / g(v)
    F  = sigma0 z + sigma1 z' + Fv(v) + offset
    g(v) = Fc_d + (Fs_d - Fc_d) exp(-(v/vs)^2),   d = sign(v)

``Fc_d`` is ``Cf`` (``d = +1``) or ``Cf_neg`` (``d = -1``); ``Fs_neg = Fs Cf_neg / Cf``
(the stiction-to-Coulomb ratio is kept in both directions); ``Fv`` is the
per-direction viscous part (``sigma2`` of the paper is ``sigma`` here).

Internal state ``st = [z, x_last, direction]``: the bristle deflection ``z`` at
the displacement ``x_last`` where the state was last advanced, and the last
direction of motion.

Update scheme. Written over displacement, the bristle equation for a motion
of constant direction ``d`` with ``g`` frozen is linear,
``dz/dx = 1 - sigma0 d z / g``, with the exact solution ::

    z(x) = z_ss + (z_last - z_ss) exp(-sigma0 |x - x_last| / g),   z_ss = d g / sigma0.

For a velocity held over a substep (``x - x_last = v h``) this is the exact
``z_ss + (z - z_ss) exp(-a h)`` with ``a = sigma0 |v| / g``. The factor is in
(0, 1] for every step, so the update is unconditionally stable and bounded
(``|z| <= max g / sigma0`` is invariant) however stiff ``sigma0`` is.
:func:`lugre_force` evaluates the same expression at the stage's ``x`` with the
state held, so the Heun stages see the bristle force of the displacement they
try; :func:`lugre_advance` stores it at the substep's end.

References
----------
C. Canudas de Wit, H. Olsson, K. J. Astrom, P. Lischinsky, "A new model for
control of systems with friction", IEEE Trans. Automat. Contr. 40(3):419-425,
1995 (Table 1: sigma0 = 1e5 N/m, sigma1 = sqrt(1e5) N s/m, sigma2 = 0.4 N s/m,
Fc = 1 N, Fs = 1.5 N, vs = 1e-3 m/s; unit mass).
H. Olsson, K. J. Astrom, C. Canudas de Wit, M. Gafvert, P. Lischinsky,
"Friction models and friction compensation", Eur. J. Control 4(3):176-195, 1998.
K. J. Astrom, C. Canudas de Wit, "Revisiting the LuGre friction model",
IEEE Control Systems Magazine 28(6):101-114, 2008.

Examples
--------
>>> import numpy as np
>>> p = np.array([0.35, 0.35, 21.1, 21.1, 0.0, 0.525, 0.525, 1e-3, 1e5, 316.2])
>>> st = np.zeros(3)
>>> lugre_init(p, st, 0.0)
>>> round(lugre_force(p, st, 1e-6, 0.0), 4)  # 1 um of pre-sliding (sigma0 x = 0.1 N)
0.0911
>>> for i in range(20000):  # slide at 10 mm/s for 0.2 s
...     lugre_advance(p, st, (i + 1) * 1e-7, 0.01, 1e-5)
>>> round(lugre_force(p, st, 2e-3, 0.01), 6)  # Cf + (Fs - Cf) e^-100 + sigma v
0.561
"""

from __future__ import annotations

import math

from numba import njit

from .common import P_FS, P_FS_NEG, P_MODEL, P_OFFSET, P_VS, sign, stribeck_magnitude, viscous

__all__ = [
    "L_FS", "L_FS_NEG", "L_VS", "L_SIGMA0", "L_SIGMA1", "N_PARAMS", "N_STATE",
    "lugre_init", "lugre_force", "lugre_advance", "lugre_stiffness", "lugre_steady",
]

L_FS, L_FS_NEG, L_VS, L_SIGMA0, L_SIGMA1 = P_FS, P_FS_NEG, P_VS, P_MODEL + 3, P_MODEL + 4
#: Length of the parameter array.
N_PARAMS = P_MODEL + 5
#: Length of the state array.
N_STATE = 3


@njit(cache=True, error_model="numpy")
def lugre_init(p, st, x0: float) -> None:
    """State for a start at rest at ``x0``: no bristle deflection."""
    st[0] = 0.0
    st[1] = x0
    st[2] = 0.0


@njit(cache=True, error_model="numpy")
def _z_moved(z: float, dx: float, g: float, sigma0: float) -> float:
    """Bristle deflection [m] after a displacement ``dx != 0`` from deflection ``z`` (exact, ``g`` frozen)."""
    d = sign(dx)
    z_ss = d * g / sigma0
    return z_ss + (z - z_ss) * math.exp(-sigma0 * abs(dx) / g)


@njit(cache=True, error_model="numpy")
def _z_at(p, st, x: float, v: float) -> float:
    """Bristle deflection [m] at ``x`` from the held state (exact, ``g`` frozen at ``|v|``)."""
    dx = x - st[1]
    if dx == 0.0:
        return st[0]
    return _z_moved(st[0], dx, stribeck_magnitude(p, sign(dx), abs(v)), p[L_SIGMA0])


@njit(cache=True, error_model="numpy")
def lugre_force(p, st, x: float, v: float) -> float:
    """Total friction force [N] at ``(x, v)`` with the state held.

    ``g`` is evaluated once where the displacement and the velocity point the same way
    (:func:`~obsdesign.friction.common.stribeck_magnitude` depends on the direction's sign only).
    """
    sigma0 = p[L_SIGMA0]
    speed = abs(v)
    dx = x - st[1]
    z = st[0]
    g = 0.0
    if dx != 0.0:
        g = stribeck_magnitude(p, sign(dx), speed)
        z = _z_moved(z, dx, g, sigma0)
    zdot = 0.0
    if v != 0.0:
        if dx == 0.0 or (dx < 0.0) != (v < 0.0):
            g = stribeck_magnitude(p, sign(v), speed)
        zdot = v - sigma0 * speed * z / g
    return sigma0 * z + p[L_SIGMA1] * zdot + viscous(p, v) + p[P_OFFSET]


@njit(cache=True, error_model="numpy")
def lugre_advance(p, st, x: float, v: float, h: float) -> None:
    """Advance the state to the end ``(x, v)`` of a substep (``h`` is not needed: exact in ``x``)."""
    dx = x - st[1]
    if dx == 0.0:
        return
    st[0] = _z_at(p, st, x, v)
    st[1] = x
    st[2] = sign(dx)


@njit(cache=True, error_model="numpy")
def lugre_stiffness(p, st, x: float, v: float) -> float:
    """Bristle stiffness ``sigma0 (1 - sigma0 z d / g(v))`` [N/m], clipped at 0.

    ``d = sign(v)``, or the last direction of motion at ``v = 0``; ``sigma0``
    before the first motion.
    """
    d = sign(v)
    if d == 0.0:
        d = st[2]
    sigma0 = p[L_SIGMA0]
    if d == 0.0:
        return sigma0
    z = _z_at(p, st, x, v)
    k = sigma0 * (1.0 - sigma0 * z * d / stribeck_magnitude(p, d, abs(v)))
    return k if k > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def lugre_steady(p, v: float) -> float:
    """Steady-state friction [N] at constant ``v``: ``sign(v) g(v) + Fv(v) + offset``."""
    d = sign(v)
    if d == 0.0:
        return p[P_OFFSET]
    return d * stribeck_magnitude(p, d, abs(v)) + viscous(p, v) + p[P_OFFSET]
