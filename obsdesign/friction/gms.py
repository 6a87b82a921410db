"""Generalized Maxwell-slip friction (Al-Bender, Lampaert, Swevers 2005), numba.

``N`` elementary elasto-slide elements in parallel, element ``i`` with stiffness
``k_i`` and a share ``alpha_i`` (``sum alpha_i = 1``) of the Stribeck curve
``s(v) = d (Fc_d + (Fs_d - Fc_d) exp(-(v/vs)^2))``, ``d = sign(v)``:

* sticking: ``dF_i/dt = k_i v`` until ``|F_i|`` reaches ``alpha_i |s(v)|``;
* slipping: ``dF_i/dt = sign(v) C (1 - F_i / (alpha_i s(v)))`` until the
  velocity reverses, when the element sticks again;
* ``F = sum_i (F_i + b_i z_i') + Fv(v) + offset`` with the element deflection rate
  ``z_i' = F_i' / k_i`` and the micro-damping ``b_i = sigma1 k_i / sum k`` (the
  damped form of Al-Bender and Swevers 2008; ``sigma1 = 0`` is the 2005 model).

``Fc_d`` is ``Cf`` or ``Cf_neg``, ``Fs_neg = Fs Cf_neg / Cf``, ``Fv`` the viscous part.

Internal state ``st = [x_last, direction, F_1..F_N, m_1..m_N]`` with the slip
mode ``m_i`` (0 sticking, +1/-1 slipping in that direction).

Update scheme (per substep ending at ``(x, v)``, displacement ``dx = x - x_last``):

* a sticking element (or a slipping one whose motion reversed) takes
  ``F_i + k_i dx`` exactly and, if that crosses ``alpha_i |s(v)|`` in the
  direction of motion, is clipped there and starts slipping;
* a slipping element relaxes exactly for the held velocity:
  ``F_i = t_i + (F_i - t_i) exp(-C h / (alpha_i |s(v)|))``, ``t_i = alpha_i s(v)``.

Both are exact for their regime, the relaxation factor is in (0, 1], and
``|F_i| <= alpha_i max(Fs, Fc)`` holds at every step: the update is bounded for
any ``k_i``, ``C`` and ``h``. :func:`gms_force` applies the sticking part at the
stage's ``x`` with the state held.

References
----------
F. Al-Bender, V. Lampaert, J. Swevers, "The generalized Maxwell-slip model: a
novel model for friction simulation and compensation", IEEE Trans. Automat.
Contr. 50(11):1883-1887, 2005.
V. Lampaert, F. Al-Bender, J. Swevers, "A generalized Maxwell-slip friction
model appropriate for control purposes", Proc. IEEE PhysCon, 2003, 1170-1177.
F. Al-Bender, J. Swevers, "Characterization of friction force dynamics",
IEEE Control Systems Magazine 28(6):64-81, 2008.

Examples
--------
>>> import numpy as np
>>> p = np.array([0.35, 0.35, 0.0, 0.0, 0.0, 0.525, 0.525, 1e-3, 20.0, 0.0, 2.0,
...               5e4, 5e4, 0.5, 0.5])
>>> st = np.zeros(gms_n_state(p))
>>> gms_init(p, st, 0.0)
>>> round(gms_force(p, st, 1e-6, 0.0), 6)  # both elements sticking: (k_1 + k_2) x
0.1
>>> gms_stiffness(p, st, 1e-6, 1e-3)
100000.0
"""

from __future__ import annotations

import math

from numba import njit

from .common import P_FS, P_FS_NEG, P_MODEL, P_OFFSET, P_VS, sign, stribeck_magnitude, viscous

__all__ = ["G_FS", "G_FS_NEG", "G_VS", "G_C", "G_SIGMA1", "G_N", "G_ELEMENTS",
           "gms_n_params", "gms_n_state", "gms_init", "gms_force",
           "gms_advance", "gms_stiffness", "gms_steady"]

G_FS, G_FS_NEG, G_VS = P_FS, P_FS_NEG, P_VS
G_C, G_SIGMA1, G_N = (P_MODEL + i for i in range(3, 6))
#: Index of ``k_1``; ``alpha_1`` is at ``G_ELEMENTS + N``.
G_ELEMENTS = P_MODEL + 6


