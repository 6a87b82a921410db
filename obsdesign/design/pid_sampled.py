"""The PID designed for the loop that runs: ``[pid] design = auto | paper | sampled`` resolved in one place.

``paper`` is the rule of section 4.1 (:func:`pid_gains`) on the continuous design model
eq:linplant. ``sampled`` keeps its structure (``k``, ``T_I``, ``kd = k tau``, ``ki = k / T_I``,
``kp = k (T_I + tau) / T_I``, the kernel's derivative filter) and chooses the gains so that the sampled loop of
:mod:`obsdesign.design.sampled_loop` (ZOH of the design model, the derivative filter, the drive's delay
``[hardware] delay_samples``) has the phase margin ``pid.phase_margin_deg``. ``auto`` (default) carries the
sampled design where the paper's loses more than :data:`AUTO_THRESHOLD_DEG` on that loop and the sampled design
keeps ``k = 1 / max_S`` (:data:`AUTO_KEEPS_MAX_S`), else the paper's (docs/delay.md).
Every reader of the PID goes through :func:`resolve_pid` (via :func:`sampled_pid_gains`
and :func:`~obsdesign.design.pid.pid_from_config`). NumPy only: the margins are those of ``L(exp(j w dt))``
in powers of ``z - 1`` (:func:`delta_loop_polynomials`), the crossovers by
:func:`~obsdesign.design.margins.gain_crossovers`.

Examples
--------
>>> import obsdesign as od
>>> c = resolve_pid(od.load_preset("vcm"))
>>> c.design, round(c.kp, 1), round(c.ki)
('paper', 429.0, 4341)
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import cast

import numpy as np

from .._memo import memo
from .._validate import POSITIVE, Choice, Range
from ..params import PID_DESIGNS, Config

__all__ = ["DESIGNS", "AUTO_THRESHOLD_DEG", "AUTO_KEEPS_MAX_S", "PIDChoice", "resolve_pid", "pid_gains", "sampled_pid_gains",
           "derivative_time",
           "sampled_phase_margin", "sampled_crossover", "delta_loop_polynomials"]

#: The choices of ``[pid] design``: the paper's rule, the sampled design, or the sampled design where the
#: loop that runs costs the paper's rule more than :data:`AUTO_THRESHOLD_DEG` of phase margin.
DESIGNS = PID_DESIGNS
#: Phase margin [deg] the sampled loop may lose against the paper's design before ``auto`` picks ``sampled``.
AUTO_THRESHOLD_DEG = 3.0
#: ``auto`` carries the sampled design only where it keeps ``k = 1 / max_S`` (the |S| bound of eq:pidGain): where
#: the target needs a lower ``k`` the two specifications conflict and ``auto`` keeps the paper's gains, saying so
#: (docs/delay.md: on the identified axes the sampled design would lower the crossover 8 to 15 times).
AUTO_KEEPS_MAX_S = True


_POS = POSITIVE
_PHASE = Range(low=0.0, high=90.0)


def pid_gains(*, phi: float, tau: float, max_S: float, phase_margin_deg: float) -> tuple[float, ...]:
    """``(k, T_I, kp, ki, kd)`` of the design rule alone, without the python-control verification.

    Parameters
    ----------
    phi : float
        Plant gain [m/(V s)].
    tau : float
        Plant time constant [s].
    max_S : float
        Bound of |S| [m/V].
    phase_margin_deg : float
        Phase margin [deg], in (0, 90).

    >>> [round(x, 4) for x in pid_gains(phi=0.0407, tau=0.006675, max_S=1/400, phase_margin_deg=60.0)]
    [400.0, 0.0921, 428.9784, 4341.3333, 2.67]
    """
    phi, tau, max_S = (cast(float, _POS.check(n, v)) for n, v in (("phi", phi), ("tau", tau), ("max_S", max_S)))
    pm = cast(float, _PHASE.check("phase_margin_deg", phase_margin_deg))  # bounded: never None
    k = 1.0 / max_S  # eq:pidGain
    t2 = math.tan(math.radians(pm)) ** 2
    T_I = t2 / (k * phi * math.sqrt(1.0 + t2))  # eq:pidTime
    return k, T_I, k * (T_I + tau) / T_I, k / T_I, k * tau  # eq:PIDparams


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


def sampled_pid_gains(cfg: Config) -> tuple[float, float, float, float]:
    """``(kp, ki, kd, tau_d)`` as the sampled controller runs them: the PID the config carries
    (:func:`resolve_pid`) and its derivative filter (:func:`derivative_time`).

    Parameters
    ----------
    cfg : Config
        The design.

    >>> import obsdesign as od
    >>> kp, ki, kd, tau_d = sampled_pid_gains(od.load_preset("vcm"))
    >>> abs(tau_d - kd / kp / 10.0) < 1e-18, round(kd, 4)
    (True, 2.67)
    """
    c = resolve_pid(cfg)
    return c.kp, c.ki, c.kd, c.tau_d


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


def _rule(k: float, phi: float, pm_deg: float) -> float:
    """``T_I`` of eq:pidTime (:func:`pid_gains`) for the gain ``k`` and the design margin."""
    return pid_gains(phi=phi, tau=1.0, max_S=1.0 / k, phase_margin_deg=pm_deg)[1]


def _sampled_search(phi: float, tau: float, max_S: float, pm: float, N: float, dt: float, d: int,
                    keep_k: bool = False) -> list:
    """``[k, T_I, design margin, sampled margin]`` of the sampled design (:func:`resolve_pid`'s search); with
    ``keep_k`` only the first stage (``[]`` where it does not reach the target)."""
    k0 = 1.0 / max_S
    cap = pm + (90.0 - pm) * 2.0 / 3.0
    grid = [pm + (cap - pm) * j / 10.0 for j in range(11)]

    def margin(k: float, design: float, points: int = 2001) -> float:
        value, stable = sampled_phase_margin(k=k, T_I=_rule(k, phi, design), tau=tau, phi=phi, derivative_N=N,
                                             dt=dt, delay_samples=d, points=points)
        return value if stable and math.isfinite(value) else -math.inf

    def bisect(meets, lo: float, hi: float) -> float:
        """The end of ``[lo, hi]`` where ``meets`` holds, moved to the boundary (``meets(hi)``, not ``meets(lo)``)."""
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            if meets(mid):
                hi = mid
            else:
                lo = mid
        return hi

    # 1. the gain k = 1 / max_S kept: the smallest design margin whose sampled loop meets the target
    values = [margin(k0, x) for x in grid]
    for j, value in enumerate(values):
        if value >= pm:
            design = grid[0] if j == 0 else bisect(lambda x: margin(k0, x) >= pm, grid[j - 1], grid[j])
            return [k0, _rule(k0, phi, design), design, margin(k0, design, 20001)]
    if keep_k:
        return []
    # 2. the gain lowered: for each design margin the largest k = 10^(-i/10) / max_S that meets the target; for
    # the design margins with the largest, k bisected to the target; the largest k (the smaller margin of a tie)
    steps, tied = 61, list[float]()
    for design in grid:
        for i in range(1, steps + 1):
            if margin(10.0 ** (-i / 10.0) * k0, design) >= pm:
                tied = (tied if i == steps else []) + [design]
                steps = i
                break
    if not tied:
        raise ValueError(f"pid.design: no sampled PID with k >= 1e-6 / max_S meets the phase margin {pm:g} deg "
                         f"at dt = {dt:g} s with a delay of {d} samples; expected a feasible loop (lower "
                         f"pid.phase_margin_deg or the delay)")
    found = []
    for design in tied:
        log_s = bisect(lambda x: margin(10.0**x * k0, design) >= pm, -(steps - 1) / 10.0, -steps / 10.0)
        found.append((-log_s, design))
    log_s, chosen = min(found)
    k = 10.0 ** -log_s * k0
    return [k, _rule(k, phi, chosen), chosen, margin(k, chosen, 20001)]


@functools.lru_cache(maxsize=256)
def _resolve(phi: float, tau: float, max_S: float, pm: float, N: float, dt: float, d: int, setting: str) -> tuple:
    """``(design, reason, k, T_I, design margin, paper's sampled margin, carried design's sampled margin)``."""
    k0 = 1.0 / max_S
    T0 = _rule(k0, phi, pm)
    kp0 = k0 * (T0 + tau) / T0
    tau_d0 = derivative_time(kp0, k0 * tau, N) if math.isfinite(kp0) else math.nan
    if not all(math.isfinite(x) and x > 0 for x in (k0, T0, kp0, k0 / T0, k0 * tau, tau_d0, dt / tau_d0, dt / tau)):
        raise OverflowError(f"pid: the paper's PID is not finite (k = {k0:g}, T_I = {T0:g}, kp = {kp0:g}, "
                            f"tau_d = {tau_d0:g} s)")
    paper_pm, paper_stable = sampled_phase_margin(k=k0, T_I=T0, tau=tau, phi=phi, derivative_N=N, dt=dt,
                                                  delay_samples=d)
    paper_pm = paper_pm if paper_stable else -math.inf
    cost = pm - paper_pm
    has = (f"the paper's design has {paper_pm:.2f} deg" if math.isfinite(paper_pm)
           else "the paper's design is unstable") + (f" on the sampled loop (dt = {dt:g} s, delay {d} samples, "
                                                       f"derivative filter N = {N:g}), target {pm:g} deg")
    if setting == "paper" or (setting == "auto" and cost <= AUTO_THRESHOLD_DEG):
        why = "[pid] design = 'paper'" if setting == "paper" else f"auto: {has}: within {AUTO_THRESHOLD_DEG:g} deg"
        return ("paper", why, k0, T0, pm, paper_pm, paper_pm)
    keep_k = setting == "auto" and AUTO_KEEPS_MAX_S
    found = memo("pid_sampled", (phi, tau, max_S, pm, N, dt, d, keep_k),
                 lambda: _sampled_search(phi, tau, max_S, pm, N, dt, d, keep_k),
                 valid=lambda v: isinstance(v, list) and len(v) in (0, 4) and all(isinstance(x, float) for x in v))
    if not found:  # auto, and only a lower k would meet the target: the two specifications conflict
        return ("paper", f"auto: {has}, and a sampled design meets it only with k below 1 / max_S (a lower "
                f"crossover; `obsdesign pid` shows it): kept the paper's; design = 'sampled' carries it",
                k0, T0, pm, paper_pm, paper_pm)
    k, T_I, design, got = found
    lost = ""
    if k != k0:
        w0, w1 = (sampled_crossover(k=x, T_I=y, tau=tau, phi=phi, derivative_N=N, dt=dt, delay_samples=d)
                  for x, y in ((k0, T0), (k, T_I)))
        lost = (f"; k lowered to {k / k0:.3g} of 1/max_S, the crossover from {w0:.4g} to {w1:.4g} rad/s (a "
                f"{pm:g} deg margin is out of this PID's reach at the paper's crossover: see docs/delay.md)")
    why = ("[pid] design = 'sampled'" if setting == "sampled" else
           f"auto: {has}: more than {AUTO_THRESHOLD_DEG:g} deg lost") + lost
    return ("sampled", why, k, T_I, design, paper_pm, got)


@dataclass(frozen=True, kw_only=True)
class PIDChoice:
    """The PID a config carries, resolved from ``[pid] design`` (:func:`resolve_pid`): NumPy only.

    Attributes
    ----------
    setting : str
        ``[pid] design`` as written (:data:`DESIGNS`).
    design : str
        ``"paper"`` or ``"sampled"``: the one carried.
    reason : str
        Why, in one line (``auto``'s comparison).
    k, T_I, design_phase_margin_deg : float
        Gain [V/m], integrator time [s] and the margin the continuous rule eq:pidTime was given [deg]
        (the config's for the paper's design; raised by the sampled design).
    kp, ki, kd, tau_d : float
        The gains and the derivative filter the kernel runs.
    paper_sampled_pm_deg, sampled_pm_deg : float
        Phase margin of the sampled loop with the delay [deg] of the paper's design and of the carried one
        (``-inf``: unstable).
    """

    setting: str
    design: str
    reason: str
    k: float
    T_I: float
    design_phase_margin_deg: float
    kp: float
    ki: float
    kd: float
    tau_d: float
    paper_sampled_pm_deg: float
    sampled_pm_deg: float


def resolve_pid(cfg: Config, *, design: str | None = None) -> PIDChoice:
    """The PID the config carries: ``[pid] design`` resolved (the one place every reader of the PID goes through).

    ``paper``: the rule of section 4.1 (:func:`pid_gains`) on the continuous design model. ``sampled``: the same
    structure, its gains chosen so that the sampled loop of :mod:`obsdesign.design.sampled_loop` (ZOH of the
    design model eq:linplant, the kernel's derivative filter, the drive's delay ``[hardware] delay_samples``)
    has the phase margin ``pid.phase_margin_deg``: first with ``k = 1 / max_S`` kept and the rule's design
    margin raised (a longer ``T_I``, at most two thirds of the way to 90 deg); where that does not reach the
    target, ``k`` lowered (the largest that does, over the same design margins). ``auto`` (default): the
    sampled design where the paper's loses more than :data:`AUTO_THRESHOLD_DEG` on the sampled loop and the
    sampled design keeps ``k = 1 / max_S`` (:data:`AUTO_KEEPS_MAX_S`), else the paper's (docs/delay.md).

    Parameters
    ----------
    cfg : Config
        The design.
    design : str, optional
        One of :data:`DESIGNS` instead of ``cfg.pid.design``.

    Returns
    -------
    PIDChoice

    Examples
    --------
    >>> import obsdesign as od
    >>> c = resolve_pid(od.load_preset("vcm"))
    >>> c.design, round(c.kp, 1), round(c.ki)
    ('paper', 429.0, 4341)
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    setting = cfg.pid.design if design is None else Choice(DESIGNS).check("design", design)
    N = cfg.pid.derivative_N
    chosen, reason, k, T_I, design_pm, paper_pm, got = _resolve(
        float(cfg.phi), float(cfg.pid.tau), float(cfg.pid.max_S), float(cfg.pid.phase_margin_deg), float(N),
        float(cfg.observer.dt), int(cfg.hardware.delay_samples), setting)
    tau = cfg.pid.tau
    if chosen == "paper":  # the rule's own arithmetic: the paper's gains bit for bit
        _, _, kp, ki, kd = pid_gains(phi=cfg.phi, tau=tau, max_S=cfg.pid.max_S, phase_margin_deg=design_pm)
    else:
        kp, ki, kd = k * (T_I + tau) / T_I, k / T_I, k * tau  # eq:PIDparams
    return PIDChoice(setting=setting, design=chosen, reason=reason, k=k, T_I=T_I, design_phase_margin_deg=design_pm,
                     kp=kp, ki=ki, kd=kd, tau_d=derivative_time(kp, kd, N), paper_sampled_pm_deg=paper_pm,
                     sampled_pm_deg=got)
