"""The sampled loop that runs with the friction compensation (the constraint of :func:`obsdesign.design.tune`).

Broken at the controller's output, ``L(z) = z^-d (C - g Gy / K) H_zoh - g Gu``: the ZOH plant ``H_zoh`` and
the kernel's discrete PID ``C`` of :mod:`obsdesign.design.sampled_loop`, the drive's delay ``d`` between the
command and the plant (``[hardware] delay_samples``), and the compensation ``g f_hat / K`` whose estimate
sees the measurement (``Gy``) and the controller's own command ``K c`` (``Gu``; the kernel feeds the
estimator the force it commanded over the last interval, undelayed: the controller does not know the
drive's delay). The measurement noise reaches the command through ``(-C + g Gy / K) / (1 + L)``. With
``g -> 0`` it is the loop of :func:`obsdesign.design.sampled_loop.sampled_loop`.

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.estimators import reference_estimator
>>> cfg = od.load_preset("vcm")
>>> pm, stable, noise = compensated_loop(cfg, reference_estimator(cfg), 1e-12)
>>> round(pm, 2), stable                       # the sampled loop without compensation
(60.02, True)
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..params import Config

__all__ = ["compensated_loop", "LOOP_POINTS"]


def compensated_loop(cfg: Config, est, gain: float) -> tuple[float, bool, float]:
    """``(phase margin [deg], closed loop stable, command noise RMS [V])`` of the compensated sampled loop.

    Parameters
    ----------
    cfg : Config
        The design (PID, plant, delay, sensor noise).
    est : DiscreteEstimator
        The estimator whose filtered ``f_hat`` is compensated (the paper's: with its low-pass).
    gain : float
        The compensation gain.

    The margin is the smallest ``180 + arg L`` (wrapped to (-180, 180]) over the gain crossovers on a
    log grid of :data:`LOOP_POINTS` frequencies up to Nyquist, each crossover located by linear
    interpolation of ``log |L|``; the stability from the closed loop's poles (python-control).
    """
    import control as ct

    from ..estimators import noise_level

    dt, d, K = cfg.observer.dt, cfg.hardware.delay_samples, cfg.plant.K
    from .pid_sampled import sampled_pid_gains

    C, H = _pid_and_plant(*sampled_pid_gains(cfg), cfg.phi, cfg.pid.tau, dt)
    Gy = est.transfer_from_measurement()[1, 0]
    Gu = est.transfer_from_input()[1, 0]
    delay = ct.ss(ct.tf([1.0], [1.0] + [0.0] * d, dt)) if d else ct.ss([], [], [], [[1.0]], dt)
    L = delay * (C - (gain / K) * Gy) * H - gain * Gu  # one copy of the plant's states
    if not float(np.max(np.abs(ct.feedback(L, 1).poles()))) < 1.0:
        return -math.inf, False, math.inf

    def loop(theta):
        z = np.exp(1j * theta)
        r = {name: _freq(sys, z) for name, sys in (("C", C), ("H", H), ("Gy", Gy), ("Gu", Gu))}
        zd = z ** (-d)
        Lz = zd * (r["C"] * r["H"] - (gain / K) * r["Gy"] * r["H"]) - gain * r["Gu"]
        return Lz, (-r["C"] + (gain / K) * r["Gy"]) / (1.0 + Lz)

    theta = np.geomspace(1e-7 * math.pi, math.pi, LOOP_POINTS)
    Lz, _ = loop(theta)
    mag = np.log(np.abs(Lz))
    pms = []
    for i in np.flatnonzero(np.sign(mag[:-1]) != np.sign(mag[1:])):
        f = mag[i] / (mag[i] - mag[i + 1])
        th = math.exp(math.log(theta[i]) + f * (math.log(theta[i + 1]) - math.log(theta[i])))
        pms.append((math.degrees(np.angle(loop(np.array([th]))[0][0])) + 360.0) % 360.0 - 180.0)
    pm = min(pms) if pms else math.inf
    eta, band = noise_level(cfg)
    top = min(2.0 * math.pi * band * dt, math.pi)
    theta = np.linspace(0.0, top, 2049)[1:]
    _, Tn = loop(theta)
    power = np.trapezoid(np.abs(Tn) ** 2, theta) / top
    return float(pm), True, float(eta * math.sqrt(power))


@functools.lru_cache(maxsize=16)
def _pid_and_plant(kp, ki, kd, tau_d, phi, tau, dt):
    """The kernel's discrete PID (the config's, :func:`~obsdesign.design.pid.sampled_pid_gains`) and the ZOH
    plant of :mod:`obsdesign.design.sampled_loop`, as state space."""
    import control as ct

    from .sampled_loop import discrete_pid, zoh_plant

    return (ct.ss(discrete_pid(kp=kp, ki=ki, kd=kd, tau_d=tau_d, dt=dt)),
            ct.ss(zoh_plant(phi=phi, tau=tau, dt=dt)))


#: Frequencies of the margin search (log grid from 1e-7 of Nyquist to Nyquist).
LOOP_POINTS = 2000


def _freq(sys, z: np.ndarray) -> np.ndarray:
    """Frequency response of a SISO state-space system at the points ``z``."""
    from ..estimators.prediction import _response

    return _response(sys, z)
