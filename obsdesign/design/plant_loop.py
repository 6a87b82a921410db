"""The sampled loop around the plant that ``simulate`` runs: margins of the loop as the hardware runs it.

:mod:`obsdesign.design.sampled_loop` closes the kernel's discrete PID around the PID's design model
eq:linplant, ``phi / (s (tau s + 1))``. The simulated plant is another system: ``m x'' = K u - G - F`` with
the config's mass, actuator gain and friction. Its linearisation about an operating point is

``H(s) = K / (m s^2 + c(s) s + k)``,  ``c(s) = sigma`` (static viscous) or ``sigma / (beta s + 1)`` (lag),

and the regime sets ``k``:

* ``sliding``: gross sliding in one direction, the Coulomb force constant: ``k = 0``. Exact for the paper's
  friction model while the motion does not reverse (the loop is linear there).
* ``rest``: pre-sliding about a standstill, the stiffness bound ``k = kappa`` of the design. The paper's
  pre-sliding is hysteretic with a stiffness that falls with the amplitude (``-s Cf ln|z|``, infinite at a
  reversal): this regime is a bound, not a linearisation that a measurement reproduces.

The loop is ``L(z) = C(z) H_zoh(z) z^-d`` with the kernel's ``C(z)`` (:func:`~obsdesign.design.sampled_loop.discrete_pid`,
derivative filter included), the ZOH of ``H`` and the drive's delay ``d`` (``[hardware] delay_samples``).
python-control computes the margins (``stability_margins``), the delay margin, the peaks of ``|S|`` and
``|T|`` up to the Nyquist frequency. The ``sliding`` numbers agree with a frequency response measured on
the simulator (sines on a ramp through the nonlinear loop, tests/test_plant_loop.py, bound 1 deg and
0.5 dB): the phase margins within 0.1 deg on vcm, table1, loop2k and a 4 kHz rotary axis (docs/loop.md).

Plant friction models other than the paper's (``[plant_friction]``: lugre, dahl, gms) have bristle dynamics
that this linearisation leaves out: their loop is computed with their viscous coefficient and says so
(:attr:`PlantLoop.note`).

Examples
--------
>>> import obsdesign as od
>>> pl = plant_loop(od.load_preset("vcm"))
>>> round(pl.phase_margin_deg, 2), pl.regime       # the design model says 60.02 deg
(44.07, 'sliding')
>>> rest = plant_loop(od.load_preset("vcm"), regime="rest")   # the spring kappa moves the crossover down
>>> round(rest.phase_margin_deg, 2), round(rest.crossover_rad_s, 2)
(99.86, 1.8)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._display import ResultDisplay
from .._memo import memo
from .._validate import Choice
from ..params import Config
from .pid_sampled import sampled_pid_gains
from .margins import closed_loop, drive_delay, loop_margins
from .sampled_loop import discrete_peak, discrete_pid

__all__ = ["PlantLoop", "plant_loop", "plant_loops", "simulated_plant", "REGIMES", "LoopMargins", "loop_margins_of"]

#: Operating points of the linearisation: gross sliding (no Coulomb stiffness), rest (stiffness kappa).
REGIMES = ("sliding", "rest")


def simulated_plant(cfg: Config, *, regime: str = "sliding"):
    """The continuous linearisation ``H(s) = K / (m s^2 + c(s) s + k)`` [m/V] of the simulated plant.

    Parameters
    ----------
    cfg : Config
        The design (its plant, friction and ``[plant_friction]``).
    regime : str
        One of :data:`REGIMES`.

    Returns
    -------
    control.TransferFunction

    Examples
    --------
    >>> import obsdesign as od
    >>> H = simulated_plant(od.load_preset("vcm"))
    >>> [round(float(c), 4) for c in H.den[0][0]], [round(float(c), 4) for c in H.num[0][0]]
    ([0.538, 21.1, 0.0], [3.28])
    """
    import control as ct

    return ct.tf(*_plant_coefficients(cfg, Choice(REGIMES).check("regime", regime)))


def _plant_coefficients(cfg: Config, regime: str) -> tuple[list[float], list[float]]:
    """Numerator and denominator of :func:`simulated_plant` (NumPy-free: the memo's key)."""
    pl, fr = cfg.plant, cfg.friction
    k = fr.kappa if regime == "rest" else 0.0
    sigma = _viscous(cfg)
    if fr.beta:  # Fv = sigma v / (beta s + 1): m s^2 (beta s + 1) + sigma s + k (beta s + 1)
        return [pl.K * fr.beta, pl.K], [pl.m * fr.beta, pl.m, sigma + k * fr.beta, k]
    return [pl.K], [pl.m, sigma, k]


def _viscous(cfg: Config) -> float:
    """The viscous coefficient of the simulated plant's friction [N s/m]."""
    pf = cfg.plant_friction
    if pf is None or pf.model == "paper":
        return cfg.friction.sigma
    return float(pf.parameters.get("sigma2", pf.parameters.get("sigma", cfg.friction.sigma)))


@dataclass(frozen=True, kw_only=True)
class PlantLoop(ResultDisplay):
    """Margins of the sampled loop ``C(z) H_zoh(z) z^-d`` around the simulated plant's linearisation.

    Attributes
    ----------
    regime : str
        The operating point (:data:`REGIMES`).
    dt : float
        Sample time [s].
    delay_samples : int
        The drive's delay ``d`` [samples].
    gain_margin, gain_margin_db : float
        Gain margin [-] and [dB] (``inf``: none).
    phase_margin_deg : float
        Phase margin [deg].
    crossover_rad_s : float
        Gain crossover [rad/s].
    delay_margin_s, delay_margin_samples : float
        The extra delay the loop tolerates, ``PM / omega_c`` [s] and [samples].
    max_S, max_T : float
        Peaks of ``|S|`` and ``|T|`` up to the Nyquist frequency [-].
    stable : bool
        All closed-loop poles inside the unit circle.
    note : str
        Where the linearisation does not hold ("" where it does).
    """

    regime: str
    dt: float
    delay_samples: int
    gain_margin: float
    gain_margin_db: float
    phase_margin_deg: float
    crossover_rad_s: float
    delay_margin_s: float
    delay_margin_samples: float
    max_S: float
    max_T: float
    stable: bool
    note: str

    @property
    def _title(self) -> str:  # type: ignore[override]
        return f"Sampled loop around the simulated plant, {self.regime} (what runs on the axis)"

    @property
    def system(self) -> str:
        """Which system the numbers are about, in words."""
        k = "k = 0, gross sliding" if self.regime == "sliding" else "k = kappa, pre-sliding at rest (a bound)"
        return (f"sampled loop: ZOH of the simulated plant K / (m s^2 + sigma s + k) ({k}), discrete PID with its "
                f"derivative filter, the drive's delay {self.delay_samples} samples, dt = {self.dt:g} s")

    def to_dict(self) -> dict:
        """JSON-ready values (infinite ones are ``None``)."""
        def fin(x):
            return None if not math.isfinite(x) else x

        return {"system": self.system, "regime": self.regime, "delay_samples": self.delay_samples,
                "gain_margin_db": fin(self.gain_margin_db), "phase_margin_deg": self.phase_margin_deg,
                "crossover_rad_s": fin(self.crossover_rad_s), "delay_margin_s": fin(self.delay_margin_s),
                "delay_margin_samples": fin(self.delay_margin_samples), "max_S": self.max_S, "max_T": self.max_T,
                "stable": self.stable, "note": self.note}

    def _rows(self):
        return [
            ("system", self.system + ("" if self.stable else " (UNSTABLE)")),
            ("gain margin [dB]", self.gain_margin_db),
            ("phase margin [deg]", self.phase_margin_deg),
            ("gain crossover [rad/s]", self.crossover_rad_s),
            ("delay margin [s] ([samples])", f"{self.delay_margin_s:.4g} ({self.delay_margin_samples:.3g} samples)"),
            ("max |S| [-]", self.max_S),
            ("max |T| [-]", self.max_T),
        ] + ([("note", self.note)] if self.note else [])


def plant_loop(cfg: Config, *, regime: str = "sliding", delay_samples: int | None = None) -> PlantLoop:
    """The sampled loop of the config's PID around the simulated plant's linearisation (module docstring).

    Parameters
    ----------
    cfg : Config
        The design.
    regime : str
        One of :data:`REGIMES`.
    delay_samples : int, optional
        The drive's delay [samples] (>= 0); default ``cfg.hardware.delay_samples`` (the PID stays the one the
        config carries for its own delay).

    Returns
    -------
    PlantLoop

    Raises
    ------
    TypeError
        ``cfg`` is not a Config.
    ValueError
        An unknown regime, or ``delay_samples`` not an integer in [0, 10000].

    Examples
    --------
    >>> import obsdesign as od
    >>> plant_loop(od.load_preset("vcm"), regime="moving")
    Traceback (most recent call last):
    ...
    ValueError: regime: expected one of 'sliding', 'rest', found 'moving'
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    regime = Choice(REGIMES).check("regime", regime)
    d = drive_delay(cfg, delay_samples)
    dt = cfg.observer.dt
    kp, ki, kd, tau_d = sampled_pid_gains(cfg)
    num, den = _plant_coefficients(cfg, regime)
    args = (kp, ki, kd, tau_d, dt, d, tuple(num), tuple(den))
    # python-control's numbers kept on disk like the sampled loop's (a warm `loop` imports no python-control);
    # no cheap NumPy re-verification of a ZOH of this plant: a kept entry rests on the memo's signature
    gm, pm, wgc, dm, max_S, max_T, stable = memo("plant_loop", args, lambda: _numbers(*args), valid=_valid)
    notes = []
    pf = cfg.plant_friction
    if pf is not None and pf.model != "paper":
        notes.append(f"plant_friction {pf.model}: its bristle dynamics are not in this linearisation")
    if regime == "rest":
        notes.append("pre-sliding is hysteretic: k = kappa is a bound, not what a small-amplitude test measures")
    return PlantLoop(regime=regime, dt=dt, delay_samples=d, gain_margin=gm,
                     gain_margin_db=20.0 * math.log10(gm) if math.isfinite(gm) else math.inf,
                     phase_margin_deg=pm, crossover_rad_s=wgc, delay_margin_s=dm, delay_margin_samples=dm / dt,
                     max_S=max_S, max_T=max_T, stable=stable, note="; ".join(notes))


def _valid(value) -> bool:
    """The schema of a kept :func:`_numbers`: six floats and a bool."""
    return (isinstance(value, list) and len(value) == 7 and all(isinstance(x, float) for x in value[:6])
            and isinstance(value[6], bool))


def _numbers(kp, ki, kd, tau_d, dt, d, num, den) -> list:
    """python-control's margins, peaks and stability of ``C(z) H_zoh(z) z^-d`` (what :func:`plant_loop` keeps)."""
    import control as ct
    import numpy as np

    sys = closed_loop(discrete_pid(kp=kp, ki=ki, kd=kd, tau_d=tau_d, dt=dt),
                      ct.c2d(ct.tf(list(num), list(den)), dt, "zoh"), d)
    L, S, T = sys["L"], sys["S"], sys["T"]
    gm, pm, wgc, _, dm = loop_margins(L)
    lnum, lden = (np.atleast_1d(np.squeeze(x)) for x in ct.tfdata(L))
    stable = bool(max(abs(np.roots(np.polyadd(lden, lnum)))) < 1.0)
    w_low = (wgc if math.isfinite(wgc) and wgc > 0 else 1.0) * 1e-3
    max_S, _ = discrete_peak(S, dt, w_low) if stable else (math.inf, math.nan)
    max_T, _ = discrete_peak(T, dt, w_low) if stable else (math.inf, math.nan)
    return [float(gm), float(pm), float(wgc), float(dm), float(max_S), float(max_T), stable]


def plant_loops(cfg: Config, *, delay_samples: int | None = None) -> dict[str, PlantLoop]:
    """:func:`plant_loop` of every regime of :data:`REGIMES`.

    Parameters
    ----------
    cfg : Config
        The design.
    delay_samples : int, optional
        The drive's delay [samples]; default ``cfg.hardware.delay_samples``.

    Returns
    -------
    dict of str to PlantLoop

    Examples
    --------
    >>> import obsdesign as od
    >>> sorted(plant_loops(od.load_preset("vcm")))
    ['rest', 'sliding']
    """
    return {regime: plant_loop(cfg, regime=regime, delay_samples=delay_samples) for regime in REGIMES}


@dataclass(frozen=True, kw_only=True)
class LoopMargins(ResultDisplay):
    """The margins of the sampled loop around the design model beside those around the simulated plant
    (``obsdesign check``).

    Attributes
    ----------
    design : str
        The PID the config carries (``"paper"`` or ``"sampled"``, :func:`~obsdesign.design.pid.resolve_pid`).
    model : SampledLoop
        The sampled loop around the PID's design model eq:linplant.
    simulated : dict of str to PlantLoop
        The sampled loop around the simulated plant, by regime.
    """

    design: str
    model: object
    simulated: dict

    _title = "Loop margins: the PID's design model beside the simulated plant (sampled loop, the drive's delay)"

    def to_dict(self) -> dict:
        """JSON-ready values: ``pid_design``, ``design_model`` and ``simulated_plant`` by regime."""
        return {"pid_design": self.design, "design_model": self.model.to_dict(),  # type: ignore[attr-defined]
                "simulated_plant": {regime: pl.to_dict() for regime, pl in self.simulated.items()}}

    def _rows(self):
        m = self.model
        loops = [("design model", m.stable, m.phase_margin_deg, m.gain_margin_db,  # type: ignore[attr-defined]
                  m.delay_margin_samples, m.max_S, m.max_T)]  # type: ignore[attr-defined]
        loops += [(f"simulated plant, {r}", pl.stable, pl.phase_margin_deg, pl.gain_margin_db, pl.delay_margin_samples,
                   pl.max_S, pl.max_T) for r, pl in self.simulated.items()]
        names = " / ".join(name for name, *_ in loops)

        def row(i: int) -> str:
            return " / ".join(f"{loop[i]:.4g}" for loop in loops)

        rows = [("loops", f"{names} (PID: {self.design}, dt = {m.dt:g} s, "  # type: ignore[attr-defined]
                          f"delay {m.delay_samples} samples)"),  # type: ignore[attr-defined]
                ("phase margin [deg]", row(2)), ("gain margin [dB]", row(3)),
                ("delay margin [samples]", row(4)), ("max |S| [-]", row(5)), ("max |T| [-]", row(6))]
        unstable = [name for name, stable, *_ in loops if not stable]
        if unstable:
            rows.append(("UNSTABLE", ", ".join(unstable)))
        rows += [(f"note ({r})", pl.note) for r, pl in self.simulated.items() if pl.note]
        return rows


def loop_margins_of(cfg: Config) -> LoopMargins:
    """:class:`LoopMargins` of the config: its PID's sampled loop around the design model and around the
    simulated plant (both regimes), with the drive's delay.

    Parameters
    ----------
    cfg : Config
        The design.

    Returns
    -------
    LoopMargins

    Examples
    --------
    >>> import obsdesign as od
    >>> lm = loop_margins_of(od.load_preset("vcm"))
    >>> round(lm.model.phase_margin_deg, 2), round(lm.simulated["sliding"].phase_margin_deg, 2)
    (60.02, 44.07)
    """
    from .pid_sampled import resolve_pid
    from .sampled_loop import sampled_loop

    return LoopMargins(design=resolve_pid(cfg).design, model=sampled_loop(cfg), simulated=plant_loops(cfg))
