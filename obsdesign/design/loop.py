"""Loop views of the sensitivity-based PID: margins, sensitivities, bandwidth, poles.

Three systems, each labelled where it is printed: the **continuous idealisation** below (ideal PID, no
sampling; the top-level numbers), the **sampled loop** on the PID's design model (ZOH plant, the kernel's
discrete PID with its derivative filter, ``hardware.delay_samples`` of drive delay;
:mod:`obsdesign.design.sampled_loop`, the ``sampled`` attribute and key) and the same sampled loop around
the **simulated plant** (mass, viscous friction, pre-sliding stiffness, actuator gain of the plant that
``simulate`` runs; :mod:`obsdesign.design.plant_loop`, the ``simulated`` attribute, key ``simulated_plant``).

The continuous loop is the one of :mod:`obsdesign.design.pid`: plant ``H = phi / (s (tau s + 1))``
(eq:linplant), controller ``C = k (tau s + 1)(T_I s + 1) / (T_I s)`` (eq:Cpid) and the
loop transfer ``L = C H``. Everything is computed with python-control:

* gain and phase margins and the gain crossover from ``stability_margins(L)``;
* the output sensitivity ``S = 1 / (1 + L)`` and the complementary sensitivity
  ``T = L / (1 + L)``, their peaks over frequency;
* the input-disturbance sensitivity ``H / (1 + H C)`` [m/V] (eq:Syd), which is the
  ``|S|`` the PID design bounds by ``max_S`` -- a different function from the output
  sensitivity above, reported as ``max_S_disturbance``;
* the bandwidth of ``T``: the first frequency where ``|T| = 1/sqrt(2)`` (-3.01 dB);
* the closed-loop poles: the roots of ``den(L) + num(L)``, without cancelling the
  controller zero against the plant pole ``-1/tau`` (that pole stays a pole of the
  disturbance response, so it belongs to the closed loop).

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.design.loop import loop_analysis
>>> la = loop_analysis(od.load_preset("vcm"))
>>> round(la.phase_margin_deg, 6), la.gain_margin_db
(60.0, inf)
>>> round(la.crossover_rad_s, 3), round(la.max_T, 4), round(la.bandwidth_rad_s, 1)
(18.796, 1.3416, 25.8)
>>> la.to_dict()["gain_margin_db"] is None
True
>>> round(la.sampled.phase_margin_deg, 2), round(la.sampled.gain_margin, 1)  # the loop that runs
(60.02, 1121.5)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._memo import memo
from ..params import Config, load_preset
from .pid import PIDDesign, check_margins, check_peak, kept_response, lazy_system, loop_polynomials, peak_magnitude, pid_from_config
from .plant_loop import PlantLoop, plant_loops
from .sampled_loop import SampledLoop, sampled_loop
from .._display import ResultDisplay

if TYPE_CHECKING:
    import control as ct

__all__ = ["LoopAnalysis", "loop_analysis", "loop_figure"]

#: ``|T| = 1/sqrt(2)`` in dB (python-control's ``bandwidth`` default of -3 dB is 0.70795).
_HALF_POWER_DB = 20.0 * math.log10(1.0 / math.sqrt(2.0))


@dataclass(frozen=True, kw_only=True)
class LoopAnalysis(ResultDisplay):
    """Margins, sensitivity peaks, bandwidth and closed-loop poles of ``L = C H``, and the sampled loop.

    The attributes but ``sampled`` are those of the continuous idealisation (ideal PID, no sampling).

    Attributes
    ----------
    gain_margin_db : float
        Gain margin [dB]; ``inf`` when the phase of ``L`` never crosses -180 deg
        (the case of this PID loop).
    phase_margin_deg : float
        Phase margin [deg] at the gain crossover.
    crossover_rad_s : float
        Gain crossover frequency, ``|L(j w)| = 1`` [rad/s].
    phase_crossover_rad_s : float
        Frequency where the phase of ``L`` is -180 deg [rad/s] (``nan`` when there is none).
    max_S, omega_max_S : float
        Peak of the output sensitivity ``|1 / (1 + L)|`` [-] and where it occurs [rad/s].
    max_T, omega_max_T : float
        Peak of ``|L / (1 + L)|`` [-] and where it occurs [rad/s].
    max_S_disturbance : float
        Peak of the input-disturbance sensitivity ``|H / (1 + H C)|`` [m/V] (the PID design's ``|S|``).
    bandwidth_rad_s : float
        First frequency where ``|T| = 1/sqrt(2)`` [rad/s].
    closed_loop_poles : tuple of complex
        Roots of the characteristic polynomial ``den(L) + num(L)`` [rad/s], sorted by real part.
    delay_margin_s : float
        ``PM / omega_c`` [s]: the delay the continuous loop tolerates.
    max_CS : float
        Peak of ``|C / (1 + L)|`` [V/m] (noise to command): ``inf`` for the ideal PID (``kd s``).
    sampled : SampledLoop
        The sampled loop on the design model (:func:`obsdesign.design.sampled_loop.sampled_loop`).
    simulated : dict of str to PlantLoop
        The sampled loop around the simulated plant, by regime (:func:`obsdesign.design.plant_loop.plant_loops`).
    pid : PIDDesign
        The PID design the loop is built from.
    L, S, T : control.TransferFunction
        Loop transfer, output sensitivity and complementary sensitivity.
    """

    _title = "Continuous idealisation: PID loop L = C H (ideal PID, no sampling)"
    gain_margin_db: float
    phase_margin_deg: float
    crossover_rad_s: float
    phase_crossover_rad_s: float
    max_S: float
    omega_max_S: float
    max_T: float
    omega_max_T: float
    max_S_disturbance: float
    bandwidth_rad_s: float
    closed_loop_poles: tuple[complex, ...]
    delay_margin_s: float
    max_CS: float
    sampled: SampledLoop
    simulated: dict[str, PlantLoop] = field(default_factory=dict)
    pid: PIDDesign = field(repr=False, compare=False)
    L = lazy_system()
    S = lazy_system()
    T = lazy_system()

    def _system_args(self) -> tuple:
        return self.pid._system_args()

    def _build_systems(self) -> dict:
        return _systems(self.pid)

    @property
    def system(self) -> str:
        """Which system the top-level numbers are about."""
        return "continuous idealisation: ideal PID kp + ki/s + kd s on phi/(s (tau s + 1)), no sampling"

    def to_dict(self) -> dict:
        """JSON-ready values: an infinite gain margin is ``None``, poles are ``[re, im]`` pairs; the
        sampled loop under ``"sampled"`` (:meth:`SampledLoop.to_dict`)."""
        gm = self.gain_margin_db
        return {
            "gain_margin_db": None if not math.isfinite(gm) else gm,
            "phase_margin_deg": self.phase_margin_deg,
            "crossover_rad_s": self.crossover_rad_s,
            "max_S": self.max_S,
            "max_T": self.max_T,
            "bandwidth_rad_s": self.bandwidth_rad_s,
            "closed_loop_poles": [[p.real, p.imag] for p in self.closed_loop_poles],
            "max_S_disturbance": self.max_S_disturbance,
            "system": self.system,
            "delay_margin_s": self.delay_margin_s,
            "max_CS": None if not math.isfinite(self.max_CS) else self.max_CS,
            "sampled": self.sampled.to_dict(),
            "simulated_plant": {regime: pl.to_dict() for regime, pl in self.simulated.items()},
        }

    def text(self, units=None) -> str:
        """The tables as text (units of ``units``, an :class:`~obsdesign.axis.AxisSpec`)."""
        return "\n\n".join([super().text(units), self.sampled.text(units)]
                           + [pl.text(units) for pl in self.simulated.values()])

    def _repr_html_(self) -> str:
        return super()._repr_html_() + self.sampled._repr_html_() + "".join(
            pl._repr_html_() for pl in self.simulated.values())

    def _rows(self):
        gm = self.gain_margin_db
        return [
            ("gain margin [dB]", "infinite (phase never reaches -180 deg)" if math.isinf(gm) else gm),
            ("phase margin [deg]", self.phase_margin_deg),
            ("gain crossover [rad/s]", self.crossover_rad_s),
            ("max |S| output sensitivity [-]", self.max_S),
            ("  at [rad/s]", self.omega_max_S),
            ("max |T| [-]", self.max_T),
            ("  at [rad/s]", self.omega_max_T),
            ("max |H/(1+HC)| input disturbance [m/V]", self.max_S_disturbance),
            ("bandwidth of T, |T| = 1/sqrt(2) [rad/s]", self.bandwidth_rad_s),
            ("closed-loop poles [rad/s]", ", ".join(_fmt_pole(p) for p in self.closed_loop_poles)),
            ("delay margin PM / omega_c [s]", self.delay_margin_s),
            ("max |CS| noise to command [V/m]", "infinite (ideal derivative kd s)" if math.isinf(self.max_CS)
             else self.max_CS),
        ]


def _fmt_pole(p: complex) -> str:
    return f"{p.real:.4g}" if p.imag == 0 else f"{p.real:.4g}{p.imag:+.4g}j"


def loop_analysis(cfg: Config | None = None, *, phi: float | None = None, tau: float | None = None,
                  delay_samples: int | None = None) -> LoopAnalysis:
    """Analyse the loop of the config's sensitivity-based PID with python-control, continuous and sampled.

    Parameters
    ----------
    cfg : Config, optional
        The design (``pid`` section and ``phi``); default the ``vcm`` preset.
    phi, tau : float, optional
        Overrides of the plant gain [m/(V s)] and time constant [s] of eq:linplant;
        the PID is designed for (and the loop closed around) the overridden plant.
    delay_samples : int, optional
        Computation delay of the sampled loop [samples] (>= 0); default ``cfg.hardware.delay_samples``.

    Returns
    -------
    LoopAnalysis

    Raises
    ------
    TypeError
        ``cfg`` is not a Config.
    ValueError
        An override is out of range, or ``delay_samples`` is not an integer in [0, 10000].

    Examples
    --------
    >>> la = loop_analysis(tau=0.01)
    >>> round(la.phase_margin_deg, 6), len(la.closed_loop_poles)
    (60.0, 3)
    """
    if cfg is None:
        cfg = load_preset("vcm")
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config or None, found {type(cfg).__name__}")
    cfg = cfg.override(phi=phi, tau=tau, delay_samples=delay_samples)
    pid = pid_from_config(cfg)
    gm, pm, wpc, wgc, max_S, w_S, max_T, w_T, poles, bandwidth = memo(
        "loop", (pid.k, pid.T_I, pid.tau, pid.phi), lambda: _numbers(pid), valid=_is_loop_numbers,
        verify=lambda value: _verify(pid, value))
    sampled = sampled_loop(cfg)
    return LoopAnalysis(
        gain_margin_db=20.0 * math.log10(gm) if math.isfinite(gm) else math.inf,
        phase_margin_deg=pm, crossover_rad_s=wgc, phase_crossover_rad_s=wpc,
        max_S=max_S, omega_max_S=w_S, max_T=max_T, omega_max_T=w_T, max_S_disturbance=pid.max_S_achieved,
        bandwidth_rad_s=bandwidth, closed_loop_poles=tuple(poles),
        delay_margin_s=math.radians(pm) / wgc, max_CS=math.inf, sampled=sampled, simulated=plant_loops(cfg), pid=pid,
    )


def _is_loop_numbers(value) -> bool:
    return (isinstance(value, list) and len(value) == 10 and all(isinstance(value[i], float) for i in (0, 1, 2, 3, 4,
            5, 6, 7, 9)) and isinstance(value[8], list) and all(isinstance(p, complex) for p in value[8]))


def _verify(pid: PIDDesign, value: list) -> str | None:
    """Why kept loop numbers are not those of the PID's loop (NumPy arithmetic), or ``None``."""
    gm, pm, wpc, wgc, max_S, w_S, max_T, w_T, poles, bandwidth = value
    num_L, den_L, _ = loop_polynomials(*pid._system_args())
    char = np.polyadd(den_L, num_L)
    why = (check_margins(num_L, den_L, pm=pm, wgc=wgc, gm=gm, wpc=wpc if math.isfinite(gm) else None)
           or check_peak(den_L, char, peak=max_S, w_peak=w_S, name="S")
           or check_peak(num_L, char, peak=max_T, w_peak=w_T, name="T"))
    if why is not None:
        return why
    roots = sorted((complex(r) for r in np.roots(char)), key=lambda p: (p.real, p.imag))
    scale = max(abs(r) for r in roots)
    if len(roots) != len(poles) or any(abs(a - b) > 1e-6 * scale for a, b in zip(roots, poles)):
        return "its closed-loop poles are not the roots of the characteristic polynomial"
    if math.isfinite(bandwidth):
        dc = abs(num_L[-1] / char[-1]) if char[-1] else 1.0
        at = abs(np.polyval(num_L, 1j * bandwidth) / np.polyval(char, 1j * bandwidth))
        if abs(20.0 * math.log10(at / dc) - _HALF_POWER_DB) > 1e-3:
            return f"its bandwidth {bandwidth:.6g} rad/s is not where |T| is 3 dB down"
    return None


def _systems(pid: PIDDesign) -> dict:
    import control as ct

    L = pid.C * pid.H
    return {"L": L, "S": ct.feedback(ct.tf([1.0], [1.0]), L), "T": ct.feedback(L, 1)}  # 1/(1 + L), L/(1 + L)


def _numbers(pid: PIDDesign) -> list:
    """python-control's numbers of the continuous loop (what :func:`loop_analysis` keeps on disk)."""
    import control as ct

    sys = _systems(pid)
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(sys["L"])
    max_S, w_S = peak_magnitude(sys["S"])
    max_T, w_T = peak_magnitude(sys["T"])
    poles = sorted((complex(p) for p in ct.poles(sys["T"])), key=lambda p: (p.real, p.imag))
    return [float(gm), float(pm), float(wpc), float(wgc), max_S, w_S, max_T, w_T, poles,
            float(ct.bandwidth(sys["T"], dbdrop=_HALF_POWER_DB))]


def _mag_phase(result, name: str, w):
    """Response, magnitude [dB] and unwrapped phase [deg] of the system ``name`` of ``result`` (kept)."""
    resp = kept_response(result, name, w)
    return resp, 20.0 * np.log10(np.abs(resp)), np.degrees(np.unwrap(np.angle(resp)))


def loop_figure(analysis: LoopAnalysis):
    """Bode plot of ``L`` with the margins, Nyquist plot, ``|S|`` and ``|T|``, closed-loop poles.

    Each panel shows the continuous idealisation and, beside it in the same axes (dashed, labelled
    "sampled"), the sampled loop ``L(z) = C(z) H_zoh(z) z^-d`` up to the Nyquist frequency; sampled
    poles are drawn at ``s = ln(z) / dt``.

    Parameters
    ----------
    analysis : LoopAnalysis

    Returns
    -------
    matplotlib.figure.Figure
        Created with the object-oriented API (no pyplot state; works with the Agg backend).

    Examples
    --------
    >>> fig = loop_figure(loop_analysis())
    >>> len(fig.axes)
    5
    """
    if not isinstance(analysis, LoopAnalysis):
        raise TypeError(f"analysis: expected a LoopAnalysis, found {type(analysis).__name__}")
    from matplotlib.figure import Figure

    a = analysis
    wc = a.crossover_rad_s
    w = np.logspace(math.log10(wc) - 3, math.log10(wc) + 3, 1200)
    resp, mag_db, phase = _mag_phase(a, "L", w)
    # phase of L is -180 deg + atan(T_I w) here; keep the unwrapped branch that starts near -180 deg
    phase -= 360.0 * np.round((phase[0] + 180.0) / 360.0)
    sl = a.sampled
    tag = f"sampled (ZOH, discrete PID N={sl.derivative_N:g}, delay {sl.delay_samples})"
    wz = w[w < math.pi / sl.dt]
    _, zmag_db, zphase = _mag_phase(sl, "L", wz)
    zphase -= 360.0 * np.round((zphase[0] + 180.0) / 360.0)
    fig = Figure(figsize=(15, 8.5), layout="constrained")
    gs = fig.add_gridspec(2, 3)
    ax_mag, ax_ph = fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[1, 0])
    ax_ny, ax_st, ax_pz = fig.add_subplot(gs[:, 1]), fig.add_subplot(gs[0, 2]), fig.add_subplot(gs[1, 2])

    ax_mag.semilogx(w, mag_db, label="loop gain |L|, continuous idealisation")
    ax_mag.semilogx(wz, zmag_db, ls="--", color="C1", label=f"|L(z)| {tag}: GM {sl.gain_margin:.3g}")
    ax_mag.axhline(0.0, color="0.5", lw=0.8, ls="--", label="0 dB")
    ax_mag.axvline(wc, color="C3", lw=0.8, ls=":", label=f"gain crossover {wc:.4g} rad/s")
    if math.isfinite(a.gain_margin_db):
        wpc = a.phase_crossover_rad_s
        ax_mag.annotate("", xy=(wpc, 0.0), xytext=(wpc, -a.gain_margin_db),
                        arrowprops={"arrowstyle": "<->", "color": "C2"})
        ax_mag.plot([], [], color="C2", label=f"gain margin {a.gain_margin_db:.3g} dB")
    else:
        ax_mag.plot([], [], " ", label="gain margin: infinite (phase never reaches -180 deg)")
    ax_mag.set(xlabel="frequency [rad/s]", ylabel="magnitude of L [dB]", title="Loop gain")
    ax_mag.legend(fontsize="small")
    ax_mag.grid(True, which="both", alpha=0.3)

    ax_ph.semilogx(w, phase, label="phase of L, continuous idealisation")
    ax_ph.semilogx(wz, zphase, ls="--", color="C1",
                   label=f"phase of L(z) {tag}: PM {sl.phase_margin_deg:.3g} deg at {sl.crossover_rad_s:.4g} rad/s")
    ax_ph.axhline(-180.0, color="0.5", lw=0.8, ls="--", label="-180 deg")
    ax_ph.annotate("", xy=(wc, -180.0), xytext=(wc, -180.0 + a.phase_margin_deg),
                   arrowprops={"arrowstyle": "<->", "color": "C3"})
    ax_ph.plot([], [], color="C3", label=f"phase margin {a.phase_margin_deg:.3g} deg at {wc:.4g} rad/s")
    ax_ph.set(xlabel="frequency [rad/s]", ylabel="phase of L [deg]", title="Loop phase")
    ax_ph.legend(fontsize="small")
    ax_ph.grid(True, which="both", alpha=0.3)

    wn = np.logspace(math.log10(wc) - 2, math.log10(wc) + 4, 3000)
    ln = kept_response(a, "L", wn)
    ax_ny.plot(ln.real, ln.imag, label="L(jw), w > 0")
    ax_ny.plot(ln.real, -ln.imag, ls=":", color="C0", alpha=0.5, label="L(jw), w < 0 (mirror image)")
    wzn = np.logspace(math.log10(wc) - 2, math.log10(0.999999 * math.pi / sl.dt), 3000)
    lz = kept_response(sl, "L", wzn)
    ax_ny.plot(lz.real, lz.imag, ls="--", color="C1", label=f"L(exp(jw dt)) {tag}, 0 < w <= pi/dt")
    theta = np.linspace(0.0, 2.0 * math.pi, 361)
    ax_ny.plot(np.cos(theta), np.sin(theta), color="0.5", lw=0.8, label="unit circle |L| = 1")
    ax_ny.plot([-1.0], [0.0], "r+", ms=12, mew=2, label="critical point -1")
    ax_ny.set(xlim=(-3.0, 1.5), ylim=(-3.0, 3.0), aspect="equal", xlabel="real part of L [-]",
              ylabel="imaginary part of L [-]", title="Nyquist plot of L (zoomed on -1)")
    ax_ny.legend(fontsize="small", loc="lower right")
    ax_ny.grid(True, alpha=0.3)

    _, s_db, _ = _mag_phase(a, "S", w)
    _, t_db, _ = _mag_phase(a, "T", w)
    ax_st.semilogx(w, s_db, label=f"output sensitivity |S|, peak {a.max_S:.3g}")
    ax_st.semilogx(w, t_db, label=f"complementary sensitivity |T|, peak {a.max_T:.3g}")
    ax_st.semilogx(wz, _mag_phase(sl, "S", wz)[1], ls="--", color="C0", label=f"|S| sampled, peak {sl.max_S:.3g}")
    ax_st.semilogx(wz, _mag_phase(sl, "T", wz)[1], ls="--", color="C1", label=f"|T| sampled, peak {sl.max_T:.3g}")
    ax_st.axvline(a.bandwidth_rad_s, color="C1", lw=0.8, ls=":",
                  label=f"bandwidth of T {a.bandwidth_rad_s:.4g} rad/s")
    ax_st.set(xlabel="frequency [rad/s]", ylabel="magnitude [dB]", title="Sensitivities")
    ax_st.legend(fontsize="small")
    ax_st.grid(True, which="both", alpha=0.3)

    p = np.array(a.closed_loop_poles)
    ax_pz.plot(p.real, p.imag, "x", ms=10, mew=2, label="closed-loop poles, continuous idealisation")
    ps = np.log(np.array([z for z in sl.poles if z != 0] or [1.0])) / sl.dt
    ax_pz.plot(ps.real, ps.imag, "+", ms=10, mew=2, color="C1", label=f"{tag} poles at s = ln(z)/dt")
    ax_pz.axvline(0.0, color="0.5", lw=0.8, label="imaginary axis")
    ax_pz.set(xlabel="real part [rad/s]", ylabel="imaginary part [rad/s]", title="Closed-loop poles")
    ax_pz.legend(fontsize="small")
    ax_pz.grid(True, alpha=0.3)
    return fig
