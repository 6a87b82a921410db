"""Dispatch on the integer model code: the functions the simulator kernel calls (numba).

Codes: those of :data:`obsdesign.friction.registry.FRICTION_MODELS` (``paper`` is reserved:
its kernel is :mod:`obsdesign.friction.presliding`). ``p`` comes from
:meth:`obsdesign.friction.registry.FrictionModelInfo.pack`, ``st`` has
:func:`friction_n_state` entries. Calling convention inside one plant substep
of length ``h`` (Heun, as in :mod:`obsdesign.sim.kernel`)::

    F1 = friction_force(code, p, st, x, v)            # stage 1, st held
    F2 = friction_force(code, p, st, x_pred, v_pred)  # stage 2, st held
    ... x, v updated ...
    friction_advance(code, p, st, x, v, h)            # st to the end of the substep

:func:`friction_plant_step` is that substep, ``n_sub`` times (the simulator's plant and
:mod:`obsdesign.friction.driver` run it), with the model's functions compiled into its loop.

An unknown code (including ``paper``) gives NaN forces, so a wiring mistake
shows up as a diverged run instead of a silently frictionless plant.

Examples
--------
>>> from obsdesign.friction.registry import FRICTION_MODELS
>>> info = FRICTION_MODELS["dahl"]
>>> p = info.pack({})
>>> import numpy as np
>>> st = np.zeros(friction_n_state(info.code, p))
>>> friction_init(info.code, p, st, 0.0)
>>> friction_force(info.code, p, st, 0.0, 0.0)
0.0
>>> friction_stiffness(info.code, p, st, 0.0, 0.0)  # sigma0 at rest
100000.0
>>> round(stribeck(info.code, p, 0.01), 6)  # Cf + sigma v
0.561
"""

from __future__ import annotations

import math

from numba import njit

from .common import viscous
from .dahl import N_STATE as DAHL_N_STATE
from .dahl import dahl_advance, dahl_force, dahl_init, dahl_steady, dahl_stiffness
from .gms import gms_advance, gms_force, gms_init, gms_n_state, gms_steady, gms_stiffness
from .lugre import N_STATE as LUGRE_N_STATE
from .lugre import lugre_advance, lugre_force, lugre_init, lugre_steady, lugre_stiffness
from .registry import DAHL, GMS, LUGRE

__all__ = ["friction_n_state", "friction_init", "friction_force", "friction_advance",
           "friction_viscous", "friction_stiffness", "friction_plant_step", "stribeck"]


@njit(cache=True, error_model="numpy")
def friction_n_state(code: int, p) -> int:
    """Length of the state array of model ``code`` with parameters ``p`` (0 if unknown)."""
    if code == LUGRE:
        return LUGRE_N_STATE
    if code == DAHL:
        return DAHL_N_STATE
    if code == GMS:
        return gms_n_state(p)
    return 0


@njit(cache=True, error_model="numpy")
def friction_init(code: int, p, st, x0: float) -> None:
    """Set ``st`` for a start at rest at ``x0`` [m]."""
    if code == LUGRE:
        lugre_init(p, st, x0)
    elif code == DAHL:
        dahl_init(p, st, x0)
    elif code == GMS:
        gms_init(p, st, x0)


@njit(cache=True, error_model="numpy")
def friction_force(code: int, p, st, x: float, v: float) -> float:
    """Total friction force ``F`` [N] at ``(x, v)`` with ``st`` held (plant: ``m x'' = u - F``)."""
    if code == LUGRE:
        return lugre_force(p, st, x, v)
    if code == DAHL:
        return dahl_force(p, st, x, v)
    if code == GMS:
        return gms_force(p, st, x, v)
    return math.nan


@njit(cache=True, error_model="numpy")
def friction_advance(code: int, p, st, x: float, v: float, h: float) -> None:
    """Advance ``st`` in place over a substep of length ``h`` [s] that ended at ``(x, v)``."""
    if code == LUGRE:
        lugre_advance(p, st, x, v, h)
    elif code == DAHL:
        dahl_advance(p, st, x, v, h)
    elif code == GMS:
        gms_advance(p, st, x, v, h)


@njit(cache=True, error_model="numpy")
def friction_viscous(code: int, p, v: float) -> float:
    """The model's linear viscous part [N] (``sigma v`` or ``sigma_neg v``); same for every code."""
    return viscous(p, v)


@njit(cache=True, error_model="numpy")
def friction_stiffness(code: int, p, st, x: float, v: float) -> float:
    """Pre-sliding stiffness ``dF/dx`` [N/m] (>= 0) along the motion at held velocity."""
    if code == LUGRE:
        return lugre_stiffness(p, st, x, v)
    if code == DAHL:
        return dahl_stiffness(p, st, x, v)
    if code == GMS:
        return gms_stiffness(p, st, x, v)
    return math.nan


@njit(cache=True, error_model="numpy")
def stribeck(code: int, p, v: float) -> float:
    """Steady-state friction [N] at constant velocity ``v`` (includes ``offset``; ``offset`` at ``v = 0``)."""
    if code == LUGRE:
        return lugre_steady(p, v)
    if code == DAHL:
        return dahl_steady(p, v)
    if code == GMS:
        return gms_steady(p, v)
    return math.nan


@njit(cache=True, error_model="numpy", inline="always")
def _heun_substeps(force, advance, p, st, x, v, u, m, h, n_sub):
    """``n_sub`` Heun substeps of ``m x'' = u - F`` with the model functions ``force`` and ``advance``
    (``F`` with the state held in both stages, then ``advance``)."""
    for _ in range(n_sub):
        k1v = (u - force(p, st, x, v)) / m
        xp = x + h * v
        vp = v + h * k1v
        k2v = (u - force(p, st, xp, vp)) / m
        x += 0.5 * h * (v + vp)
        v += 0.5 * h * (k1v + k2v)
        advance(p, st, x, v, h)
    return x, v


def _inlined(fn):
    """The numba function ``fn`` compiled into each caller: the same source, so the same arithmetic.

    The plant loop below evaluates a model's force twice and advances it once a substep; as calls
    between separately compiled functions that costs more than the model itself (the dispatch of
    :mod:`obsdesign.friction.kernels` keeps the ordinary calls, and its short compile time).
    """
    return njit(cache=True, error_model="numpy", inline="always")(fn.py_func)


_lugre_force, _lugre_advance = _inlined(lugre_force), _inlined(lugre_advance)
_dahl_force, _dahl_advance = _inlined(dahl_force), _inlined(dahl_advance)
_gms_force, _gms_advance = _inlined(gms_force), _inlined(gms_advance)


@njit(cache=True, error_model="numpy", inline="never")
def friction_plant_step(code, p, st, x, v, u, m, h, n_sub):
    """``(x, v)`` after ``n_sub`` Heun substeps of length ``h`` [s] of ``m x'' = u - F`` with model
    ``code`` (``F`` with ``st`` held in both stages, then :func:`friction_advance`; ``u`` [N] held).

    One loop per model with the model's force and advance compiled into it; an unknown code gives
    NaN, as :func:`friction_force` does.
    """
    if code == LUGRE:
        return _heun_substeps(_lugre_force, _lugre_advance, p, st, x, v, u, m, h, n_sub)
    if code == DAHL:
        return _heun_substeps(_dahl_force, _dahl_advance, p, st, x, v, u, m, h, n_sub)
    if code == GMS:
        return _heun_substeps(_gms_force, _gms_advance, p, st, x, v, u, m, h, n_sub)
    return math.nan, math.nan
