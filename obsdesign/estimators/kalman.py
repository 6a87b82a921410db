"""Steady-state Kalman filter with a random-walk friction state, designed in discrete time.

Model at the sample time ``dt`` (exact ZOH of ``x' = v``, ``m v' = u - sigma_model v - f``,
``f' = w``)::

    w[n] = Ad w[n-1] + Bd u[n-1] + G e[n-1],   y[n] = c w[n] + eta[n]

with ``w = (x, v, f)``, ``G = (0, 0, 1)``, process noise variance ``q dt`` per step (``q``
[N^2/s], the intensity of the friction random walk: the tuning knob) and measurement noise
variance ``R = eta^2`` (the sensor RMS, :func:`noise_level`). python-control's ``dlqe``
returns the a-priori covariance ``P`` of the stationary filter; the "current estimator"
(filtered) form uses the innovation gain ``M = P c^T / (c P c^T + R)``::

    w_hat[n|n] = (I - M c) (Ad w_hat[n-1|n-1] + Bd u[n-1]) + M y[n]

so ``z = w_hat[n|n]``, ``Phi = (I - M c) Ad``, ``gu = (I - M c) Bd``, ``g0 = 0``, ``g1 = M``.
(``dlqe``'s own gain ``L = Ad M`` is that of the predictor form.)

Examples
--------
>>> import obsdesign as od, numpy as np
>>> est = build_kalman(od.load_preset("vcm"), q=1.0)
>>> est.nz, bool(np.all(np.abs(est.poles()) < 1.0)), est.g0.tolist()
(3, True, [0.0, 0.0, 0.0])
"""

from __future__ import annotations

import math

import numpy as np

from .._memo import memo
from ..params import Config
from .base import DiscreteEstimator, check_config, check_positive, foh_matrices
from .paper import model_sigma

__all__ = ["build_kalman", "kalman_model", "noise_level"]


def noise_level(cfg: Config) -> tuple[float, float]:
    """``(eta, B)``: sensor noise RMS [m] and bandwidth [Hz] as in :func:`obsdesign.noise_analysis`.

    Parameters
    ----------
    cfg : Config
        The design; its sensor section.

    ``eta = sqrt(noise_rms^2 + quantization^2/12)`` (the encoder's rounding as uniform noise).

    >>> import obsdesign as od
    >>> eta, B = noise_level(od.load_preset("vcm"))
    >>> round(eta * 1e9, 2), B          # 1 um / sqrt(12)
    (288.68, 1000.0)
    """
    s = check_config(cfg).sensor
    return math.hypot(s.noise_rms, s.quantization / math.sqrt(12.0)), float(s.noise_bandwidth)


def kalman_model(m: float, sigma_model: float, dt: float):
    """``(Ad, Bd, c, G)`` of the sampled model with the friction as a random walk.

    Parameters
    ----------
    m : float
        Mass [kg].
    sigma_model : float
        Viscous coefficient of the model [N s/m].
    dt : float
        Sample time [s].
    """
    A = np.array([[0.0, 1.0, 0.0], [0.0, -sigma_model / m, -1.0 / m], [0.0, 0.0, 0.0]])
    Ad, G0, _ = foh_matrices(A, dt)
    Bd = G0 @ np.array([0.0, 1.0 / m, 0.0])
    return Ad, Bd, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0], [0.0], [1.0]])


def _is_3x3(value) -> bool:
    return (isinstance(value, list) and len(value) == 3
            and all(isinstance(r, list) and len(r) == 3 and all(isinstance(x, float) for x in r) for r in value))


def _riccati(Ad: np.ndarray, G: np.ndarray, c_scaled: np.ndarray, q_dt: float) -> np.ndarray:
    """The steady-state prediction covariance of python-control's ``dlqe`` with the outputs scaled to unit
    noise (``R = 1``, a well-conditioned Riccati equation); kept in the result memo (:mod:`obsdesign._memo`),
    so a warm process imports no python-control for it."""
    def solve():
        import control as ct

        _, P, _ = ct.dlqe(Ad, G, c_scaled, np.array([[q_dt]]), np.eye(1))
        return np.asarray(P, dtype=float).tolist()

    return np.array(memo("dlqe", (Ad, G, c_scaled, q_dt), solve, valid=_is_3x3))


def build_kalman(cfg: Config, *, q: float, measurement_rms: float | None = None,
                 sigma_model: float | None = None, tuning: str = "manual") -> DiscreteEstimator:
    """Steady-state Kalman filter (current-estimator form) at ``cfg.observer.dt``.

    Parameters
    ----------
    q : float
        Intensity of the friction random walk [N^2/s]; its variance per sample is ``q dt``.
    measurement_rms : float, optional
        Measurement noise RMS [m]; default the sensor's (:func:`noise_level`).
    cfg : Config
        The design (plant, sensor, sample time).
    sigma_model : float, optional
        Viscous coefficient of the model (default from the variant).
    tuning : str
        How the knob was chosen (recorded in the result).

    Raises
    ------
    ValueError
        ``q`` or the measurement RMS not a finite number > 0 (the filter needs ``R > 0``).
    """
    cfg = check_config(cfg)
    q = check_positive("q", q, "N^2/s")
    eta = noise_level(cfg)[0] if measurement_rms is None else measurement_rms
    eta = check_positive("measurement_rms (sensor noise_rms or quantization)", eta, "m")
    m, sig, dt = cfg.plant.m, model_sigma(cfg, sigma_model), cfg.observer.dt
    Ad, Bd, c, G = kalman_model(m, sig, dt)
    R = eta * eta
    P = _riccati(Ad, G, c / eta, q * dt)
    M = P @ c.T / (c @ P @ c.T + R)           # innovation gain, shape (3, 1)
    IMC = np.eye(3) - M @ c
    Phi = IMC @ Ad
    radius = float(np.max(np.abs(np.linalg.eigvals(Phi))))
    return DiscreteEstimator(
        name="kalman", dt=dt, Phi=Phi, gu=IMC @ Bd, g0=np.zeros(3), g1=M.ravel(),
        Cz=np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), d=np.zeros(2),
        params={"q": q, "measurement_rms": eta, "sigma_model": sig, "m": m,
                "M": M.ravel().tolist(), "slowest_pole": math.log(radius) / dt,
                "fastest_pole": math.log(float(np.min(np.abs(np.linalg.eigvals(Phi))))) / dt},
        tuning=tuning, init=np.eye(3),
    )