@njit(cache=True, error_model="numpy")
def gms_n_params(n: int) -> int:
    """Length of the parameter array for ``n`` elements."""
    return G_ELEMENTS + 2 * n


@njit(cache=True, error_model="numpy")
def gms_n_state(p) -> int:
    """Length of the state array: ``2 + 2 N``."""
    return 2 + 2 * int(p[G_N])


@njit(cache=True, error_model="numpy")
def gms_init(p, st, x0: float) -> None:
    """State for a start at rest at ``x0``: every element sticking and unloaded."""
    st[0] = x0
    st[1] = 0.0
    for j in range(2, st.shape[0]):
        st[j] = 0.0


@njit(cache=True, error_model="numpy")
def gms_force(p, st, x: float, v: float) -> float:
    """Total friction force [N] at ``(x, v)`` with the state held."""
    n = int(p[G_N])
    dx = x - st[0]
    d = sign(dx)
    dv = sign(v)
    speed = abs(v)
    level_d = stribeck_magnitude(p, d, speed)
    level_v = level_d  # the magnitude depends on the direction's sign only: evaluated again where it differs
    if (d < 0.0) != (dv < 0.0):
        level_v = stribeck_magnitude(p, dv, speed)
    k_sum = 0.0
    for i in range(n):
        k_sum += p[G_ELEMENTS + i]
    damping = p[G_SIGMA1] / k_sum
    total = 0.0
    for i in range(n):
        k = p[G_ELEMENTS + i]
        a = p[G_ELEMENTS + n + i]
        f = st[2 + i]
        mode = st[2 + n + i]
        rate = 0.0
        if mode != 0.0 and mode * dx >= 0.0:
            if dv == mode:
                rate = mode * p[G_C] * (1.0 - f / (mode * a * level_v))
        else:
            f += k * dx
            rate = k * v
            if d != 0.0 and d * f > a * level_d:
                f = d * a * level_d
                rate = 0.0
        total += f + damping * rate  # b_i z_i' = (sigma1 k_i / sum k) F_i' / k_i
    return total + viscous(p, v) + p[P_OFFSET]


@njit(cache=True, error_model="numpy")
def gms_advance(p, st, x: float, v: float, h: float) -> None:
    """Advance the elements over a substep of length ``h`` that ended at ``(x, v)``."""
    n = int(p[G_N])
    dx = x - st[0]
    d = sign(dx)
    speed = abs(v)
    level_d = stribeck_magnitude(p, d, speed)
    for i in range(n):
        a = p[G_ELEMENTS + n + i]
        mode = st[2 + n + i]
        if mode != 0.0 and mode * dx >= 0.0:
            if dx != 0.0:
                target = mode * a * level_d
                st[2 + i] = target + (st[2 + i] - target) * math.exp(-p[G_C] * h / (a * level_d))
        else:
            f = st[2 + i] + p[G_ELEMENTS + i] * dx
            mode = 0.0
            if d != 0.0 and d * f >= a * level_d:
                f = d * a * level_d
                mode = d
            st[2 + i] = f
            st[2 + n + i] = mode
    st[0] = x
    if d != 0.0:
        st[1] = d


@njit(cache=True, error_model="numpy")
def gms_stiffness(p, st, x: float, v: float) -> float:
    """Sum of the sticking elements' ``k_i`` [N/m] for a motion along ``sign(v)``.

    At ``v = 0`` the last direction of motion is used; an element slipping in that
    direction does not count.
    """
    n = int(p[G_N])
    d = sign(v)
    if d == 0.0:
        d = st[1]
    dx = x - st[0]
    level = stribeck_magnitude(p, d, abs(v))
    k_sum = 0.0
    for i in range(n):
        k = p[G_ELEMENTS + i]
        mode = st[2 + n + i]
        if mode != 0.0 and mode == d:
            continue
        f = st[2 + i] + k * dx
        if d != 0.0 and d * f >= p[G_ELEMENTS + n + i] * level:
            continue
        k_sum += k
    return k_sum


@njit(cache=True, error_model="numpy")
def gms_steady(p, v: float) -> float:
    """Steady-state friction [N] at constant ``v``: ``s(v) + Fv(v) + offset``."""
    d = sign(v)
    if d == 0.0:
        return p[P_OFFSET]
    return d * stribeck_magnitude(p, d, abs(v)) + viscous(p, v) + p[P_OFFSET]
