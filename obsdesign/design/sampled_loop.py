"""The sampled loop that runs: ZOH plant, the kernel's discrete PID, the drive's delay of d samples.

At sample ``n`` the controller (:func:`obsdesign.sampled.kernel.controller_sample`) computes, from
the error ``e[n] = x_ref[n] - x_meas[n]``,

* ``I[n] = I[n-1] + dt e[n]`` (the integral includes the current sample),
* ``D[n] = a D[n-1] + (1 - a) (e[n] - e[n-1]) / dt`` with ``a = exp(-dt / tau_d)``,
  ``tau_d = kd / (kp N)`` (``N = pid.derivative_N``),
* ``u[n] = kp e[n] + ki I[n] + kd D[n]``,

so its z-transform (zero initial state) is exactly

``C(z) = kp + ki dt z / (z - 1) + kd (1 - a) / dt (z - 1) / (z - a)``.

The command is held over ``[n dt, (n + 1) dt)`` (ZOH) on the plant ``H = phi / (s (tau s + 1))``
of eq:linplant, ``H_zoh(z) = c2d(H, dt, 'zoh')``, after ``d = hardware.delay_samples`` samples of
the drive's delay: ``L(z) = C(z) H_zoh(z) z^-d``. The linear loop leaves out the feed-forward, the friction
compensation, the saturation (with its conditional integration) and quantization.

Computed with python-control on the discrete system: margins (``stability_margins``), the delay
margin ``PM / omega_c`` (the extra delay the loop tolerates, exact for whole samples: the loop stays
stable with ``k`` more samples of delay for ``k < delay_margin_samples``), the gang of four
``S = 1/(1+L)``, ``T = L/(1+L)``, ``PS = H_zoh/(1+L)`` [m/V] (input disturbance to position),
``CS = C z^-d/(1+L)`` [V/m] (measurement noise to command), their peaks over ``0 < omega <= pi/dt``,
the closed-loop poles ``roots(den L + num L)`` and the step metrics of ``T`` (``step_info``, 2 %).

Examples
--------
>>> import obsdesign as od
>>> sl = sampled_loop(od.load_preset("vcm"))
>>> round(sl.phase_margin_deg, 2), round(sl.gain_margin, 1), sl.delay_samples
(60.02, 1121.5, 0)
>>> sl2 = sampled_loop(od.load_preset("vcm"), delay_samples=1)
>>> round(sl2.phase_margin_deg, 2), round(sl2.delay_margin_samples, 1)
(59.91, 555.6)
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._display import ResultDisplay
from .._memo import list_of, memo
from .._validate import POSITIVE
from ..params import Config
from .margins import closed_loop, drive_delay, loop_margins as _margins
from .pid import lazy_system
from .pid_sampled import sampled_pid_gains

if TYPE_CHECKING:
    import control as ct

__all__ = ["SampledLoop", "sampled_loop", "discrete_pid", "derivative_pole", "zoh_plant", "discrete_peak"]


def derivative_pole(dt: float, tau_d: float) -> float:
    """Pole ``a = exp(-dt / tau_d)`` of the PID's first-order derivative filter per sample: its one definition.

    The kernel's recursion ``D[n] = a D[n-1] + (1 - a) (e[n] - e[n-1]) / dt``
    (:func:`obsdesign.sampled.kernel.controller_sample`, the exports' ``ALPHA_D``) and the sampled loop's
    ``C(z)`` (:func:`discrete_pid`) read it; ``tau_d`` is
    :func:`obsdesign.design.pid_sampled.derivative_time`. Two places write it again on purpose:
    :func:`obsdesign.design.pid_sampled.delta_loop_polynomials` takes ``1 - a = -expm1(-dt / tau_d)``
    (accurate where ``dt << tau_d``), and the report's explorer page recomputes it in JavaScript
    when its fields change.

    Parameters
    ----------
    dt : float
        Sample time [s].
    tau_d : float
        Time constant of the derivative filter [s]; 0 or less: no filter (pole 0).

    Examples
    --------
    >>> round(derivative_pole(1e-4, 1e-4), 12), derivative_pole(1e-4, 0.0)
    (0.367879441171, 0.0)
    """
    return math.exp(-dt / tau_d) if tau_d > 0.0 else 0.0


def discrete_pid(*, kp: float, ki: float, kd: float, tau_d: float, dt: float) -> ct.TransferFunction:
    """``C(z)`` of the kernel's PID recursion (module docstring), as one transfer function.

    Parameters
    ----------
    kp, ki, kd : float
        Parallel PID gains [V/m, V/(m s), V s/m].
    tau_d : float
        Time constant of the derivative filter [s] (> 0).
    dt : float
        Sample time [s] (> 0).

    Returns
    -------
    control.TransferFunction
        ``(kp (z-1)(z-a) + ki dt z (z-a) + kd (1-a)/dt (z-1)^2) / ((z-1)(z-a))``, ``a = exp(-dt/tau_d)``.

    Examples
    --------
    >>> C = discrete_pid(kp=2.0, ki=0.0, kd=0.0, tau_d=1.0, dt=0.1)
    >>> round(float(abs(C(1j))), 12)
    2.0
    """
    tau_d, dt = POSITIVE.check("tau_d", tau_d), POSITIVE.check("dt", dt)
    a = derivative_pole(dt, tau_d)
    zm1, zma = np.array([1.0, -1.0]), np.array([1.0, -a])
    num = (kp * np.polymul(zm1, zma) + ki * dt * np.polymul([1.0, 0.0], zma)
           + kd * (1.0 - a) / dt * np.polymul(zm1, zm1))
    import control as ct

    return ct.tf(num, np.polymul(zm1, zma), dt)


def zoh_plant(*, phi: float, tau: float, dt: float) -> ct.TransferFunction:
    """``H_zoh(z) = c2d(phi / (s (tau s + 1)), dt, 'zoh')`` [m/V].

    Parameters
    ----------
    phi, tau, dt : float
        Plant gain [m/(V s)], time constant [s] and sample time [s].

    Examples
    --------
    >>> H = zoh_plant(phi=1.0, tau=1.0, dt=0.1)
    >>> H.dt, len(H.poles())
    (0.1, 2)
    """
    import control as ct

    H = ct.tf([POSITIVE.check("phi", phi)], [POSITIVE.check("tau", tau), 1.0, 0.0])
    return ct.c2d(H, POSITIVE.check("dt", dt), "zoh")


def discrete_peak(sys: ct.TransferFunction, dt: float, w_low: float) -> tuple[float, float]:
    """``max |sys(exp(j w dt))|`` over ``w_low <= w <= pi/dt`` and where it is [rad/s].

    A log grid of 4001 points ending at the Nyquist frequency, then a bounded refinement.

    Parameters
    ----------
    sys : control.TransferFunction
        A discrete, stable SISO system.
    dt : float
        Its sample time [s].
    w_low : float
        Lowest frequency of the search [rad/s] (below the Nyquist frequency).

    Examples
    --------
    >>> import control as ct
    >>> z = ct.tf([1.0, 0.0], [1.0], 0.1)
    >>> peak, w = discrete_peak(1 / (z + 0.5), 0.1, 0.01)   # largest at z = -1 (w = pi/dt): 1 / 0.5
    >>> round(peak, 9), round(w * 0.1, 9)
    (2.0, 3.141592654)
    """
    w_nyq = math.pi / dt
    w = np.logspace(math.log10(w_low), math.log10(w_nyq), 4001)
    w[-1] = w_nyq

    def mag(x):
        return np.abs(np.asarray(sys(np.exp(1j * np.asarray(x) * dt)))).ravel()

    m = mag(w)
    i = int(m.argmax())
    lo, hi = w[max(i - 1, 0)], w[min(i + 1, w.size - 1)]
    import scipy.optimize

    res = scipy.optimize.minimize_scalar(lambda x: -float(mag(x)[0]), bounds=(lo, hi), method="bounded",
                                         options={"xatol": 1e-12 * hi})
    best = -float(res.fun)
    return (best, float(res.x)) if best > m[i] else (float(m[i]), float(w[i]))


@dataclass(frozen=True, kw_only=True)
class SampledLoop(ResultDisplay):
    """Margins, gang of four, poles and step of the sampled loop ``L(z) = C(z) H_zoh(z) z^-d``.

    Attributes
    ----------
    dt : float
        Sample time [s] (``observer.dt``).
    delay_samples : int
        Computation delay ``d`` [samples].
    derivative_N : float
        The derivative filter's ``N``.
    gain_margin, gain_margin_db : float
        Gain margin as python-control's ``stability_margins`` reports it [-] and in dB (``inf``: none).
    phase_margin_deg : float
        Phase margin [deg].
    crossover_rad_s, phase_crossover_rad_s : float
        Gain and phase crossover frequencies [rad/s] (``nan``: none).
    delay_margin_s, delay_margin_samples : float
        Smallest ``PM_i / omega_i`` over the gain crossovers [s], and in samples.
    max_S, omega_max_S, max_T, omega_max_T : float
        Peaks of ``|S|``, ``|T|`` [-] and where they are [rad/s].
    max_PS : float
        Peak of ``|H_zoh / (1 + L)|`` [m/V].
    max_CS, omega_max_CS : float
        Peak of ``|C z^-d / (1 + L)|`` [V/m] (noise to command) and where it is [rad/s].
    poles : tuple of complex
        Closed-loop poles in the z-plane, sorted by magnitude.
    max_pole_magnitude : float
        ``max |z|`` of the poles (stable when < 1).
    overshoot_pct, rise_time_s, settling_time_s : float or None
        ``step_info`` of ``T``: overshoot [%], 10-90 % rise and 2 % settling time [s] (None if unstable).
    kp, ki, kd, tau_d : float
        The PID the kernel runs.
    phi, tau : float
        The plant of eq:linplant the loop is closed around [m/(V s)], [s].
    C, H, L, S, T, PS, CS : control.TransferFunction
        The discrete systems (sample time ``dt``).
    """

    _title = "Sampled loop on the PID's design model eq:linplant: L(z) = C(z) H_zoh(z) z^-d"
    dt: float
    delay_samples: int
    derivative_N: float
    gain_margin: float
    gain_margin_db: float
    phase_margin_deg: float
    crossover_rad_s: float
    phase_crossover_rad_s: float
    delay_margin_s: float
    delay_margin_samples: float
    max_S: float
    omega_max_S: float
    max_T: float
    omega_max_T: float
    max_PS: float
    max_CS: float
    omega_max_CS: float
    poles: tuple[complex, ...]
    max_pole_magnitude: float
    overshoot_pct: float | None
    rise_time_s: float | None
    settling_time_s: float | None
    kp: float
    ki: float
    kd: float
    tau_d: float
    phi: float
    tau: float
    C = lazy_system()
    H = lazy_system()
    L = lazy_system()
    S = lazy_system()
    T = lazy_system()
    PS = lazy_system()
    CS = lazy_system()

    def _system_args(self) -> tuple:
        return (self.kp, self.ki, self.kd, self.tau_d, self.dt, self.phi, self.tau, self.delay_samples)

    def _build_systems(self) -> dict:
        return _systems(*self._system_args())

    @property
    def system(self) -> str:
        """Which system the numbers are about, in words."""
        return (f"sampled loop: ZOH plant, discrete PID with derivative filter N={self.derivative_N:g}, "
                f"delay {self.delay_samples} samples, dt = {self.dt:g} s")

    @property
    def stable(self) -> bool:
        """All closed-loop poles inside the unit circle."""
        return self.max_pole_magnitude < 1.0

    def to_dict(self) -> dict:
        """JSON-ready values (infinite margins are ``None``, poles ``[re, im]`` pairs)."""
        def fin(x):
            return None if x is None or not math.isfinite(x) else x

        return {
            "system": self.system, "dt": self.dt, "delay_samples": self.delay_samples,
            "derivative_N": self.derivative_N, "gain_margin": fin(self.gain_margin),
            "gain_margin_db": fin(self.gain_margin_db), "phase_margin_deg": self.phase_margin_deg,
            "crossover_rad_s": fin(self.crossover_rad_s), "phase_crossover_rad_s": fin(self.phase_crossover_rad_s),
            "delay_margin_s": fin(self.delay_margin_s), "delay_margin_samples": fin(self.delay_margin_samples),
            "max_S": self.max_S, "max_T": self.max_T, "max_PS": self.max_PS, "max_CS": self.max_CS,
            "poles": [[p.real, p.imag] for p in self.poles], "max_pole_magnitude": self.max_pole_magnitude,
            "stable": self.stable, "overshoot_pct": self.overshoot_pct, "rise_time_s": self.rise_time_s,
            "settling_time_s": self.settling_time_s,
        }

    def _rows(self):
        unstable = "" if self.stable else " (UNSTABLE)"
        return [
            ("system", self.system + unstable),
            ("gain margin [-] ([dB])", f"{self.gain_margin:.4g} ({self.gain_margin_db:.3g} dB)"),
            ("phase margin [deg]", self.phase_margin_deg),
            ("gain crossover [rad/s]", self.crossover_rad_s),
            ("phase crossover [rad/s]", self.phase_crossover_rad_s),
            ("delay margin [s] ([samples])", f"{self.delay_margin_s:.4g} ({self.delay_margin_samples:.3g} samples)"),
            ("max |S| [-]", self.max_S),
            ("max |T| [-]", self.max_T),
            ("max |PS| input disturbance to position [m/V]", self.max_PS),
            ("max |CS| noise to command [V/m]", self.max_CS),
            ("  at [rad/s]", self.omega_max_CS),
            ("closed-loop poles, max |z| [-]", self.max_pole_magnitude),
            ("step of T: overshoot [%]", self.overshoot_pct),
            ("step of T: rise 10-90 % [s]", self.rise_time_s),
            ("step of T: settling 2 % [s]", self.settling_time_s),
        ]


def sampled_loop(cfg: Config, *, delay_samples: int | None = None) -> SampledLoop:
    """Analyse the sampled loop of the config's PID as the kernel runs it (module docstring).

    Parameters
    ----------
    cfg : Config
        The design: ``pid`` section, ``phi``, ``observer.dt``, ``pid.derivative_N``.
    delay_samples : int, optional
        Computation delay [samples] (>= 0); default ``cfg.hardware.delay_samples``. The PID is the one the
        config carries (:func:`~obsdesign.design.pid_sampled.resolve_pid`, for the config's own delay): another
        value analyses those gains in a loop with another delay.

    Returns
    -------
    SampledLoop

    Raises
    ------
    TypeError
        ``cfg`` is not a Config.
    ValueError
        ``delay_samples`` is not an integer in [0, 10000].

    Examples
    --------
    >>> import obsdesign as od
    >>> sampled_loop(od.load_preset("vcm"), delay_samples=-1)
    Traceback (most recent call last):
    ...
    ValueError: delay_samples: expected an integer >= 0 and <= 10000, found -1
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    d = drive_delay(cfg, delay_samples)
    dt, N = cfg.observer.dt, cfg.pid.derivative_N
    kp, ki, kd, tau_d = sampled_pid_gains(cfg)
    args = (kp, ki, kd, tau_d, dt, cfg.phi, cfg.pid.tau, d)
    numbers = memo("sampled_loop", args, lambda: _numbers(*args), valid=list_of(17),
                   verify=lambda value: _verify(args, value))
    gm, pm, wgc, wpc, dm, max_S, w_S, max_T, w_T, max_PS, max_CS, w_CS, poles, rmax, over, rise, settle = numbers
    return SampledLoop(
        dt=dt, delay_samples=d, derivative_N=N, gain_margin=gm,
        gain_margin_db=20.0 * math.log10(gm) if math.isfinite(gm) else math.inf,
        phase_margin_deg=pm, crossover_rad_s=wgc, phase_crossover_rad_s=wpc, delay_margin_s=dm,
        delay_margin_samples=dm / dt, max_S=max_S, omega_max_S=w_S, max_T=max_T, omega_max_T=w_T, max_PS=max_PS,
        max_CS=max_CS, omega_max_CS=w_CS, poles=poles, max_pole_magnitude=rmax, overshoot_pct=over,
        rise_time_s=rise, settling_time_s=settle, kp=kp, ki=ki, kd=kd, tau_d=tau_d, phi=cfg.phi, tau=cfg.pid.tau,
    )


def _systems(kp, ki, kd, tau_d, dt, phi, tau, d) -> dict:
    C = discrete_pid(kp=kp, ki=ki, kd=kd, tau_d=tau_d, dt=dt)
    return closed_loop(C, zoh_plant(phi=phi, tau=tau, dt=dt), d)


def _loop_polynomials(kp, ki, kd, tau_d, dt, phi, tau, d) -> tuple:
    """``L(z) = C(z) H_zoh(z) z^-d`` as polynomials in ``z`` (NumPy only: :func:`discrete_pid`'s numerator and
    the closed form of the ZOH plant, ``phi ((dt - tau (1 - e)) z + tau (1 - e) - dt e) / ((z - 1)(z - e))``)."""
    a, e = derivative_pole(dt, tau_d), math.exp(-dt / tau)
    zm1, zma, zme = np.array([1.0, -1.0]), np.array([1.0, -a]), np.array([1.0, -e])
    num_C = (kp * np.polymul(zm1, zma) + ki * dt * np.polymul([1.0, 0.0], zma)
             + kd * (1.0 - a) / dt * np.polymul(zm1, zm1))
    num_H = phi * np.array([dt - tau * (1.0 - e), tau * (1.0 - e) - dt * e])
    den = np.polymul(np.polymul(zm1, zma), np.polymul(zm1, zme))
    return np.polymul(num_C, num_H), np.polymul(den, np.r_[1.0, np.zeros(d)])


def _verify(args: tuple, value: list) -> str | None:
    """Why kept sampled-loop numbers are not those of the loop (cheap arithmetic on ``L(exp(j w dt))``), or None."""
    gm, pm, wgc, wpc, _, max_S, w_S, max_T, w_T, _, _, _, poles, rmax, *_ = value
    dt = args[4]
    num, den = _loop_polynomials(*args)

    def L(w: float) -> complex:
        z = complex(math.cos(w * dt), math.sin(w * dt))
        return complex(np.polyval(num, z) / np.polyval(den, z))

    if not all(isinstance(x, (float, int)) for x in (gm, pm, wgc, wpc, max_S, w_S, max_T, w_T, rmax)):
        return "holds a number of another type"
    if math.isfinite(wgc) and wgc > 0:
        at = L(wgc)
        if abs(abs(at) - 1.0) > 1e-5 or abs((180.0 + math.degrees(math.atan2(at.imag, at.real))) % 360.0
                                             - pm % 360.0) > 1e-4 * max(1.0, abs(pm)):
            return f"its phase margin {pm:.6g} deg is not the loop's at {wgc:.6g} rad/s"
    if math.isfinite(gm) and math.isfinite(wpc) and wpc > 0:
        at = L(wpc)
        if abs(abs(at) * gm - 1.0) > 1e-5 or at.real > 0:
            return f"its gain margin {gm:.6g} is not the loop's at {wpc:.6g} rad/s"
    for peak, w, name in ((max_S, w_S, "S"), (max_T, w_T, "T")):
        if math.isfinite(w) and w > 0:
            at = L(w)
            got = abs(1.0 / (1.0 + at)) if name == "S" else abs(at / (1.0 + at))
            if abs(got - peak) > 1e-6 * max(abs(peak), 1e-300):
                return f"its peak of |{name}| {peak:.6g} is not |{name}| = {got:.6g} at {w:.6g} rad/s"
    roots = sorted((complex(p) for p in np.roots(np.polyadd(den, num))), key=lambda p: (abs(p), p.imag))
    if (not isinstance(poles, (list, tuple)) or len(poles) != len(roots)
            or any(not isinstance(p, complex) or abs(p - r) > 1e-6 for p, r in zip(poles, roots))
            or abs(max(abs(r) for r in roots) - rmax) > 1e-6):  # the poles' tolerance (near-double poles)
        return "its closed-loop poles are not the roots of the characteristic polynomial"
    return None


def _numbers(kp, ki, kd, tau_d, dt, phi, tau, d) -> list:
    """python-control's numbers of the sampled loop (what :func:`sampled_loop` keeps on disk)."""
    import control as ct

    sys = _systems(kp, ki, kd, tau_d, dt, phi, tau, d)
    L, S, T = sys["L"], sys["S"], sys["T"]
    gm, pm, wgc, wpc, dm = _margins(L)
    num, den = (np.atleast_1d(np.squeeze(x)) for x in ct.tfdata(L))
    poles = tuple(sorted((complex(p) for p in np.roots(np.polyadd(den, num))), key=lambda p: (abs(p), p.imag)))
    rmax = max(abs(p) for p in poles)
    w_low = (wgc if math.isfinite(wgc) and wgc > 0 else 1.0 / tau) * 1e-3
    max_S, w_S = discrete_peak(S, dt, w_low)
    max_T, w_T = discrete_peak(T, dt, w_low)
    max_PS, _ = discrete_peak(sys["PS"], dt, w_low)
    max_CS, w_CS = discrete_peak(sys["CS"], dt, w_low)
    over = rise = settle = None
    if rmax < 1.0:
        n = int(min(2e6, max(1000, 20.0 / (-math.log(rmax)))))  # 20 time constants of the slowest pole
        info = ct.step_info(T, T=np.arange(n) * dt, SettlingTimeThreshold=0.02)
        over, rise, settle = (float(info[k]) for k in ("Overshoot", "RiseTime", "SettlingTime"))
    return [gm, pm, wgc, wpc, dm, max_S, w_S, max_T, w_T, max_PS, max_CS, w_CS, poles, rmax, over, rise, settle]
