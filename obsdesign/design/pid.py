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
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._display import ResultDisplay
from .._memo import memo
from .._validate import POSITIVE, Range
from ..params import Config
from .pid_sampled import pid_gains, resolve_pid

if TYPE_CHECKING:
    import control as ct

__all__ = ["PIDDesign", "design_pid", "pid_gains", "pid_from_config", "pid_from_gains", "peak_magnitude",
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
    T_z : float or None
        The controller's derivative time [s] where it is not ``tau`` (the sampled design frees ``kd`` from the
        pole cancellation: ``C = k (T_z s + 1)(T_I s + 1) / (T_I s)``); ``None``: ``tau``.
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
    T_z: float | None = None
    H = lazy_system()
    C = lazy_system()
    S = lazy_system()

    def _system_args(self) -> tuple:
        return (self.k, self.T_I, self.tau, self.phi) + (() if self.T_z is None else (self.T_z,))

    def _build_systems(self) -> dict:
        return _systems(*self._system_args())

    def to_dict(self) -> dict:
        """JSON-ready values (the keys of ``obsdesign pid --json`` and more)."""
        keys = ("k", "T_I", "kp", "ki", "kd", "omega_s", "max_S_achieved", "phase_margin_deg", "tau", "phi",
                "omega_peak", "phase_margin_achieved_deg", "gain_margin", "omega_crossover", "closed_loop_stable",
                "design", "reason", "T_z")
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


def _systems(k: float, T_I: float, tau: float, phi: float, T_z: float | None = None) -> dict:
    import control as ct

    z = tau if T_z is None else T_z  # the controller's derivative time: tau cancels the plant pole (eq:Cpid)
    H = ct.tf([phi], [tau, 1.0, 0.0])
    C = ct.tf([k * z * T_I, k * (z + T_I), k], [T_I, 0.0])
    return {"H": H, "C": C, "S": ct.feedback(H, C)}  # S = H / (1 + H C), eq:Syd


def _verification(k: float, T_I: float, tau: float, phi: float, T_z: float | None = None) -> list:
    """python-control's numbers of the loop: peak of |S| and where, margins, stability."""
    import control as ct

    sys = _systems(k, T_I, tau, phi, T_z)
    peak, w_peak = peak_magnitude(sys["S"])
    gm, pm, _, _, wgc, _ = ct.stability_margins(sys["C"] * sys["H"])
    return [peak, w_peak, float(pm), float(gm), float(wgc), bool(np.all(np.real(ct.poles(sys["S"])) < 0))]


def loop_polynomials(k: float, T_I: float, tau: float, phi: float,
                     T_z: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``L = C H`` of eq:Cpid and eq:linplant as polynomials in ``s`` (highest power first), NumPy only.

    Parameters
    ----------
    k, T_I, tau, phi : float
        Total gain [V/m], integrator time [s], plant time constant [s], plant gain [m/(V s)].
    T_z : float, optional
        The controller's derivative time [s] where it is not ``tau`` (the sampled design's free ``kd``,
        :func:`~obsdesign.design.pid_sampled.resolve_pid`): ``C = k (T_z s + 1)(T_I s + 1) / (T_I s)``.

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
    z = tau if T_z is None else T_z
    num_C, den_C = np.array([k * z * T_I, k * (z + T_I), k]), np.array([T_I, 0.0])
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


def _build(k: float, T_I: float, tau: float, phi: float, phase_margin_deg: float,
           T_z: float | None = None) -> PIDDesign:
    args = (k, T_I, tau, phi) + (() if T_z is None else (T_z,))
    z = tau if T_z is None else T_z
    peak, w_peak, pm, gm, wgc, stable = memo("pid", args, lambda: _verification(*args), valid=_is_pid_numbers,
                                             verify=_verify(args))
    return PIDDesign(
        k=k, T_I=T_I, tau=tau, phi=phi, kp=k * (T_I + z) / T_I, ki=k / T_I, kd=k * z, T_z=T_z,  # eq:PIDparams
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


def pid_from_config(cfg: Config, *, design: str | None = None) -> PIDDesign:
    """The PID the config carries (:func:`~obsdesign.design.pid_sampled.resolve_pid`), verified by python-control.

    Parameters
    ----------
    cfg : Config
        The design; its ``pid`` section, ``phi``, ``observer.dt`` and ``[hardware] delay_samples``.
    design : str, optional
        ``"auto"``, ``"paper"`` or ``"sampled"`` instead of ``cfg.pid.design``.
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    c = resolve_pid(cfg, design=design)
    if c.design == "paper":
        pid = design_pid(phi=cfg.phi, tau=cfg.pid.tau, max_S=cfg.pid.max_S, phase_margin_deg=cfg.pid.phase_margin_deg)
    else:
        tau = float(cfg.pid.tau)
        pid = _build(c.k, c.T_I, tau, float(cfg.phi), c.design_phase_margin_deg, None if c.T_z == tau else c.T_z)
    return dataclasses.replace(pid, design=c.design, reason=c.reason)


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
