"""Sensitivity-based PID design of section 4.1, verified with python-control.

The plant is approximated by ``H = phi / (lambda (tau lambda + 1))``
(eq:linplant) and the controller is ``C = k (tau lambda + 1)(T_I lambda + 1) /
(T_I lambda)`` (eq:Cpid), whose zero cancels the plant pole. The design rule:
``k = 1 / max|S|`` (eq:pidGain), ``T_I`` from the phase margin (eq:pidTime),
parallel gains (eq:PIDparams). At the crossover ``|C H| = 1`` and the phase
``pi + arg(C H) = atan(T_I omega_s)``, so ``omega_s = tan(Phi) / T_I``.

Examples
--------
>>> import obsdesign as od
>>> pid = od.pid_from_config(od.load_preset("vcm"))
>>> round(pid.kp, 1), round(pid.ki), pid.kd
(429.0, 4341, 2.67)
>>> pid.max_S_achieved <= 1 / pid.k
True
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._display import ResultDisplay
from .._memo import memo
from .._validate import POSITIVE, Choice, Range
from ..params import PID_DESIGNS, Config

if TYPE_CHECKING:
    import control as ct

__all__ = ["PIDDesign", "PIDChoice", "DESIGNS", "AUTO_THRESHOLD_DEG", "design_pid", "pid_gains", "sampled_pid_gains",
           "derivative_time", "sampled_phase_margin", "sampled_crossover", "delta_loop_polynomials", "resolve_pid", "PIDDesigns", "pid_designs", "pid_from_config", "pid_from_gains", "peak_magnitude",
           "lazy_system", "kept_response", "loop_polynomials", "check_margins", "check_peak"]


class lazy_system:  # noqa: N801 (used like property)
    """A transfer function of a result, built on first use by the result's ``_build_systems()``.

    The numbers of :class:`PIDDesign`, :class:`~obsdesign.design.loop.LoopAnalysis` and
    :class:`~obsdesign.design.sampled_loop.SampledLoop` are kept on disk (:mod:`obsdesign._memo`);
    their python-control systems are rebuilt from those numbers only when a caller (a figure, a
    notebook) asks, so printing the numbers needs no python-control import.
    """

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        systems = obj.__dict__.get("_systems")
        if systems is None:
            systems = obj.__dict__["_systems"] = obj._build_systems()
        return systems[self.name]


def _is_response(n: int):
    def valid(value) -> bool:
        return (isinstance(value, list) and len(value) == 2
                and all(isinstance(part, list) and len(part) == n and all(isinstance(x, float) for x in part)
                        for part in value))

    return valid


def kept_response(result, name: str, w) -> np.ndarray:
    """The frequency response of the system ``name`` of ``result`` at ``w`` [rad/s], kept on disk.

    python-control's ``frequency_response`` of the :class:`lazy_system` ``name``, computed once per
    system and grid and kept in the result memo (:mod:`obsdesign._memo`) under the numbers the system
    is built from (``result._system_args()``), like the numbers themselves: a figure drawn again needs
    no python-control import, and its curves are the same floats.

    Parameters
    ----------
    result : PIDDesign, LoopAnalysis, SampledLoop or NoiseAnalysis
        A result with lazily built systems.
    name : str
        One of its systems (``"S"``, ``"L"``, ``"G_friction"``, ...).
    w : array_like
        Angular frequencies [rad/s], 1-D.

    Returns
    -------
    ndarray of complex
        ``G(j w)`` (continuous systems) or ``G(exp(j w dt))`` (sampled ones).

    Examples
    --------
    >>> import control as ct, obsdesign as od
    >>> pid = od.pid_from_config(od.load_preset("vcm"))
    >>> w = np.logspace(0, 4, 5)
    >>> bool(np.array_equal(kept_response(pid, "S", w), ct.frequency_response(pid.S, w).complex.ravel()))
    True
    """
    if not isinstance(getattr(type(result), name, None), lazy_system):
        raise ValueError(f"name: expected a system of {type(result).__name__}, found {name!r}")
    w = np.asarray(w, dtype=float).ravel()

    def compute() -> list:
        import control as ct

        resp = np.asarray(ct.frequency_response(getattr(result, name), w).complex, dtype=complex).ravel()
        return [resp.real.tolist(), resp.imag.tolist()]

    re, im = memo("frequency_response", (type(result).__name__, result._system_args(), name, w), compute,
                  valid=_is_response(len(w)))
    resp = np.empty(len(w), dtype=complex)
    resp.real, resp.imag = re, im  # every bit of both parts (no arithmetic: -0.0, inf and nan stay)
    return resp


_POS = POSITIVE
_PHASE = Range(low=0.0, high=90.0)


@dataclass(frozen=True, kw_only=True)
class PIDDesign(ResultDisplay):
    """A sensitivity-based PID and its verification by python-control.

    Attributes
    ----------
    k, T_I, tau, phi : float
        Total gain [V/m], integrator time [s], plant time constant [s], plant gain [m/(V s)].
    kp, ki, kd : float
        Parallel gains of eq:PIDparallel [V/m, V/(m s), V s/m].
    phase_margin_deg : float
        Design phase margin Phi [deg].
    omega_s : float
        Crossover frequency [rad/s] from the design rule.
    max_S_achieved, omega_peak : float
        Peak of |S(j omega)| over frequency [m/V] and where it occurs [rad/s].
    phase_margin_achieved_deg, gain_margin, omega_crossover : float
        From ``control.stability_margins(C H)``: phase margin, gain margin (``inf``
        for this loop, whose phase never reaches -180 deg) and gain crossover.
    closed_loop_stable : bool
        All poles of S in the open left half-plane.
    design : str
        ``"paper"`` (the rule of section 4.1) or ``"sampled"`` (gains chosen on the sampled loop with the delay,
        :func:`resolve_pid`).
    reason : str
        Why the config carries this design, in one line ("" for a design built from numbers alone).
    H, C, S : control.TransferFunction
        Plant, controller and input disturbance sensitivity ``H / (1 + H C)`` (eq:Syd).
    """

    _title = "Sensitivity-based PID"
    k: float
    T_I: float
    tau: float
    phi: float
    kp: float
    ki: float
    kd: float
    phase_margin_deg: float
    omega_s: float
    max_S_achieved: float
    omega_peak: float
    phase_margin_achieved_deg: float
    gain_margin: float
    omega_crossover: float
    closed_loop_stable: bool
    design: str = "paper"
    reason: str = ""
    H = lazy_system()
    C = lazy_system()
    S = lazy_system()

    def _system_args(self) -> tuple:
        return (self.k, self.T_I, self.tau, self.phi)

    def _build_systems(self) -> dict:
        return _systems(*self._system_args())

    def to_dict(self) -> dict:
        """JSON-ready values (the keys of ``obsdesign pid --json`` and more)."""
        keys = ("k", "T_I", "kp", "ki", "kd", "omega_s", "max_S_achieved", "phase_margin_deg", "tau", "phi",
                "omega_peak", "phase_margin_achieved_deg", "gain_margin", "omega_crossover", "closed_loop_stable",
                "design", "reason")
        return {key: getattr(self, key) for key in keys}

    def _rows(self):
        return [("k = 1/max|S| [V/m]", self.k), ("T_I [s]", self.T_I), ("tau [s]", self.tau),
                ("phi [m/(V s)]", self.phi), ("kp [V/m]", self.kp), ("ki [V/(m s)]", self.ki),
                ("kd [V s/m]", self.kd), ("phase margin (design) [deg]", self.phase_margin_deg),
                ("omega_s [rad/s]", self.omega_s), ("max|S| achieved [m/V]", self.max_S_achieved),
                ("at omega [rad/s]", self.omega_peak),
                ("phase margin (python-control) [deg]", self.phase_margin_achieved_deg),
                ("crossover (python-control) [rad/s]", self.omega_crossover),
                ("closed loop stable", self.closed_loop_stable), ("design", self.design)] + (
                    [("why", self.reason)] if self.reason else [])


def peak_magnitude(sys: ct.TransferFunction) -> tuple[float, float]:
    """Peak magnitude over frequency and where it is: dense log grid, then a bounded refinement.

    Parameters
    ----------
    sys : control.TransferFunction
        A stable SISO system.

    Returns
    -------
    (float, float)
        ``max |sys(j omega)|`` and ``omega`` [rad/s].
    """
    import control as ct
    import scipy.optimize

    w = np.logspace(-4, 6, 4001)
    mag = np.abs(ct.frequency_response(sys, w).complex.ravel())
    i = int(mag.argmax())
    lo, hi = np.log10(w[max(i - 1, 0)]), np.log10(w[min(i + 1, w.size - 1)])
    res = scipy.optimize.minimize_scalar(
        lambda lw: -abs(complex(sys(1j * 10.0**lw))), bounds=(lo, hi), method="bounded",
        options={"xatol": 1e-10},
    )
    best = -float(res.fun)
    return (best, float(10.0**res.x)) if best >= mag[i] else (float(mag[i]), float(w[i]))


def _systems(k: float, T_I: float, tau: float, phi: float) -> dict:
    import control as ct

    H = ct.tf([phi], [tau, 1.0, 0.0])
    C = ct.tf([k * tau * T_I, k * (tau + T_I), k], [T_I, 0.0])
    return {"H": H, "C": C, "S": ct.feedback(H, C)}  # S = H / (1 + H C), eq:Syd


def _verification(k: float, T_I: float, tau: float, phi: float) -> list:
    """python-control's numbers of the loop: peak of |S| and where, margins, stability."""
    import control as ct

    sys = _systems(k, T_I, tau, phi)
    peak, w_peak = peak_magnitude(sys["S"])
    gm, pm, _, _, wgc, _ = ct.stability_margins(sys["C"] * sys["H"])
    return [peak, w_peak, float(pm), float(gm), float(wgc), bool(np.all(np.real(ct.poles(sys["S"])) < 0))]


