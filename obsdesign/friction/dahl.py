"""Dahl friction (Dahl 1968, 1976), compiled with numba.

Model (rate independent: the friction depends on the path, not on time)::

    dFd/dx = sigma0 |1 - Fd d / Fc_d|^alpha sign(1 - Fd d / Fc_d),   d = sign(v)
    F      = Fd + Fv(v) + offset

``Fc_d`` is ``Cf`` (``d = +1``) or ``Cf_neg`` (``d = -1``), ``Fv`` the per-direction
viscous part. Internal state ``st = [Fd, x_last, direction]``.

Exact branch. With ``y = 1 - Fd d / Fc_d`` and the travelled distance
``s = |x - x_last|`` of a motion in direction ``d`` the equation is
``dy/ds = -(sigma0 / Fc_d) y^alpha``, solved in closed form::

    alpha = 1:  y = y0 exp(-sigma0 s / Fc_d)
    alpha < 1:  y = max(0, y0^(1-alpha) - (1 - alpha) sigma0 s / Fc_d)^(1/(1-alpha))
    alpha > 1:  y = (y0^(1-alpha) + (alpha - 1) sigma0 s / Fc_d)^(-1/(alpha-1))

so ``Fd = d Fc_d (1 - y)``. For ``alpha = 1`` after a reversal at ``(x_r, F_r)``
this is the hysteresis branch ::

    Fd(x) = d Fc_d + (F_r - d Fc_d) exp(-sigma0 |x - x_r| / Fc_d).

The update uses the substep's actual displacement, so it is exact for any
motion of one direction within the substep, unconditionally stable, and keeps
``-Cf_neg <= Fd <= Cf`` (for ``y0 >= 0``).

References
----------
P. R. Dahl, "A solid friction model", Aerospace Corp., TOR-0158(3107-18)-1, 1968.
P. R. Dahl, "Solid friction damping of mechanical vibrations", AIAA J.
14(12):1675-1682, 1976.
H. Olsson et al., "Friction models and friction compensation", Eur. J. Control
4(3):176-195, 1998 (section 3: alpha = 1 is the common choice; a larger alpha
gives a sharper bend of the curve).

Examples
--------
>>> import numpy as np
>>> p = np.array([0.35, 0.35, 0.0, 0.0, 0.0, 1e5, 1.0])
>>> st = np.zeros(3)
>>> dahl_init(p, st, 0.0)
>>> round(dahl_force(p, st, 3.5e-6, 0.01), 6)  # Cf (1 - e^-1) after Cf/sigma0
0.221242
>>> dahl_advance(p, st, 1e-3, 0.01, 0.1)  # slid far: saturated at Cf
>>> round(dahl_force(p, st, 1e-3 - 3.5e-6, -0.01), 6)  # back by Cf/sigma0: Cf (2 e^-1 - 1)
-0.092484
"""

from __future__ import annotations

import math

from numba import njit

from .common import P_MODEL, P_OFFSET, coulomb_level, sign, viscous

__all__ = ["D_SIGMA0", "D_ALPHA", "N_PARAMS", "N_STATE",
           "dahl_init", "dahl_force", "dahl_advance", "dahl_stiffness", "dahl_steady"]

D_SIGMA0, D_ALPHA = P_MODEL, P_MODEL + 1
#: Length of the parameter array.
N_PARAMS = P_MODEL + 2
#: Length of the state array.
N_STATE = 3


@njit(cache=True, error_model="numpy")
def dahl_init(p, st, x0: float) -> None:
    """State for a start at rest at ``x0``: no friction force."""
    st[0] = 0.0
    st[1] = x0
    st[2] = 0.0


@njit(cache=True, error_model="numpy")
def _fd_at(p, st, x: float) -> float:
    """Dahl force [N] at ``x`` on the branch from the held state (exact)."""
    dx = x - st[1]
    if dx == 0.0:
        return st[0]
    d = sign(dx)
    fc = coulomb_level(p, d)
    y0 = 1.0 - st[0] * d / fc
    r = p[D_SIGMA0] * abs(dx) / fc
    alpha = p[D_ALPHA]
    if alpha == 1.0 or y0 <= 0.0:
        y = y0 * math.exp(-r)  # also the relaxation of an (invalid) overshoot y0 < 0
    elif alpha < 1.0:
        q = y0 ** (1.0 - alpha) - (1.0 - alpha) * r
        y = q ** (1.0 / (1.0 - alpha)) if q > 0.0 else 0.0
    else:
        y = (y0 ** (1.0 - alpha) + (alpha - 1.0) * r) ** (-1.0 / (alpha - 1.0))
    return d * fc * (1.0 - y)


@njit(cache=True, error_model="numpy")
def dahl_force(p, st, x: float, v: float) -> float:
    """Total friction force [N] at ``(x, v)`` with the state held."""
    return _fd_at(p, st, x) + viscous(p, v) + p[P_OFFSET]


@njit(cache=True, error_model="numpy")
def dahl_advance(p, st, x: float, v: float, h: float) -> None:
    """Advance the state to ``x`` (exact in the displacement; ``v`` and ``h`` unused)."""
    dx = x - st[1]
    if dx == 0.0:
        return
    st[0] = _fd_at(p, st, x)
    st[1] = x
    st[2] = sign(dx)


@njit(cache=True, error_model="numpy")
def dahl_stiffness(p, st, x: float, v: float) -> float:
    """``dFd/dx = sigma0 y^alpha`` [N/m] along ``d = sign(v)`` (last direction at ``v = 0``)."""
    d = sign(v)
    if d == 0.0:
        d = st[2]
    if d == 0.0:
        return p[D_SIGMA0]
    y = 1.0 - _fd_at(p, st, x) * d / coulomb_level(p, d)
    if y <= 0.0:
        return 0.0
    return p[D_SIGMA0] * y ** p[D_ALPHA]


@njit(cache=True, error_model="numpy")
def dahl_steady(p, v: float) -> float:
    """Steady-state friction [N] at constant ``v``: ``sign(v) Fc_d + Fv(v) + offset``."""
    d = sign(v)
    return d * coulomb_level(p, d) + viscous(p, v) + p[P_OFFSET]
