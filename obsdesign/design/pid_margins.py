"""The sampled PID loop's margins in NumPy: the loop ``C(z) H_zoh(z) z^-d`` of :mod:`obsdesign.design.pid_sampled`.

The kernel's discrete PID with its derivative filter ``tau_d = kd / (kp N)`` (:func:`derivative_time`, its one
definition), the ZOH of the design model eq:linplant and the drive's delay, written in powers of ``z - 1``
(:func:`delta_loop_polynomials`) so that fast sampling keeps its digits; the margins at the gain crossovers
(:func:`~obsdesign.design.margins.gain_crossovers`), the ``|S|`` peak and the gain margin
(:func:`sampled_loop_margins`). What :func:`~obsdesign.design.pid_sampled.resolve_pid` designs on; no SymPy,
no python-control (the tests check these margins against python-control's).

Examples
--------
>>> from obsdesign.design.pid_sampled import pid_gains
>>> k, T_I, *_ = pid_gains(phi=0.0407, tau=0.006675, max_S=1/400, phase_margin_deg=60.0)      # vcm
>>> pm, stable = sampled_phase_margin(k=k, T_I=T_I, tau=0.006675, phi=0.0407, derivative_N=10.0,
...                                   dt=1e-4, delay_samples=0)
>>> round(pm, 2), stable
(60.02, True)
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["derivative_time", "sampled_phase_margin", "sampled_crossover", "sampled_loop_margins",
           "delta_loop_polynomials"]


def derivative_time(kp: float, kd: float, derivative_N: float) -> float:
    """The derivative filter's time constant ``tau_d = kd / (kp N)`` [s]: its one definition.

    Parameters
    ----------
    kp, kd, derivative_N : float
        Proportional and derivative gains, and the filter's ``N`` (``pid.derivative_N``).

    >>> derivative_time(400.0, 2.0, 10.0)
    0.0005
    """
    return kd / kp / derivative_N


def sampled_phase_margin(*, k: float, T_I: float, tau: float, phi: float, derivative_N: float, dt: float,
                         delay_samples: int, points: int = 20001) -> tuple[float, bool]:
    """Phase margin [deg] and stability of the sampled loop ``C(z) H_zoh(z) z^-d`` of the PID ``(k, T_I)``.

    The loop of :mod:`obsdesign.design.sampled_loop` (the kernel's discrete PID with its derivative filter, the
    ZOH of eq:linplant, the drive's delay), NumPy only: the smallest margin over the gain crossovers
    (:func:`~obsdesign.design.margins.gain_crossovers`, ``inf`` without one) and whether every closed-loop pole
    is inside the unit circle.

    Parameters
    ----------
    k, T_I : float
        Total gain [V/m] and integrator time [s] of eq:Cpid.
    tau, phi : float
        The design model's time constant [s] and gain [m/(V s)].
    derivative_N, dt : float
        The derivative filter's ``N`` and the sample time [s].
    delay_samples : int
        The drive's delay [samples].
    points : int
        Points of the crossover search's grid.

    Examples
    --------
    >>> pm, stable = sampled_phase_margin(k=400.0, T_I=0.092140, tau=0.006675, phi=0.0407, derivative_N=10.0,
    ...                                   dt=1e-4, delay_samples=0)
    >>> round(pm, 1), stable
    (60.0, True)
    """
    from .margins import gain_crossovers

    kp, ki, kd = k * (T_I + tau) / T_I, k / T_I, k * tau  # eq:PIDparams
    num, den = delta_loop_polynomials(kp, ki, kd, derivative_time(kp, kd, derivative_N), dt, phi, tau,
                                      delay_samples)
    found = gain_crossovers(num, den, dt, points, delta=True)
    pm = min(found)[0] if found else math.inf
    poles = np.roots(np.polyadd(den, num))  # delta = z - 1: |z| < 1 is 2 Re(delta) + |delta|^2 < 0
    return float(pm), bool(np.all(2.0 * poles.real + np.abs(poles) ** 2 < 0.0))


def sampled_crossover(*, k: float, T_I: float, tau: float, phi: float, derivative_N: float, dt: float,
                      delay_samples: int) -> float:
    """The gain crossover [rad/s] of :func:`sampled_phase_margin`'s loop with the smallest margin (``nan``: none).

    Parameters
    ----------
    k, T_I, tau, phi, derivative_N, dt : float
        As in :func:`sampled_phase_margin`.
    delay_samples : int
        The drive's delay [samples].

    >>> w = sampled_crossover(k=400.0, T_I=0.092140, tau=0.006675, phi=0.0407, derivative_N=10.0, dt=1e-4,
    ...                       delay_samples=0)
    >>> round(w, 1)
    18.8
    """
    from .margins import gain_crossovers

    kp, ki, kd = k * (T_I + tau) / T_I, k / T_I, k * tau  # eq:PIDparams
    num, den = delta_loop_polynomials(kp, ki, kd, derivative_time(kp, kd, derivative_N), dt, phi, tau,
                                      delay_samples)
    found = gain_crossovers(num, den, dt, delta=True)
    return float(min(found)[1]) if found else math.nan


def _ramp_remainder(x: float) -> float:
    """``x - (1 - exp(-x))`` without the cancellation at small ``x`` (its series below 0.1)."""
    if x >= 0.1:
        return x + math.expm1(-x)
    term, total = -x, 0.0
    for n in range(2, 30):
        term *= -x / n
        total += term
    return total


def delta_loop_polynomials(kp: float, ki: float, kd: float, tau_d: float, dt: float, phi: float, tau: float,
                           d: int) -> tuple[np.ndarray, np.ndarray]:
    """``L(z) = C(z) H_zoh(z) z^-d`` of :mod:`obsdesign.design.sampled_loop` in powers of ``delta = z - 1``.

    The same loop as the polynomials in ``z`` (the kernel's PID with ``a = exp(-dt / tau_d)``, the ZOH of
    ``phi / (s (tau s + 1))`` with ``e = exp(-dt / tau)``), its coefficients formed from ``1 - a``, ``1 - e``
    and ``dt / tau - (1 - e)`` without cancellation: at a fast sample rate the poles crowd ``z = 1`` and the
    polynomials in ``z`` lose the digits that set the margin.

    Parameters
    ----------
    kp, ki, kd, tau_d, dt, phi, tau : float
        The PID, its derivative filter [s], the sample time [s] and the design model.
    d : int
        The drive's delay [samples].

    Returns
    -------
    (ndarray, ndarray)
        Numerator and denominator in ``delta``, highest power first.

    Examples
    --------
    >>> import math
    >>> num, den = delta_loop_polynomials(2.0, 0.0, 0.0, 1.0, 0.1, 1.0, 1.0, 0)
    >>> z = 0.5 + 0.5j
    >>> L = complex(np.polyval(num, z - 1) / np.polyval(den, z - 1))
    >>> e = math.exp(-0.1)
    >>> H = ((0.1 - (1 - e)) * z + (1 - e) - 0.1 * e) / ((z - 1) * (z - e))
    >>> abs(L - 2.0 * H) < 1e-12
    True
    """
    ca, ce = -math.expm1(-dt / tau_d), -math.expm1(-dt / tau)
    b1 = tau * _ramp_remainder(dt / tau)  # dt - tau (1 - e): the ZOH numerator is b1 z + b0, b1 + b0 = dt (1 - e)
    dl, dla, dle = np.array([1.0, 0.0]), np.array([1.0, ca]), np.array([1.0, ce])
    num_C = (kp * np.polymul(dl, dla) + ki * dt * np.polymul([1.0, 1.0], dla)
             + kd * ca / dt * np.polymul(dl, dl))
    num_H = phi * np.array([b1, dt * ce])
    den: np.ndarray = np.polymul(np.polymul(dl, dla), np.polymul(dl, dle))
    for _ in range(d):
        den = np.polymul(den, [1.0, 1.0])
    return np.polymul(num_C, num_H), den


def sampled_loop_margins(kp: float, ki: float, kd: float, *, tau: float, phi: float, derivative_N: float, dt: float,
                         delay_samples: int, points: int = 20001) -> tuple[float, float, float, float, bool]:
    """``(phase margin [deg], its crossover [rad/s], |S| peak, gain margin [dB], stable)`` of the sampled loop of
    any PID ``(kp, ki, kd)`` with the kernel's derivative filter ``tau_d = kd / (kp N)`` (:func:`derivative_time`).

    The loop of :func:`sampled_phase_margin` (:func:`delta_loop_polynomials`, the crossovers by
    :func:`~obsdesign.design.margins.gain_crossovers`); the |S| peak and the gain margin (the smallest
    ``1 / |L|`` where ``L`` crosses the negative real axis with ``|L| < 1``, ``inf`` where it does not) on a log
    grid of ``points`` up to the Nyquist frequency.

    Parameters
    ----------
    kp, ki, kd : float
        The PID's gains.
    tau, phi, derivative_N, dt : float
        The design model, the derivative filter's ``N`` and the sample time [s].
    delay_samples : int
        The drive's delay [samples].
    points : int
        Grid points.

    Examples
    --------
    The paper's gains on vcm: the margin and crossover of :func:`sampled_phase_margin`; the ZOH's lag crosses
    -180 deg near the Nyquist frequency, 61 dB down.

    >>> from obsdesign.design.pid_sampled import pid_gains
    >>> k, T_I, kp, ki, kd = pid_gains(phi=0.0407, tau=0.006675, max_S=1/400, phase_margin_deg=60.0)
    >>> loop = dict(tau=0.006675, phi=0.0407, derivative_N=10.0, dt=1e-4, delay_samples=0)
    >>> pm, wc, ms, gm, stable = sampled_loop_margins(kp, ki, kd, **loop)
    >>> ref = sampled_phase_margin(k=k, T_I=T_I, **loop)[0]
    >>> pm == ref, wc == sampled_crossover(k=k, T_I=T_I, **loop), round(ms, 2), round(gm), stable
    (True, True, 1.03, 61, True)
    """
    from .margins import gain_crossovers

    num, den = delta_loop_polynomials(kp, ki, kd, derivative_time(kp, kd, derivative_N), dt, phi, tau, delay_samples)
    found = gain_crossovers(num, den, dt, points, delta=True)
    pm, wc = min(found) if found else (math.inf, math.nan)
    _, ms, gm, stable = _grid_margins(num, den, dt, points)
    return float(pm), float(wc), ms, gm, stable


def _grid_margins(num, den, dt: float, points: int) -> tuple[list, float, float, bool]:
    """``([(phase margin [deg], w)] at the grid's gain crossovers, |S| peak, gain margin [dB], stable)`` of the loop
    ``num / den`` in delta (:func:`delta_loop_polynomials`)."""
    w = np.logspace(math.log10(math.pi / dt) - 6.0, math.log10(math.pi / dt), points)
    delta = np.expm1(1j * w * dt)
    L = np.polyval(num, delta) / np.polyval(den, delta)
    ms = float(np.max(1.0 / np.abs(1.0 + L)))
    mag, im = np.abs(L), L.imag
    cross = np.flatnonzero((np.sign(im[:-1]) != np.sign(im[1:])) & (L.real[:-1] < 0.0))
    low = [x for x in (float(mag[i] + (mag[i + 1] - mag[i]) * im[i] / (im[i] - im[i + 1])) for i in cross) if x < 1.0]
    gm = -20.0 * math.log10(max(low)) if low else math.inf
    up = np.flatnonzero(np.sign(mag[:-1] - 1.0) != np.sign(mag[1:] - 1.0))
    pms = [((math.degrees(float(np.angle(L[i]))) + 360.0) % 360.0 - 180.0, float(w[i])) for i in up]
    poles = np.roots(np.polyadd(den, num))  # delta = z - 1: |z| < 1 is 2 Re(delta) + |delta|^2 < 0
    return pms, ms, gm, bool(np.all(2.0 * poles.real + np.abs(poles) ** 2 < 0.0))
