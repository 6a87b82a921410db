"""Reference driver: a friction-loaded mass integrated like the simulator's plant loop (numba).

Used by the tests and benchmarks; the closed-loop kernel (:mod:`obsdesign.sim.kernel`)
runs the same substep sequence.

Examples
--------
>>> import numpy as np
>>> from obsdesign.friction.registry import FRICTION_MODELS
>>> info = FRICTION_MODELS["lugre"]
>>> p = info.pack({})
>>> x, v, F = simulate_block(info.code, p, np.full(2000, 0.3), 0.538, 1e-4, 10)
>>> bool(abs(x[-1]) < 1e-5)  # 0.3 N stays below the breakaway level Fs = 0.525 N
True
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import friction_advance, friction_force, friction_init, friction_n_state, friction_plant_step

__all__ = ["simulate_block", "drive_displacement"]


@njit(cache=True, error_model="numpy")
def simulate_block(code, p, u, m, dt, n_sub, x0=0.0, v0=0.0):
    """Mass ``m x'' = u - F`` under a force sequence ``u`` held per sample.

    Parameters
    ----------
    code : int
        Model code (``lugre`` 1, ``dahl`` 2, ``gms`` 3).
    p : ndarray of float64
        Packed parameters (:meth:`FrictionModelInfo.pack`).
    u : ndarray of float64, shape (n,)
        Applied force [N] per sample (zero-order hold).
    m : float
        Mass [kg].
    dt : float
        Sample time [s].
    n_sub : int
        Heun substeps per sample (``h = dt / n_sub``).
    x0, v0 : float
        Initial displacement [m] and velocity [m/s]; the friction state starts at rest at ``x0``.

    Returns
    -------
    x, v, F : ndarray of float64, shape (n,)
        Displacement, velocity and friction force at the start of each sample.

    Notes
    -----
    Per substep: stage 1 at ``(x, v)``, stage 2 at the Euler predictor, the
    friction state held in both, then :func:`friction_advance`.
    """
    n = u.shape[0]
    h = dt / n_sub
    st = np.zeros(friction_n_state(code, p))
    friction_init(code, p, st, x0)
    x = x0
    v = v0
    out_x = np.empty(n)
    out_v = np.empty(n)
    out_f = np.empty(n)
    for k in range(n):
        out_x[k] = x
        out_v[k] = v
        out_f[k] = friction_force(code, p, st, x, v)
        x, v = friction_plant_step(code, p, st, x, v, u[k], m, h, n_sub)
    return out_x, out_v, out_f


@njit(cache=True, error_model="numpy")
def drive_displacement(code, p, x, v, h):
    """Friction force along a prescribed motion: ``x[k]``, ``v[k]`` at steps of ``h`` [s].

    Returns ``F[k]`` evaluated at ``(x[k], v[k])`` after advancing the state to
    sample ``k`` (the state starts at rest at ``x[0]``).
    """
    n = x.shape[0]
    st = np.zeros(friction_n_state(code, p))
    friction_init(code, p, st, x[0])
    out = np.empty(n)
    for k in range(n):
        if k > 0:
            friction_advance(code, p, st, x[k], v[k], h)
        out[k] = friction_force(code, p, st, x[k], v[k])
    return out