def loop_polynomials(k: float, T_I: float, tau: float, phi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``L = C H`` of eq:Cpid and eq:linplant as polynomials in ``s`` (highest power first), NumPy only.

    Parameters
    ----------
    k, T_I, tau, phi : float
        Total gain [V/m], integrator time [s], plant time constant [s], plant gain [m/(V s)].

    Returns
    -------
    (ndarray, ndarray, ndarray)
        Numerator and denominator of ``L``, and the numerator of ``S = H / (1 + H C)`` over ``den_L + num_L``.

    Examples
    --------
    >>> num, den, _ = loop_polynomials(400.0, 0.1, 0.01, 0.04)
    >>> [float(c) for c in den]
    [0.001, 0.1, 0.0, 0.0]
    """
    num_C, den_C = np.array([k * tau * T_I, k * (tau + T_I), k]), np.array([T_I, 0.0])
    num_H, den_H = np.array([phi]), np.array([tau, 1.0, 0.0])
    return np.polymul(num_C, num_H), np.polymul(den_C, den_H), np.polymul(num_H, den_C)


_GRID = np.logspace(-4, 6, 801)
_RTOL = 1e-6


def _close(a: float, b: float, rtol: float = _RTOL) -> bool:
    return bool(abs(a - b) <= rtol * max(abs(a), abs(b), 1e-300))


def check_margins(num_L, den_L, *, pm: float, wgc: float, gm: float, wpc: float | None = None) -> str | None:
    """Why kept margins are not those of the loop ``L = num_L / den_L`` (continuous), or ``None`` if they are.

    Parameters
    ----------
    num_L, den_L : array_like
        The loop's polynomials in ``s`` (highest power first).
    pm, wgc : float
        Kept phase margin [deg] and gain crossover [rad/s].
    gm : float
        Kept gain margin [-] (``inf``: none).
    wpc : float, optional
        Kept phase crossover [rad/s].

    Notes
    -----
    Cheap arithmetic (NumPy's ``polyval``), used when a result is read back from the result memo: at the
    kept gain crossover ``|L| = 1`` and ``180 + arg L`` is the kept phase margin; a finite gain margin is
    ``1 / |L|`` where the phase is -180 deg (at ``wpc`` when given, else at a phase crossover on a grid),
    an infinite one means the grid holds no phase crossover.
    """
    def L(w):
        jw = 1j * np.asarray(w, dtype=float)
        return np.polyval(num_L, jw) / np.polyval(den_L, jw)

    if math.isfinite(wgc) and wgc > 0:
        at = complex(L(wgc))
        if not _close(abs(at), 1.0, 1e-5):
            return f"its gain crossover {wgc:.6g} rad/s has |L| = {abs(at):.6g}, not 1"
        phase = (180.0 + math.degrees(math.atan2(at.imag, at.real))) % 360.0
        if not (_close(phase, pm % 360.0, 1e-5) or abs(phase - pm % 360.0) > 360.0 - 1e-6):
            return f"its phase margin {pm:.6g} deg is not the loop's {phase:.6g} deg at {wgc:.6g} rad/s"
    elif math.isfinite(pm):
        return f"a phase margin of {pm:.6g} deg without a gain crossover"
    values = L(_GRID)
    crossing = (values.imag[:-1] * values.imag[1:] <= 0) & (values.real[:-1] < 0)
    if math.isinf(gm):
        if gm < 0 or crossing.any():
            return "an infinite gain margin although the phase crosses -180 deg"
    elif not (gm > 0):
        return f"a gain margin of {gm!r}"
    elif wpc is not None:
        if not (math.isfinite(wpc) and wpc > 0):
            return f"a gain margin of {gm:.6g} without a phase crossover"
        at = complex(L(wpc))
        if not (_close(abs(at), 1.0 / gm, 1e-5) and abs(at.imag) <= 1e-5 * abs(at) and at.real < 0):
            return f"its gain margin {gm:.6g} is not the loop's at {wpc:.6g} rad/s"
    elif not crossing.any():
        return f"a gain margin of {gm:.6g} although the phase never crosses -180 deg"
    return None


def check_peak(num, den, *, peak: float, w_peak: float, name: str) -> str | None:
    """Why a kept peak of ``|num / den|`` over frequency is wrong (its value at ``w_peak``, and no grid point
    above it), or ``None``.

    Parameters
    ----------
    num, den : array_like
        The system's polynomials in ``s`` (highest power first).
    peak, w_peak : float
        Kept peak magnitude and its frequency [rad/s].
    name : str
        The system's name, for the reason.

    Examples
    --------
    >>> check_peak([1.0], [1.0, 1.0], peak=1.0, w_peak=1e-4, name="G") is None
    True
    >>> check_peak([1.0], [1.0, 1.0], peak=0.5, w_peak=1.0, name="G")
    'its peak of |G| 0.5 is not |G| = 0.707107 at 1 rad/s'
    """
    if not (math.isfinite(peak) and math.isfinite(w_peak) and w_peak > 0):
        return f"a peak of |{name}| of {peak!r} at {w_peak!r} rad/s"
    at = float(abs(np.polyval(num, 1j * w_peak) / np.polyval(den, 1j * w_peak)))
    if not _close(at, peak):
        return f"its peak of |{name}| {peak:.6g} is not |{name}| = {at:.6g} at {w_peak:.6g} rad/s"
    grid = np.abs(np.polyval(num, 1j * _GRID) / np.polyval(den, 1j * _GRID)).max()
    if grid > peak * (1 + _RTOL):
        return f"its peak of |{name}| {peak:.6g} is below |{name}| = {grid:.6g} elsewhere"
    return None


def _verify(args: tuple):
    """The re-verification of a kept ``pid`` entry (see :func:`obsdesign._memo.memo`)."""
    def verify(value) -> str | None:
        num_L, den_L, num_S = loop_polynomials(*args)
        peak, w_peak, pm, gm, wgc, stable = value
        char = np.polyadd(den_L, num_L)
        why = (check_margins(num_L, den_L, pm=pm, wgc=wgc, gm=gm)
               or check_peak(num_S, char, peak=peak, w_peak=w_peak, name="S"))
        if why is None and stable != bool(np.all(np.roots(char).real < 0)):
            why = f"it says the closed loop is {'stable' if stable else 'unstable'}; its poles say otherwise"
        return why

    return verify


def _is_pid_numbers(value) -> bool:
    return (isinstance(value, list) and len(value) == 6 and all(isinstance(x, float) for x in value[:5])
            and isinstance(value[5], bool))


def _build(k: float, T_I: float, tau: float, phi: float, phase_margin_deg: float) -> PIDDesign:
    args = (k, T_I, tau, phi)
    peak, w_peak, pm, gm, wgc, stable = memo("pid", args, lambda: _verification(*args), valid=_is_pid_numbers,
                                             verify=_verify(args))
    return PIDDesign(
        k=k, T_I=T_I, tau=tau, phi=phi, kp=k * (T_I + tau) / T_I, ki=k / T_I, kd=k * tau,  # eq:PIDparams
        phase_margin_deg=phase_margin_deg, omega_s=math.tan(math.radians(phase_margin_deg)) / T_I,
        max_S_achieved=peak, omega_peak=w_peak, phase_margin_achieved_deg=pm,
        gain_margin=gm, omega_crossover=wgc, closed_loop_stable=stable,
    )


def design_pid(*, phi: float, tau: float, max_S: float, phase_margin_deg: float) -> PIDDesign:
    """Design the PID from the plant (phi, tau) and the specification (max|S|, Phi).

    Parameters
    ----------
    phi : float
        Plant gain of eq:linplant [m/(V s)].
    tau : float
        Plant time constant [s].
    max_S : float
        Bound of the input disturbance sensitivity [m/V]; ``k = 1/max_S`` (eq:pidGain).
    phase_margin_deg : float
        Phase margin Phi at the crossover, in (0, 90) degrees (eq:pidTime, eq:L_omegas).

    Returns
    -------
    PIDDesign

    Examples
    --------
    >>> pid = design_pid(phi=0.0407, tau=0.006675, max_S=1/400, phase_margin_deg=60.0)
    >>> round(pid.T_I, 5), round(pid.phase_margin_achieved_deg, 6)
    (0.09214, 60.0)
    """
    k, T_I, _, _, _ = pid_gains(phi=phi, tau=tau, max_S=max_S, phase_margin_deg=phase_margin_deg)
    return _build(k, T_I, float(tau), float(phi), float(phase_margin_deg))


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
    phi = _POS.check("phi", phi)
    tau = _POS.check("tau", tau)
    max_S = _POS.check("max_S", max_S)
    pm = _PHASE.check("phase_margin_deg", phase_margin_deg)
    k = 1.0 / max_S  # eq:pidGain
    t2 = math.tan(math.radians(pm)) ** 2
    T_I = t2 / (k * phi * math.sqrt(1.0 + t2))  # eq:pidTime
    return k, T_I, k * (T_I + tau) / T_I, k / T_I, k * tau  # eq:PIDparams


#: The choices of ``[pid] design``: the paper's rule, the sampled design, or the sampled design where the
#: loop that runs costs the paper's rule more than :data:`AUTO_THRESHOLD_DEG` of phase margin.
DESIGNS = PID_DESIGNS
#: Phase margin [deg] the sampled loop may lose against the paper's design before ``auto`` picks ``sampled``.
AUTO_THRESHOLD_DEG = 3.0


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


def _rule(k: float, phi: float, pm_deg: float) -> float:
    """``T_I`` of eq:pidTime for the gain ``k`` and the design phase margin ``pm_deg``."""
    t2 = math.tan(math.radians(pm_deg)) ** 2
    return t2 / (k * phi * math.sqrt(1.0 + t2))


def _sampled_search(phi: float, tau: float, max_S: float, pm: float, N: float, dt: float, d: int) -> list:
    """``[k, T_I, design margin, sampled margin]`` of the sampled design (:func:`sampled_design`'s search)."""
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
    k, T_I, design, got = memo("pid_sampled", (phi, tau, max_S, pm, N, dt, d),
                               lambda: _sampled_search(phi, tau, max_S, pm, N, dt, d),
                               valid=lambda v: isinstance(v, list) and len(v) == 4
                               and all(isinstance(x, float) for x in v))
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
    sampled design where the paper's loses more than :data:`AUTO_THRESHOLD_DEG` on the sampled loop, else the
    paper's (docs/delay.md).

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


def pid_from_config(cfg: Config, *, design: str | None = None) -> PIDDesign:
    """The PID the config carries (:func:`resolve_pid`) with python-control's verification (:func:`design_pid`'s).

    Parameters
    ----------
    cfg : Config
        The design; its ``pid`` section, ``phi``, ``observer.dt`` and ``[hardware] delay_samples``.
    design : str, optional
        One of :data:`DESIGNS` instead of ``cfg.pid.design``.
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    c = resolve_pid(cfg, design=design)
    if c.design == "paper":
        pid = design_pid(phi=cfg.phi, tau=cfg.pid.tau, max_S=cfg.pid.max_S, phase_margin_deg=cfg.pid.phase_margin_deg)
    else:
        pid = _build(c.k, c.T_I, float(cfg.pid.tau), float(cfg.phi), c.design_phase_margin_deg)
    return dataclasses.replace(pid, design=c.design, reason=c.reason)


@dataclass(frozen=True, kw_only=True)
class PIDDesigns(ResultDisplay):
    """Both PID designs of a config on the sampled loop with the delay, and the one the config carries.

    Attributes
    ----------
    carried : PIDDesign
        The design the config carries (:func:`pid_from_config`), verified by python-control.
    paper, sampled : PIDChoice or None
        The paper's rule and the sampled design (``None``: no sampled design meets the target, see ``note``).
    dt : float
        Sample time [s].
    delay_samples : int
        The drive's delay [samples].
    target_deg : float
        The config's phase margin ``pid.phase_margin_deg`` [deg].
    note : str
        Why there is no sampled design ("" when there is).
    """

    _title = "Sensitivity-based PID: the paper's rule and the sampled design"
    carried: PIDDesign
    paper: PIDChoice
    sampled: PIDChoice | None
    dt: float
    delay_samples: int
    target_deg: float
    note: str = ""

    def to_dict(self) -> dict:
        """JSON-ready values: the carried design's keys of :meth:`PIDDesign.to_dict`, ``paper`` and ``sampled``."""
        def one(c: PIDChoice | None):
            if c is None:
                return None
            pm = c.sampled_pm_deg
            return {"k": c.k, "T_I": c.T_I, "kp": c.kp, "ki": c.ki, "kd": c.kd, "tau_d": c.tau_d,
                    "design_phase_margin_deg": c.design_phase_margin_deg,
                    "sampled_phase_margin_deg": pm if math.isfinite(pm) else None}

        return {**self.carried.to_dict(), "setting": self.paper.setting, "dt": self.dt,
                "delay_samples": self.delay_samples, "target_phase_margin_deg": self.target_deg,
                "paper": one(self.paper), "sampled": one(self.sampled), "note": self.note}

    def _rows(self):
        rows = list(self.carried._rows())
        where = f"dt = {self.dt:g} s, delay {self.delay_samples} samples"
        for name, c in (("paper", self.paper), ("sampled", self.sampled)):
            if c is None:
                rows.append((f"{name}: no design", self.note))
                continue
            rows += [(f"{name}: kp [V/m] / ki [V/(m s)] / kd [V s/m]", f"{c.kp:.6g} / {c.ki:.6g} / {c.kd:.6g}"),
                     (f"{name}: k [V/m] / T_I [s]", f"{c.k:.6g} / {c.T_I:.6g}"),
                     (f"{name}: phase margin on the sampled loop ({where}) [deg]",
                      f"{c.sampled_pm_deg:.4g} (target {self.target_deg:g})")]
        rows.append(("carried by the config", f"{self.carried.design} ([pid] design = {self.paper.setting!r})"))
        return rows


def pid_designs(cfg: Config) -> PIDDesigns:
    """The paper's and the sampled PID of ``cfg`` on its sampled loop, and the one it carries (``obsdesign pid``).

    Parameters
    ----------
    cfg : Config
        The design.

    Returns
    -------
    PIDDesigns

    Examples
    --------
    >>> import obsdesign as od
    >>> d = pid_designs(od.load_preset("vcm").override(delay_samples=1))
    >>> d.carried.design, round(d.paper.sampled_pm_deg, 2), round(d.sampled.sampled_pm_deg, 2)
    ('paper', 59.91, 60.0)
    """
    carried = pid_from_config(cfg)
    paper = resolve_pid(cfg, design="paper")
    paper = dataclasses.replace(paper, setting=cfg.pid.design)
    sampled, note = None, ""
    try:
        sampled = dataclasses.replace(resolve_pid(cfg, design="sampled"), setting=cfg.pid.design)
    except ValueError as exc:
        note = str(exc)
    return PIDDesigns(carried=carried, paper=paper, sampled=sampled, dt=cfg.observer.dt,
                      delay_samples=cfg.hardware.delay_samples, target_deg=cfg.pid.phase_margin_deg, note=note)


def pid_from_gains(*, kp: float, ki: float, kd: float, phi: float) -> PIDDesign:
    """Recover ``k, T_I, tau`` and the phase margin from parallel gains and phi.

    Parameters
    ----------
    kp, ki, kd : float
        Parallel gains [V/m, V/(m s), V s/m], > 0.
    phi : float
        Plant gain of eq:linplant [m/(V s)], > 0.

    From eq:PIDparams, ``kd = k tau`` and ``ki = k / T_I`` give
    ``kp = k + kd ki / k``, i.e. ``k^2 - kp k + kd ki = 0``. Its two roots swap
    the roles of ``tau`` and ``T_I``; the larger ``k`` (``T_I >= tau``: the
    integrator slower than the plant pole) is returned. The phase margin solves
    eq:pidTime: ``tan^2(Phi) / sqrt(1 + tan^2(Phi)) = k phi T_I``.

    Examples
    --------
    >>> pid = pid_from_gains(kp=429, ki=4348, kd=2.67, phi=3.28 * 0.006675 / 0.538)
    >>> round(pid.k, 1), round(pid.tau, 6), round(pid.phase_margin_deg, 2)
    (400.0, 0.006675, 59.96)
    """
    kp, ki, kd, phi = (_POS.check(n, v) for n, v in (("kp", kp), ("ki", ki), ("kd", kd), ("phi", phi)))
    disc = kp * kp - 4.0 * kd * ki
    if disc < 0:
        raise ValueError(f"gains: expected kp^2 >= 4 kd ki for a real k, found kp^2 - 4 kd ki = {disc:.6g}")
    k = (kp + math.sqrt(disc)) / 2.0
    tau, T_I = kd / k, k / ki
    c = k * phi * T_I  # = t / sqrt(1 + t) with t = tan^2(Phi)
    t = (c * c + math.sqrt(c**4 + 4.0 * c * c)) / 2.0
    return _build(k, T_I, tau, phi, math.degrees(math.atan(math.sqrt(t))))
