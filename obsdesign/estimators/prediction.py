"""Predicted error of a compensated friction estimate: noise propagation plus tracking lag.

The compensation applies ``g f_hat`` (``g`` the compensation gain, ``f_hat`` the estimator's
compensation signal: the paper's low-pass filtered estimate, a baseline's own one) as the estimate
of the friction ``f``. Its error ``f - g f_hat`` has two independent parts:

* **noise**: the measurement noise (band-limited, RMS ``eta``, :func:`~obsdesign.estimators.noise_level`)
  through ``y -> f_hat``: ``g`` times :func:`~obsdesign.estimators.friction_noise_rms`;
* **lag**: the friction itself through the plant and the estimator. The friction is modelled as the
  Coulomb level switching sign at reversals that come at random (a random telegraph signal of
  amplitude ``Cf`` and rate ``lambda`` reversals per second: autocorrelation ``Cf^2 exp(-2 lambda
  |tau|)``), held over each sample; it moves the physical plant at ``u = 0`` (ZOH, :func:`control.c2d`):
  ``static``: ``m v' = -Fc - sigma v`` and the friction to estimate is ``f = Fc``; ``lag``:
  ``m v' = -Fc - Fv``, ``beta Fv' = sigma v - Fv`` and ``f = Fc + Fv = F(z) Fc``. The estimate follows
  through ``Gy(z)`` (:meth:`~obsdesign.estimators.DiscreteEstimator.transfer_from_measurement`): with
  ``T(z) = Gy(z) X(z)`` (``X``: ``Fc -> x``) the error spectrum is ``|F - g T|^2 S(theta)``,
  ``S = Cf^2 (1 - r^2) / |1 - r e^{j theta}|^2``, ``r = exp(-2 lambda dt)``, so::

      lag^2 = A - 2 g B + g^2 C,   A = (1/pi) int_0^pi |F|^2 S,   B = (1/pi) int_0^pi Re(conj(F) T) S,
      C = (1/pi) int_0^pi |T|^2 S

  (``A = Cf^2`` for ``static``, ``F = 1``)

and ``total = sqrt(lag^2 + noise^2)`` (the two are uncorrelated). The moments are integrated on
``log theta`` by 16-point Gauss-Legendre rules over half decades, split at the estimator's pole
frequencies and the reversal corner (``theta >= 1e-8 pi``: below it the error vanishes as
``|F - T| -> 0``), vectorised. At ``k = 0`` (gross sliding), as the noise analysis of section 3.4.

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.estimators import reference_estimator
>>> cfg = od.load_preset("vcm")
>>> p = predict_error(reference_estimator(cfg), cfg)
>>> round(p.total, 5), round(p.noise, 6), round(p.lag, 5)
(0.06539, 0.001232, 0.06538)
>>> p.gain, p.reversal_rate
(1.0, 1.0)
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .._display import ResultDisplay
from ..params import Config
from .base import DiscreteEstimator, check_config
from .kalman import noise_level
from .noise_rms import friction_noise_rms

__all__ = ["ErrorPrediction", "predict_error", "lag_moments", "REVERSAL_RATE"]

#: Default rate of friction reversals [1/s] of the lag model (one reversal per second).
REVERSAL_RATE = 1.0
#: Gauss-Legendre nodes per interval of the lag integral (intervals: half decades of theta, split at the poles).
_NODES = 16


@dataclass(frozen=True, kw_only=True)
class ErrorPrediction(ResultDisplay):
    """The predicted RMS error [N] of ``g f_hat`` as an estimate of the friction.

    Attributes
    ----------
    total : float
        ``sqrt(lag^2 + noise^2)`` [N].
    noise : float
        Noise propagation part [N] (``g`` times the friction-noise RMS).
    lag : float
        Tracking-lag part [N] for Coulomb reversals at ``reversal_rate``.
    gain : float
        The compensation gain ``g`` of the prediction.
    reversal_rate : float
        Reversals per second [1/s] of the lag model.
    """

    _title = "Predicted friction-estimate error"
    total: float
    noise: float
    lag: float
    gain: float
    reversal_rate: float

    def to_dict(self) -> dict:
        """JSON-ready values."""
        return {"total": self.total, "noise": self.noise, "lag": self.lag, "gain": self.gain,
                "reversal_rate": self.reversal_rate}

    def _rows(self):
        return [("total [N]", self.total), ("noise part [N]", self.noise), ("lag part [N]", self.lag),
                ("gain [-]", self.gain), ("reversal rate [1/s]", self.reversal_rate)]


def _response(sys, z: np.ndarray) -> np.ndarray:
    """``D + C (zI - A)^-1 B`` of a SISO state-space system at every point of ``z``."""
    A, B, C, D = (np.asarray(m, float) for m in (sys.A, sys.B, sys.C, sys.D))
    n = A.shape[0]
    if n == 0:
        return np.full(z.shape, D[0, 0], dtype=complex)
    M = z[:, None, None] * np.eye(n)[None] - A[None]
    x = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (z.size, n, 1)))
    return (C @ x)[:, 0, 0] + D[0, 0]


def _factored(sys):
    """``z -> sys(z)`` of a discrete SISO system from its zeros, poles and gain (exact near a pole at 1)."""
    import control as ct

    tf = ct.tf(sys)
    zeros, poles = tf.zeros(), tf.poles()
    num, den = np.trim_zeros(np.squeeze(tf.num[0][0]), "f"), np.squeeze(tf.den[0][0])
    gain = float(num[0] / den[0]) if num.size else 0.0

    def response(z: np.ndarray) -> np.ndarray:
        top = np.prod(z[:, None] - zeros[None, :], axis=1) if zeros.size else np.ones_like(z)
        return gain * top / np.prod(z[:, None] - poles[None, :], axis=1)

    return response


def _plant(cfg: Config, dt: float):
    """:func:`_plant_of` of a config (cached per plant and sample time)."""
    fr = cfg.friction
    return _plant_of(cfg.plant.m, fr.sigma, fr.beta, cfg.observer.variant, dt)


@functools.lru_cache(maxsize=64)
def _plant_of(m: float, sigma: float, beta: float | None, variant: str, dt: float):
    """The physical plant driven by the Coulomb friction ``Fc`` (``u = 0``, ZOH): ``(Fc -> x, Fc -> Fv)``.

    ``static``: ``m v' = -Fc - sigma v``, the estimated friction is ``Fc`` (``Fv`` is none). ``lag``:
    ``m v' = -Fc - Fv``, ``beta Fv' = sigma v - Fv``, the estimated friction is ``Fc + Fv``.
    """
    import control as ct

    if variant == "static" or beta is None:
        sysc = ct.ss([[0.0, 1.0], [0.0, -sigma / m]], [[0.0], [-1.0 / m]], [[1.0, 0.0]], [[0.0]])
        sysd = ct.c2d(sysc, dt, "zoh")
        return _factored(sysd), (lambda z: np.zeros_like(z))
    A = [[0.0, 1.0, 0.0], [0.0, 0.0, -1.0 / m], [0.0, sigma / beta, -1.0 / beta]]
    sysd = ct.c2d(ct.ss(A, [[0.0], [-1.0 / m], [0.0]], [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], [[0.0], [0.0]]), dt, "zoh")
    return _factored(sysd[0, 0]), _factored(sysd[1, 0])


def lag_moments(est: DiscreteEstimator, cfg: Config, *,
                reversal_rate: float = REVERSAL_RATE) -> tuple[float, float, float]:
    """``(A, B, C)`` of the module's lag formula [N^2], for the friction level ``cfg.friction.Cf``.

    Parameters
    ----------
    est : DiscreteEstimator
        The estimator (its ``f_hat`` row is the compensation signal).
    cfg : Config
        Mass, ``Cf`` and the viscous coefficient of the model (:func:`~obsdesign.estimators.paper.model_sigma`).
    reversal_rate : float
        Reversals per second [1/s] (> 0).

    Returns
    -------
    (float, float, float)
        ``lag^2 = A - 2 g B + g^2 C`` (``A = Cf^2`` for ``static``).
    """
    cfg = check_config(cfg)
    lam = float(reversal_rate)
    if not (math.isfinite(lam) and lam > 0.0):
        raise ValueError(f"reversal_rate: expected a finite number > 0 [1/s], found {reversal_rate!r}")
    dt = est.dt
    x_of_f, fv_of_f = _plant(cfg, dt)
    Gy = est.transfer_from_measurement()[1, 0]
    r = math.exp(-2.0 * lam * dt)
    level = cfg.friction.Cf ** 2
    poles = [abs(np.log(p)) for p in np.linalg.eigvals(est.Phi) if p != 0]
    lo, hi = math.log(1e-8 * math.pi), math.log(math.pi)
    cuts = {lo, hi, *np.arange(lo, hi, math.log(10.0) / 2)}
    cuts |= {math.log(c) for c in (*poles, 2.0 * lam * dt) if 1e-8 * math.pi < c < math.pi}
    edges = np.array(sorted(cuts))
    x, w = np.polynomial.legendre.leggauss(_NODES)
    half = np.diff(edges)[:, None] / 2.0
    u = ((edges[:-1, None] + edges[1:, None]) / 2.0 + half * x[None, :]).ravel()
    weights = (half * w[None, :]).ravel()
    theta = np.exp(u)
    z = np.exp(1j * theta)
    T = _response(Gy, z) * x_of_f(z)
    F = 1.0 + fv_of_f(z)                   # the friction the estimate follows, per unit of Coulomb level
    S = level * (1.0 - r * r) / np.abs(1.0 - r * z) ** 2
    common = weights * theta * S / math.pi
    total = (float(np.sum(common * np.abs(F) ** 2)), float(np.sum(common * (np.conj(F) * T).real)),
             float(np.sum(common * np.abs(T) ** 2)))
    return total


def predict_error(est: DiscreteEstimator, cfg: Config, *, gain: float | None = None,
                  reversal_rate: float = REVERSAL_RATE) -> ErrorPrediction:
    """Predicted RMS error of ``gain * f_hat`` as an estimate of the friction (module docstring).

    Parameters
    ----------
    est : DiscreteEstimator
        The estimator whose ``f_hat`` is compensated (for the paper's observer: with its low-pass,
        :func:`~obsdesign.estimators.reference_estimator`).
    cfg : Config
        The design: sensor noise, ``m``, ``Cf``, the model's viscous coefficient.
    gain : float, optional
        Compensation gain in (0, 1]; default ``cfg.compensation.gain``.
    reversal_rate : float
        Reversals per second [1/s] of the lag model.

    Returns
    -------
    ErrorPrediction
        ``inf`` parts for an estimator with a pole on or outside the unit circle.
    """
    cfg = check_config(cfg)
    g = cfg.compensation.gain if gain is None else float(gain)
    if not (math.isfinite(g) and 0.0 < g <= 1.0):
        raise ValueError(f"gain: expected a finite number > 0 and <= 1, found {gain!r}")
    if not float(np.max(np.abs(est.poles()))) < 1.0:
        return ErrorPrediction(total=math.inf, noise=math.inf, lag=math.inf, gain=g, reversal_rate=reversal_rate)
    noise = g * friction_noise_rms(est, *noise_level(cfg))
    A, B, C = lag_moments(est, cfg, reversal_rate=reversal_rate)
    lag = math.sqrt(max(A - 2.0 * g * B + g * g * C, 0.0))
    return ErrorPrediction(total=math.hypot(lag, noise), noise=noise, lag=lag, gain=g,
                           reversal_rate=float(reversal_rate))
