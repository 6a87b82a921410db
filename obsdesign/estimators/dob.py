"""Classical disturbance observer (DOB) with a binomial Q-filter, in its minimal realization.

With the nominal plant ``P_n(s) = 1/(m s^2 + sigma_model s)`` and
``Q(s) = omega_q^2/(s + omega_q)^2`` (relative degree 2, the least that makes
``Q P_n^-1`` proper) the friction estimate is the block diagram::

    f_hat = Q(s) u - Q(s) (m s^2 + sigma_model s) y

This transfer has McMillan degree 2. Its minimal realization is a linear reduced-order
observer of ``(v, f)`` (the paper's structure eq:3:1:2-3 at ``k = 0``) with both poles at
``-omega_q``::

    L1 = 2 omega_q - sigma_model/m,   L2 = -m omega_q^2
    ytilde' = [[-a - L1, -1/m], [-L2, 0]] ytilde + (1/m, 0) u + g y,   a = sigma_model/m
    g = (-a L1 - L2/m - L1^2, -L1 L2),   (v_hat, f_hat) = ytilde + (L1, L2) y

(:func:`dob_continuous` returns it; the tests check it against the block diagram.)

Velocity: the same realization gives ``v_hat = Q s y + s/(s + omega_q)^2 (u/m + L1 s y)``, the
derivative filtered by the same Q plus a model-based correction of Q's lag. It is unbiased for
a constant friction under any input; the plain filtered derivative ``s Q y`` is not (under a
2 Hz sine it lags the velocity by about ``2 omega / omega_q`` of its amplitude).

Discrete form: ``z = ytilde``, exact ZOH for ``u`` and FOH for ``y`` (the kernel's 2x2
recursion), ``Cz = I``, ``d = (L1, L2)``.

Examples
--------
>>> import obsdesign as od
>>> est = build_dob(od.load_preset("vcm"), omega_q=200.0)
>>> est.nz, est.d.round(4).tolist()          # (L1, L2) = (2 omega_q - sigma/m, -m omega_q^2)
(2, [360.7807, -21520.0])
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..params import Config
from .base import DiscreteEstimator, check_config, check_positive
from .paper import model_sigma, step_matrices

if TYPE_CHECKING:
    import control as ct

__all__ = ["build_dob", "q_filter", "dob_continuous"]


def q_filter(omega_q: float) -> ct.TransferFunction:
    """``Q(s) = omega_q^2/(s + omega_q)^2`` as a python-control transfer function (unit DC gain).

    Parameters
    ----------
    omega_q : float
        Cutoff [rad/s].

    >>> float(q_filter(3.0).dcgain())
    1.0
    """
    import control as ct

    w = check_positive("omega_q", omega_q, "rad/s")
    return ct.tf([w * w], [1.0, 2.0 * w, w * w])


def _matrices(w: float, m: float, sig: float):
    a = sig / m
    L1, L2 = 2.0 * w - a, -m * w * w
    A = np.array([[-a - L1, -1.0 / m], [-L2, 0.0]])
    b = np.array([1.0 / m, 0.0])
    g = np.array([-a * L1 - L2 / m - L1 * L1, -L1 * L2])
    return A, b, g, np.array([L1, L2])


def dob_continuous(omega_q: float, m: float, sigma_model: float) -> ct.StateSpace:
    """The continuous realization: inputs ``(u, y)``, outputs ``(v_hat, f_hat)``.

    Parameters
    ----------
    omega_q : float
        Q-filter cutoff [rad/s].
    m : float
        Mass [kg].
    sigma_model : float
        Viscous coefficient of the nominal model [N s/m].
    """
    import control as ct

    A, b, g, L = _matrices(check_positive("omega_q", omega_q, "rad/s"), m, sigma_model)
    return ct.ss(A, np.column_stack([b, g]), np.eye(2), np.column_stack([np.zeros(2), L]),
                 inputs=["u", "x_meas"], outputs=["v_hat", "f_hat"])


def build_dob(cfg: Config, *, omega_q: float, sigma_model: float | None = None,
              tuning: str = "manual") -> DiscreteEstimator:
    """DOB with Q-filter cutoff ``omega_q`` [rad/s], discretized at ``cfg.observer.dt``.

    Parameters
    ----------
    cfg : Config
        The design (plant, sensor, sample time).
    omega_q : float
        Q-filter cutoff [rad/s].
    sigma_model : float, optional
        Viscous coefficient of the nominal model (default from the variant).
    tuning : str
        How the knob was chosen (recorded in the result).

    Raises
    ------
    ValueError
        ``omega_q`` not a finite number > 0.
    """
    cfg = check_config(cfg)
    w = check_positive("omega_q", omega_q, "rad/s")
    m, sig = cfg.plant.m, model_sigma(cfg, sigma_model)
    A, b, g, L = _matrices(w, m, sig)
    Phi, gu, g0, g1 = step_matrices(A, b, g, cfg.observer.dt)
    return DiscreteEstimator(
        name="dob", dt=cfg.observer.dt, Phi=Phi, gu=gu, g0=g0, g1=g1, Cz=np.eye(2), d=L,
        params={"omega_q": w, "q_order": 2, "L1": float(L[0]), "L2": float(L[1]), "sigma_model": sig, "m": m,
                "slowest_pole": -w, "fastest_pole": -w},
        tuning=tuning, init=np.column_stack([-L, np.eye(2)]),
    )
