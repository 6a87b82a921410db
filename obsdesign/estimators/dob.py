"""Classical disturbance observer (DOB) with a binomial Q-filter.

With the nominal plant ``P_n(s) = 1/(m s^2 + sigma_model s)`` and
``Q(s) = omega_q^2/(s + omega_q)^2`` (relative degree 2, the least that makes
``Q P_n^-1`` proper), the friction and velocity estimates are::

    f_hat = Q(s) u - Q(s) (m s^2 + sigma_model s) y,     v_hat = s Q(s) y

(the velocity is the derivative of ``y`` filtered by the same Q). Realization with
``nz = 4``: ``(zeta1, zeta2) = (Q y, s Q y)`` and ``(mu1, mu2) = (Q u, s Q u)``, each
``zeta1' = zeta2``, ``zeta2' = omega_q^2 (y - zeta1) - 2 omega_q zeta2``, so that
``s^2 Q y = zeta2'`` and::

    f_hat = mu1 + m omega_q^2 zeta1 + (2 m omega_q - sigma_model) zeta2 - m omega_q^2 y
    v_hat = zeta2

Discrete form: exact ZOH for ``u`` and FOH for ``y`` of this block-diagonal system.

Notes
-----
Its friction estimate equals that of a linear reduced-order observer (the paper's
structure at ``k = 0``) with a double pole at ``-omega_q``: ``L1 = 2 omega_q - sigma_model/m``,
``L2 = -m omega_q^2``. With a third-order Q it would equal the ESO's (see :mod:`.eso`).

Examples
--------
>>> import obsdesign as od
>>> est = build_dob(od.load_preset("vcm"), omega_q=200.0)
>>> est.nz, est.d.tolist()          # the -m omega_q^2 feedthrough of y into f_hat
(4, [0.0, -21520.0])
"""

from __future__ import annotations

import numpy as np

from ..params import Config
from .base import DiscreteEstimator, check_positive, foh_matrices
from .paper import _check_config, model_sigma

__all__ = ["build_dob", "q_filter"]


def q_filter(omega_q: float):
    """``Q(s) = omega_q^2/(s + omega_q)^2`` as a python-control transfer function (unit DC gain).

    >>> q_filter(3.0).dcgain()
    np.float64(1.0)
    """
    import control as ct

    w = check_positive("omega_q", omega_q, "rad/s")
    return ct.tf([w * w], [1.0, 2.0 * w, w * w])


def build_dob(cfg: Config, *, omega_q: float, sigma_model: float | None = None,
              tuning: str = "manual") -> DiscreteEstimator:
    """DOB with Q-filter cutoff ``omega_q`` [rad/s], discretized at ``cfg.observer.dt``.

    Raises
    ------
    ValueError
        ``omega_q`` not a finite number > 0.
    """
    cfg = _check_config(cfg)
    w = check_positive("omega_q", omega_q, "rad/s")
    m, sig = cfg.plant.m, model_sigma(cfg, sigma_model)
    block = np.array([[0.0, 1.0], [-w * w, -2.0 * w]])
    A = np.zeros((4, 4))
    A[:2, :2] = block
    A[2:, 2:] = block
    b_u = np.array([0.0, 0.0, 0.0, w * w])
    b_y = np.array([0.0, w * w, 0.0, 0.0])
    Phi, G0, G1 = foh_matrices(A, cfg.observer.dt)
    Cz = np.array([[0.0, 1.0, 0.0, 0.0], [m * w * w, 2.0 * m * w - sig, 1.0, 0.0]])
    d = np.array([0.0, -m * w * w])
    # Start: Q y = x0, s Q y = v0, Q u chosen so that f_hat = f0 at y = x0.
    init = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -(2.0 * m * w - sig), 1.0], [0.0, 0.0, 0.0]])
    return DiscreteEstimator(
        name="dob", dt=cfg.observer.dt, Phi=Phi, gu=G0 @ b_u, g0=(G0 - G1) @ b_y, g1=G1 @ b_y, Cz=Cz, d=d,
        params={"omega_q": w, "q_order": 2, "sigma_model": sig, "m": m, "slowest_pole": -w, "fastest_pole": -w},
        tuning=tuning, init=init,
    )
