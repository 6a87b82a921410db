"""Linear extended state observer (ESO) with bandwidth parameterization (Gao 2003).

Model: states ``(x, v, f)``, ``x' = v``, ``m v' = u - sigma_model v - f``, ``f' = 0``
(the friction as an unknown constant, driven by its unmodelled rate), output ``x``.
The observer ``w_hat' = A w_hat + b u + l (y - x_hat)`` has error matrix ``A - l c`` with
characteristic polynomial::

    s^3 + (l1 + a) s^2 + (a l1 + l2) s - l3/m,     a = sigma_model / m

Placing all three roots at ``-omega_o``, ``(s + omega_o)^3``, gives::

    l1 = 3 omega_o - a,   l2 = 3 omega_o^2 - a l1,   l3 = -m omega_o^3

Discrete form: ``z = w_hat``, exact ZOH for ``u`` and FOH for ``y``
(:func:`obsdesign.estimators.base.discretize_observer`), ``Cz`` picks ``(v, f)``, ``d = 0``.
The discrete poles are ``exp(-omega_o dt)`` (triple).

Its friction estimate is ``f_hat = Q(s) (u - (m s^2 + sigma_model s) y)`` with
``Q(s) = omega_o^3/(s + omega_o)^3``: a disturbance observer with a third-order binomial Q.

Examples
--------
>>> import obsdesign as od, numpy as np
>>> est = build_eso(od.load_preset("vcm"), omega_o=300.0)
>>> pole = np.exp(-300.0 * 1e-4)         # characteristic polynomial (z - pole)^3
>>> est.nz, bool(np.allclose(np.poly(est.Phi), np.poly([pole] * 3), rtol=0, atol=1e-12))
(3, True)
"""

from __future__ import annotations

import numpy as np

from ..params import Config
from .base import DiscreteEstimator, check_config, check_positive, discretize_observer
from .paper import model_sigma

__all__ = ["build_eso", "eso_gains", "eso_continuous"]


def eso_gains(omega_o: float, m: float, sigma_model: float) -> np.ndarray:
    """``(l1, l2, l3)`` placing the three error poles at ``-omega_o``.

    Parameters
    ----------
    omega_o : float
        Observer bandwidth [rad/s].
    m : float
        Mass [kg].
    sigma_model : float
        Viscous coefficient of the model [N s/m].

    >>> eso_gains(10.0, 1.0, 0.0).tolist()
    [30.0, 300.0, -1000.0]
    """
    a = sigma_model / m
    l1 = 3.0 * omega_o - a
    return np.array([l1, 3.0 * omega_o**2 - a * l1, -m * omega_o**3])


def eso_continuous(omega_o: float, m: float, sigma_model: float):
    """``(A, b, c, l)`` of the continuous model and gains; the error matrix is ``A - l c``.

    Parameters
    ----------
    omega_o : float
        Observer bandwidth [rad/s].
    m : float
        Mass [kg].
    sigma_model : float
        Viscous coefficient of the model [N s/m].
    """
    A = np.array([[0.0, 1.0, 0.0], [0.0, -sigma_model / m, -1.0 / m], [0.0, 0.0, 0.0]])
    b = np.array([0.0, 1.0 / m, 0.0])
    c = np.array([1.0, 0.0, 0.0])
    return A, b, c, eso_gains(omega_o, m, sigma_model)


def build_eso(cfg: Config, *, omega_o: float, sigma_model: float | None = None,
              tuning: str = "manual") -> DiscreteEstimator:
    """ESO with all error poles at ``-omega_o`` [rad/s], discretized at ``cfg.observer.dt``.

    Parameters
    ----------
    cfg : Config
        The design (plant, sensor, sample time).
    omega_o : float
        Observer bandwidth [rad/s].
    sigma_model : float, optional
        Viscous coefficient of the model (default from the variant).
    tuning : str
        How the knob was chosen (recorded in the result).

    Raises
    ------
    ValueError
        ``omega_o`` not a finite number > 0.
    """
    cfg = check_config(cfg)
    w = check_positive("omega_o", omega_o, "rad/s")
    m, sig = cfg.plant.m, model_sigma(cfg, sigma_model)
    A, b, c, l = eso_continuous(w, m, sig)  # noqa: E741 (the gain vector l of the docstring)
    Phi, gu, g0, g1 = discretize_observer(A - np.outer(l, c), b, l, cfg.observer.dt)
    return DiscreteEstimator(
        name="eso", dt=cfg.observer.dt, Phi=Phi, gu=gu, g0=g0, g1=g1,
        Cz=np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), d=np.zeros(2),
        params={"omega_o": w, "l1": float(l[0]), "l2": float(l[1]), "l3": float(l[2]), "sigma_model": sig,
                "m": m, "slowest_pole": -w, "fastest_pole": -w},
        tuning=tuning, init=np.eye(3),
    )
