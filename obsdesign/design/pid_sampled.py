"""The PID designed for the loop that runs: ``[pid] design = auto | paper | sampled`` resolved in one place.

``paper`` is the rule of section 4.1 (:func:`pid_gains`) on the continuous design model
eq:linplant. ``sampled`` is a PID of the kernel's form (``kp``, ``ki``, ``kd``, its derivative filter
``tau_d = kd / (kp N)``) whose derivative gain is free of the paper's pole cancellation (``kd = k tau``), chosen
on the sampled loop of :mod:`obsdesign.design.sampled_loop` (ZOH of the design model, the derivative filter, the
drive's delay ``[hardware] delay_samples``): a phase margin of at least ``pid.phase_margin_deg``, ``|S|`` at most
:data:`MAX_SENSITIVITY_PEAK`, a gain margin of at least :data:`MIN_GAIN_MARGIN_DB`, at the paper's crossover
where that is reachable, else at :data:`CROSSOVER_KEPT` of the largest crossover that is, with the largest
integral gain there. ``auto`` (default) carries the sampled design where the paper's loses more than
:data:`AUTO_THRESHOLD_DEG` on that loop and the sampled design keeps the paper's crossover
(:data:`AUTO_KEEPS_CROSSOVER`), else the paper's, saying why (docs/delay.md).
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
from typing import Any, cast

import numpy as np

from .._memo import memo
from .._validate import POSITIVE, Choice, Range
from ..params import PID_DESIGNS, Config
from .pid_margins import (_grid_margins, delta_loop_polynomials, derivative_time, sampled_crossover,
                          sampled_loop_margins, sampled_phase_margin)

__all__ = ["DESIGNS", "AUTO_THRESHOLD_DEG", "AUTO_KEEPS_CROSSOVER", "MAX_SENSITIVITY_PEAK", "MIN_GAIN_MARGIN_DB", "CROSSOVER_KEPT",
           "PIDChoice", "resolve_pid", "pid_gains", "sampled_pid_gains", "derivative_time", "sampled_phase_margin",
           "sampled_crossover", "sampled_loop_margins", "delta_loop_polynomials"]

#: The choices of ``[pid] design``: the paper's rule, the sampled design, or the sampled design where the
#: loop that runs costs the paper's rule more than :data:`AUTO_THRESHOLD_DEG` of phase margin.
DESIGNS = PID_DESIGNS
#: Phase margin [deg] the sampled loop may lose against the paper's design before ``auto`` picks ``sampled``.
AUTO_THRESHOLD_DEG = 3.0
#: ``auto`` carries the sampled design only where it keeps the paper's crossover. Where the target forces the
#: crossover lower (8 to 17 times on the test axes of docs/delay.md), the margin and the speed conflict: the slow
#: loop was measured to hunt against friction with the observer on the 4 kHz rotary axis (94 % overshoot, never
#: settling) where the paper's settles in 14 ms, so ``auto`` keeps the paper's gains and says so in its reason;
#: ``design = "sampled"`` carries the sampled design there.
AUTO_KEEPS_CROSSOVER = True
#: The sampled design's robustness besides the phase margin: the peak of ``|S| = |1 / (1 + L)|`` on the sampled
#: loop (2: 6 dB, the usual upper end of an acceptable sensitivity peak) ...
MAX_SENSITIVITY_PEAK = 2.0
#: ... and its gain margin [dB].
MIN_GAIN_MARGIN_DB = 6.0
#: Where the target forces the crossover below the paper's, the sampled design keeps this fraction of the largest
#: crossover that meets it and spends the rest on the integral gain (``1 / ki`` is the integrated error of a load
#: step: friction).
CROSSOVER_KEPT = 0.95
#: The memo namespace of the sampled design's search (a new one whenever the search changes).
SEARCH_VERSION = "pid_sampled_free_kd_v2"


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



def _rule(k: float, phi: float, pm_deg: float) -> float:
    """``T_I`` of eq:pidTime (:func:`pid_gains`) for the gain ``k`` and the design margin."""
    return pid_gains(phi=phi, tau=1.0, max_S=1.0 / k, phase_margin_deg=pm_deg)[1]



def _series(k: float, T_I: float, T_z: float) -> tuple[float, float, float]:
    """``(kp, ki, kd)`` of the series PID ``k (1 + 1 / (T_I s)) (1 + T_z s)`` (eq:PIDparams with ``T_z = tau``)."""
    return k * (T_I + T_z) / T_I, k / T_I, k * T_z


def _free_search(phi: float, tau: float, pm: float, N: float, dt: float, d: int, w_cap: float) -> list:
    """``[k, T_I, T_z, crossover, w_max]`` of the sampled design (:func:`resolve_pid`), ``[]``: none.

    The PID ``k (1 + 1 / (T_I s)) (1 + T_z s)`` with the kernel's filter ``tau_d = kd / (kp N)``, its zeros
    placed relative to a crossover ``w`` (``T_I = x / w``, ``T_z = y / w``, ``k`` such that ``|L(e^{j w dt})| = 1``).
    A shape is admissible where the loop is stable with a phase margin of at least ``pm`` at every crossover,
    ``|S|`` at most :data:`MAX_SENSITIVITY_PEAK` and a gain margin of at least :data:`MIN_GAIN_MARGIN_DB`.
    1. ``w_max``: the largest ``w <= w_cap`` (the paper's crossover) with an admissible shape, the integral
       pushed out (``x = 1e3``, the lead ``y`` searched); 2. at ``w* = w_cap`` if that is reached, else
    :data:`CROSSOVER_KEPT` ``w_max``: the admissible shape with the largest ``ki`` (the integrated error of a load
    step, friction, is ``1 / ki``).
    """
    w_nyq = math.pi / dt
    points = 1001
    x_free, ys = 1.0e3, np.geomspace(0.2, 200.0, 31)

    def gains(w: float, x: float, y: float) -> tuple[float, float, float, float]:
        T_I, T_z = x / w, y / w
        kp, ki, kd = _series(1.0, T_I, T_z)
        num, den = delta_loop_polynomials(kp, ki, kd, derivative_time(kp, kd, N), dt, phi, tau, d)
        dl = complex(np.expm1(1j * w * dt))
        k = abs(complex(np.polyval(den, dl) / np.polyval(num, dl)))
        return k, T_I, T_z, math.degrees(math.pi + float(np.angle(np.polyval(num, dl) / np.polyval(den, dl))))

    def margin(w: float, x: float, y: float) -> float:
        """The phase margin at ``w`` where the shape is admissible (else ``-inf``)."""
        k, T_I, T_z, at_w = gains(w, x, y)
        if not (math.isfinite(k) and k > 0.0):
            return -math.inf
        kp, ki, kd = _series(k, T_I, T_z)
        num, den = delta_loop_polynomials(kp, ki, kd, derivative_time(kp, kd, N), dt, phi, tau, d)
        crossings, ms, gm, stable = _grid_margins(num, den, dt, points)
        if not stable or ms > MAX_SENSITIVITY_PEAK or gm < MIN_GAIN_MARGIN_DB:
            return -math.inf
        others = [p for p, at in crossings if not 0.98 < at / w < 1.02]  # crossovers other than w's, on the grid
        return min([(at_w + 180.0) % 360.0 - 180.0, *others])

    def best(w: float) -> tuple[float, float]:
        """The largest margin at ``w`` over the lead ``y`` (integral pushed out) and its ``y``."""
        values = [margin(w, x_free, y) for y in ys]
        j = int(np.argmax(values))
        lo, hi = math.log(ys[max(j - 1, 0)]), math.log(ys[min(j + 1, len(ys) - 1)])
        for _ in range(20):  # golden section on log y
            a, b = hi - 0.618 * (hi - lo), lo + 0.618 * (hi - lo)
            if margin(w, x_free, math.exp(a)) >= margin(w, x_free, math.exp(b)):
                hi = b
            else:
                lo = a
        y = math.exp(0.5 * (lo + hi))
        value = margin(w, x_free, y)
        return (value, y) if value >= values[j] else (values[j], float(ys[j]))

    w_hi = min(w_cap, 0.9 * w_nyq)
    if best(w_hi)[0] >= pm:
        w_max = w_star = w_hi
    else:
        w_lo = w_hi
        while best(w_lo)[0] < pm:
            w_lo /= 2.0
            if w_lo < 1e-6 * w_nyq:
                return []
        for _ in range(24):  # w_max to 3e-8 of the bracket's log width
            mid = math.sqrt(w_lo * w_hi)
            if best(mid)[0] >= pm:
                w_lo = mid
            else:
                w_hi = mid
        w_max = w_lo
        w_star = CROSSOVER_KEPT * w_max
    found = []  # (ki, x, y) of the smallest x (the strongest integral) admissible for each lead y
    for y in ys:
        if margin(w_star, x_free, y) < pm:
            continue
        lo, hi = math.log(1e-2), math.log(x_free)
        if margin(w_star, math.exp(lo), y) >= pm:
            hi = lo
        for _ in range(40):
            if hi - lo < 1e-9:
                break
            mid = 0.5 * (lo + hi)
            if margin(w_star, math.exp(mid), y) >= pm:
                hi = mid
            else:
                lo = mid
        k, T_I, _, _ = gains(w_star, math.exp(hi), y)
        found.append((k / T_I, math.exp(hi), float(y)))
    if not found:
        return []
    _, x, y = max(found)
    k, T_I, T_z, _ = gains(w_star, x, y)
    if T_z > T_I:  # the same controller with the integral's zero the lower one: k (1 + 1/(T_I s)) (1 + T_z s)
        k, T_I, T_z = k * T_z / T_I, T_z, T_I
    return [k, T_I, T_z, w_star, w_max]


@functools.lru_cache(maxsize=256)
def _resolve(phi: float, tau: float, max_S: float, pm: float, N: float, dt: float, d: int, setting: str) -> tuple:
    """``(design, reason, the paper's gains?, k, T_I, T_z, design margin, paper's sampled margin, carried design's
    sampled margin)``."""
    k0 = 1.0 / max_S
    T0 = _rule(k0, phi, pm)
    kp0 = k0 * (T0 + tau) / T0
    tau_d0 = derivative_time(kp0, k0 * tau, N) if math.isfinite(kp0) else math.nan
    if not all(math.isfinite(x) and x > 0 for x in (k0, T0, kp0, k0 / T0, k0 * tau, tau_d0, dt / tau_d0, dt / tau)):
        raise OverflowError(f"pid: the paper's PID is not finite (k = {k0:g}, T_I = {T0:g}, kp = {kp0:g}, "
                            f"tau_d = {tau_d0:g} s)")
    loop: dict[str, Any] = dict(tau=tau, phi=phi, derivative_N=N, dt=dt, delay_samples=d)
    paper_pm, w0, ms0, _, paper_stable = sampled_loop_margins(*_series(k0, T0, tau), **loop)
    paper_pm = paper_pm if paper_stable else -math.inf
    cost = pm - paper_pm
    has = (f"the paper's design has {paper_pm:.2f} deg" if math.isfinite(paper_pm)
           else "the paper's design is unstable") + (f" on the sampled loop (dt = {dt:g} s, delay {d} samples, "
                                                       f"derivative filter N = {N:g}), target {pm:g} deg")
    paper = (True, k0, T0, tau, pm, paper_pm, paper_pm)
    if setting == "paper" or (setting == "auto" and cost <= AUTO_THRESHOLD_DEG):
        why = "[pid] design = 'paper'" if setting == "paper" else f"auto: {has}: within {AUTO_THRESHOLD_DEG:g} deg"
        return ("paper", why, *paper)
    head = ("[pid] design = 'sampled'" if setting == "sampled" else
            f"auto: {has}: more than {AUTO_THRESHOLD_DEG:g} deg lost")
    if paper_pm >= pm:  # the paper's gains meet the target on the sampled loop: they are the sampled design
        return ("sampled", f"{head}; the paper's gains meet the target on the sampled loop", *paper)
    w_cap = w0 if math.isfinite(w0) and paper_stable else 0.5 * math.pi / dt
    found = memo(SEARCH_VERSION, (phi, tau, pm, N, dt, d, w_cap),
                 lambda: _free_search(phi, tau, pm, N, dt, d, w_cap),
                 valid=lambda v: isinstance(v, list) and len(v) in (0, 5) and all(isinstance(x, float) for x in v))
    if not found:
        raise ValueError(f"pid.design: no sampled PID meets the phase margin {pm:g} deg with |S| <= "
                         f"{MAX_SENSITIVITY_PEAK:g} and a gain margin >= {MIN_GAIN_MARGIN_DB:g} dB at dt = {dt:g} s "
                         f"with a delay of {d} samples (derivative filter N = {N:g}); expected a feasible loop "
                         f"(lower pid.phase_margin_deg or the delay, or raise pid.derivative_N)")
    k, T_I, T_z, _, w_max = found
    got, w1, ms1, gm1, _ = sampled_loop_margins(*_series(k, T_I, T_z), **loop)
    if setting == "auto" and AUTO_KEEPS_CROSSOVER and w1 < 0.999 * w0:
        return ("paper", f"auto: {has}, and a sampled PID meets it only at a crossover of {w1:.4g} rad/s, {w1 / w0:.3g} "
                f"of the paper's {w0:.4g} (the margin and the speed conflict: docs/delay.md): kept the paper's; "
                f"design = 'sampled' carries it", *paper)
    if w1 < 0.999 * w0:
        cost_w = (f"the crossover {w1:.4g} rad/s, {w1 / w0:.3g} of the paper's {w0:.4g} (the largest this PID "
                  f"reaches with the target is {w_max:.4g}: docs/delay.md)")
    else:
        cost_w = f"the paper's crossover {w0:.4g} rad/s kept"
    why = (f"{head}; kd free of the pole cancellation: {got:.2f} deg, {cost_w}, |S| peak {ms1:.3g} (paper's "
           f"{ms0:.3g}), gain margin {gm1:.3g} dB")
    return ("sampled", why, False, k, T_I, T_z, pm, paper_pm, got)


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
    k, T_I, T_z : float
        The PID as ``k (1 + 1 / (T_I s)) (1 + T_z s)``: gain [V/m], integrator time [s] and derivative time [s]
        (``T_z = tau`` for the paper's: its zero cancels the design model's pole; free in the sampled design).
    design_phase_margin_deg : float
        The margin the continuous rule eq:pidTime was given [deg] (the config's target).
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
    T_z: float
    design_phase_margin_deg: float
    kp: float
    ki: float
    kd: float
    tau_d: float
    paper_sampled_pm_deg: float
    sampled_pm_deg: float


def resolve_pid(cfg: Config, *, design: str | None = None) -> PIDChoice:
    """The PID the config carries: ``[pid] design`` resolved (the one place every reader of the PID goes through).

    ``paper``: the rule of section 4.1 (:func:`pid_gains`) on the continuous design model. ``sampled``: the
    paper's gains where they meet ``pid.phase_margin_deg`` on the sampled loop of
    :mod:`obsdesign.design.sampled_loop` (ZOH of the design model eq:linplant, the kernel's derivative filter
    ``tau_d = kd / (kp N)`` with the config's ``N``, the drive's delay ``[hardware] delay_samples``); else the
    PID ``k (1 + 1 / (T_I s)) (1 + T_z s)`` with ``T_z`` free (no pole cancellation) that meets it with
    ``|S| <= MAX_SENSITIVITY_PEAK`` and a gain margin of at least ``MIN_GAIN_MARGIN_DB``: at the paper's
    crossover if any such PID reaches it, else at ``CROSSOVER_KEPT`` of the largest crossover one reaches, and
    there the one with the largest ``ki``. ``auto`` (default): the sampled design where the paper's loses more
    than :data:`AUTO_THRESHOLD_DEG` on the sampled loop and the sampled design keeps the paper's crossover
    (:data:`AUTO_KEEPS_CROSSOVER`), else the paper's (docs/delay.md). Its ``reason`` says
    what the sampled design costs: its crossover against the paper's, its ``|S|`` peak and gain margin.

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
    chosen, reason, papers, k, T_I, T_z, design_pm, paper_pm, got = _resolve(
        float(cfg.phi), float(cfg.pid.tau), float(cfg.pid.max_S), float(cfg.pid.phase_margin_deg), float(N),
        float(cfg.observer.dt), int(cfg.hardware.delay_samples), setting)
    tau = cfg.pid.tau
    if papers:  # the rule's own arithmetic: the paper's gains bit for bit
        _, _, kp, ki, kd = pid_gains(phi=cfg.phi, tau=tau, max_S=cfg.pid.max_S, phase_margin_deg=design_pm)
    else:
        kp, ki, kd = _series(k, T_I, T_z)  # eq:PIDparams with the derivative time T_z
    return PIDChoice(setting=setting, design=chosen, reason=reason, k=k, T_I=T_I, T_z=T_z,
                     design_phase_margin_deg=design_pm,
                     kp=kp, ki=ki, kd=kd, tau_d=derivative_time(kp, kd, N), paper_sampled_pm_deg=paper_pm,
                     sampled_pm_deg=got)
