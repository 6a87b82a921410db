"""Rules that turn an :class:`~obsdesign.data.Identification` into a complete design config.

The data give the plant (``m``, ``sigma``, ``Cf``, ``offset``), the sample time and the
sensor; everything else follows from documented rules tied to the sample time ``dt``:

=================  ==========================================================================
field              rule
=================  ==========================================================================
axis               the log's units: ``kind`` linear or rotary, ``input`` the logged input's unit
plant.K            the trace's input gain (|gain|; 1.0 when the input was logged in N)
plant.G            the identified offset (a constant load force)
plant.u_max        the actuator limit given (``u_max``, in the input unit); else 1.2 x the largest
                   logged |input| (= max |force| / K), with a caution; 10 if no force
friction.s         identified; else ``1 / presliding_window`` (1e4 1/m at the default 0.1 mm)
friction.kappa     fastest observer pole ``(rho + 1) sqrt(kappa/m) = 0.2 / dt``
observer           variant ``static``, ``rho`` = 4, ``dt`` of the trace,
                   ``omega_co = 2 pi f_s / 10`` (a fifth of the Nyquist frequency)
sensor             ``noise_rms`` and ``quantization`` estimated from the trace,
                   white noise up to the Nyquist frequency
compensation       with the Stribeck term kept: ``ff_stribeck = Fs - Cf`` and ``ff_stribeck_velocity = vs``
                   (the feed-forward's curve; the simulated plant keeps the paper's friction)
hardware           ``delay_samples``: the samples the position is logged after the input it answers to,
                   found from the log or given (:mod:`obsdesign.data.timing`): the loop's delay
pid                ``tau = m / sigma`` (so ``H = phi / (s (tau s + 1))`` with ``phi = K tau / m`` is
                   ``K / (m s^2 + sigma s)``), phase margin 60 deg, ``max_S`` placing the
                   crossover ``omega_c = k phi / sin(Phi)`` at a tenth of the Nyquist frequency
=================  ==========================================================================
"""

from __future__ import annotations

import dataclasses
import math

from ..compensation import CompensationSpec
from ..params import Config, FrictionParams, ObserverSpec, PIDSpec, PlantParams, SensorSpec
from ..provenance import WRITTEN_AS

__all__ = ["config_from", "design_rules", "PHASE_MARGIN_DEG", "FASTEST_POLE_DT", "U_MAX_MARGIN", "DELAY_KEY",
           "with_drive_delay"]

#: Phase margin [deg] of the PID rule.
PHASE_MARGIN_DEG = 60.0
#: Fastest observer pole times dt.
FASTEST_POLE_DT = 0.2
#: Margin on the largest logged input for the actuator limit.
U_MAX_MARGIN = 1.2
#: Where a config keeps the drive's delay [samples] (the one place, with :func:`with_drive_delay`).
DELAY_KEY = "hardware.delay_samples"


def with_drive_delay(cfg: Config, delay: int) -> Config:
    """``cfg`` with the drive's delay [samples] at :data:`DELAY_KEY`, the one place a config keeps it.

    Parameters
    ----------
    cfg : Config
    delay : int
        Samples from the input to the measured position (the loop's delay).

    Examples
    --------
    >>> from obsdesign import load_preset
    >>> with_drive_delay(load_preset("vcm"), 2).hardware.delay_samples
    2
    """
    return dataclasses.replace(cfg, hardware=dataclasses.replace(cfg.hardware, delay_samples=int(delay)))


def _positive(name: str, value: float, why: str, ident=None) -> float:
    if not (math.isfinite(value) and value > 0):
        side = getattr(ident, "at_bound", {}).get(name)
        hint = (f"; it is at its {side} bound: the record does not resolve it. Fix it (--fix {name}=VALUE, "
                f"identify(..., fix={{'{name}': VALUE}})), or record an excitation with faster moves"
                if side else "")
        raise ValueError(f"{name}: expected an identified value > 0 for a design, found {value!r} ({why}){hint}")
    return value


def config_from(ident, *, name: str = "identified", K: float | None = None, u_max: float | None = None,
                rho: float = 4.0, presliding_window: float = 1e-4) -> Config:
    """A complete :class:`~obsdesign.Config` from an identification (rules in the module docstring).

    Parameters
    ----------
    ident : Identification
    name : str
        Name of the design.
    K : float, optional
        Actuator gain [N/V]; default the trace's ``|input_gain|``.
    u_max : float, optional
        Actuator limit in the logged input's unit (V, A, N); default 1.2 max|force| / K (the log's
        peak, named as such in the config's sources), or 10 for an all-zero force.
    rho : float
        Observer gain parameter (> 1). With 4, the gross-sliding poles are
        ``-(rho -+ 1) sqrt(kappa/m)``: the dominant one is 3/5 of the fastest (0.12/dt).
    presliding_window : float
        Pre-sliding distance ``1/s`` [m] assumed when ``s`` was not identified.

    Returns
    -------
    Config

    Raises
    ------
    ValueError
        If ``m``, ``sigma`` or ``Cf`` was identified non-positive (no physical design; a value at its
        bound is named as such), or ``u_max`` is not a number > 0.

    Notes
    -----
    The config's ``[sources]`` table records each rule of :func:`design_rules` with its unit (so the
    input unit and the axis kind travel with the file).

    Examples
    --------
    >>> from obsdesign.data import Identification
    >>> ident = Identification(model="coulomb-viscous", m=2.0, sigma=20.0, Cf=1.0, offset=3.0, m_std=0.0,
    ...                        sigma_std=0.0, Cf_std=0.0, offset_std=0.0, nrmse_percent=1.0,
    ...                        condition_number=2.0, samples=1000, sample_time=1e-3, force_peak=5.0)
    >>> cfg = config_from(ident)
    >>> cfg.plant.u_max, cfg.friction.kappa, cfg.friction.s, cfg.pid.tau
    (6.0, 3200.0, 10000.0, 0.1)
    """
    return _build(ident, name=name, K=K, u_max=u_max, rho=rho, presliding_window=presliding_window)[0]


def design_rules(ident, *, K: float | None = None, u_max: float | None = None, rho: float = 4.0,
                 presliding_window: float = 1e-4) -> list[tuple[str, float, str, str]]:
    """Every field :func:`config_from` sets: ``(key, value, unit, rule)`` rows, in the config's order.

    The units are those of the identified axis (a rotary axis in kg m^2, N m, rad; the input unit named).

    Parameters
    ----------
    ident : Identification
    K, u_max, rho, presliding_window :
        As for :func:`config_from`.

    Examples
    --------
    >>> from obsdesign.data import Identification
    >>> ident = Identification(model="coulomb-viscous", m=2.0, sigma=20.0, Cf=1.0, offset=3.0, m_std=0.0,
    ...                        sigma_std=0.0, Cf_std=0.0, offset_std=0.0, nrmse_percent=1.0,
    ...                        condition_number=2.0, samples=1000, sample_time=1e-3, force_peak=5.0)
    >>> [row[:3] for row in design_rules(ident, u_max=8.0)][:4]
    [('plant.m', 2.0, 'kg'), ('plant.K', 1.0, 'N/N'), ('plant.G', 3.0, 'N'), ('plant.u_max', 8.0, 'N')]
    """
    return _build(ident, name="identified", K=K, u_max=u_max, rho=rho, presliding_window=presliding_window)[1]


def _build(ident, *, name, K, u_max, rho, presliding_window):
    from .units import Units

    units = getattr(ident, "units", None) or Units()
    unit_in = units.input_unit(ident.input_gain)
    F, L, M = units.force_unit, units.length_unit, units.mass_unit
    dt = ident.sample_time
    delay = int(getattr(ident, "delay_samples", 0))
    m = _positive("m", ident.m, "the mass must be positive", ident)
    sigma = _positive("sigma", ident.sigma, "the viscous coefficient must be positive", ident)
    Cf = _positive("Cf", ident.Cf, "the Coulomb level must be positive", ident)
    gain = abs(ident.input_gain) if K is None else K
    if u_max is None:
        u_max_rule = (f"{U_MAX_MARGIN:g} x the log's peak |input| {ident.force_peak / gain:.4g} {unit_in}: NOT the "
                      "actuator's limit (give it: --u-max, to_config(u_max=...)); the controller saturates early "
                      "if the actuator can do more" if ident.force_peak > 0 else "no force in the log: 10")
        u_max = U_MAX_MARGIN * ident.force_peak / gain if ident.force_peak > 0 else 10.0
    else:
        if isinstance(u_max, bool) or not isinstance(u_max, (int, float)) or not (math.isfinite(u_max) and u_max > 0):
            raise ValueError(f"u_max: expected the actuator limit > 0 [{unit_in}], found {u_max!r}")
        peak = ident.force_peak / gain
        if peak > u_max * (1 + 1e-9):  # the log went beyond the limit: a wrong limit, unit or gain
            raise ValueError(f"u_max: expected at least the log's peak |input| {peak:.6g} {unit_in} (the actuator "
                             f"reached it), found {u_max!r}")
        u_max_rule = "the actuator limit given"
    if isinstance(rho, bool) or not isinstance(rho, (int, float)) or not rho > 1:
        raise ValueError(f"rho: expected a finite number > 1 (stable observer), found {rho!r}")
    s = ident.s if ident.s is not None else 1.0 / presliding_window
    kappa = m * (FASTEST_POLE_DT / (dt * (rho + 1.0))) ** 2
    nyquist = 0.5 / dt
    omega_c = 2.0 * math.pi * nyquist / 10.0
    tau = m / sigma
    phi = gain * tau / m
    max_S = phi / (omega_c * math.sin(math.radians(PHASE_MARGIN_DEG)))
    omega_co = 2.0 * math.pi * nyquist / 5.0
    src = f"identified from {ident.source or 'a record'}"
    axis = f"{units.axis} axis"
    per_gain = K is None and units.gain_unknown(ident.input_gain)  # m/K, Cf/K: see Units.gain_note
    per = f"; per {F}/{unit_in} of an unknown {units.force_word} constant K (m/K, Cf/K), not physical" if per_gain else ""
    rules = [
        ("plant.m", m, M, f"{src} ({'inertia of a rotary' if units.rotary else 'mass of a linear'} axis{per})"),
        ("plant.K", gain, f"{F}/{unit_in}", f"NOT measured: 1 (no input gain given), so every {units.force_word} "
         f"here is in {unit_in} (m/K, sigma/K, Cf/K, G/K): the loop and the compensation in {unit_in} are right, the "
         f"{F} and {M} values are not physical; input logged in {unit_in}, {axis}" if per_gain else
         f"the input gain ({'given' if K is not None else '|input_gain|'}); input logged in {unit_in}, {axis}"),
        ("plant.G", ident.offset, F, f"{src}: the offset, a constant load"),
        ("plant.u_max", u_max, unit_in, u_max_rule),
        ("friction.Cf", Cf, F, src + (" (mean of the two directions)" if ident.model == "asymmetric" else "")),
        ("friction.sigma", sigma, f"{F} s/{L}", src + (" (mean of the two directions)"
                                                     if ident.model == "asymmetric" else "")),
        ("friction.s", s, f"1/{L}", f"{src} (pre-sliding)" if ident.s is not None
         else f"not resolved by the record: 1 / presliding_window = 1 / {presliding_window:g} {L}"),
        ("friction.kappa", kappa, f"{F}/{L}", f"fastest observer pole (rho + 1) sqrt(kappa/m) = "
         f"{FASTEST_POLE_DT:g} / dt"),
        ("sensor.noise_rms", ident.noise_rms, L, ("RMS of the position's white noise (the position minus its low-pass, over the share of a white "
                                                     "noise above the cut-off), less q^2/12")),
        ("sensor.noise_bandwidth", nyquist, "Hz", "white up to the Nyquist frequency"),
        ("sensor.quantization", ident.quantization, L, "smallest position increment, if all are multiples of it"),
        ("observer.rho", float(rho), "", "gross-sliding poles -(rho -+ 1) sqrt(kappa/m)"),
        ("observer.omega_co", omega_co, "rad/s", "2 pi f_s / 10 (a fifth of the Nyquist frequency)"),
        ("observer.variant", "static", "", "viscous friction in the model (the paper's section 4)"),
        ("observer.dt", dt, "s", "the record's sample time"),
        ("pid.tau", tau, "s", "m / sigma"),
        ("pid.phase_margin_deg", PHASE_MARGIN_DEG, "deg", "the PID rule"),
        ("pid.max_S", max_S, f"{L}/{unit_in}", "crossover k phi / sin(Phi) at a tenth of the Nyquist frequency"),
        (DELAY_KEY, delay, "samples", f"the log's delay from input to position ({_delay_rule(ident)})"),
    ]
    compensation = CompensationSpec()
    Fs, vs = getattr(ident, "Fs", None), getattr(ident, "vs", None)
    if getattr(ident, "stribeck", False) and Fs is not None and vs is not None:
        drop = max(Fs - Cf, 0.0)
        compensation = CompensationSpec(ff_stribeck=drop, ff_stribeck_velocity=vs)
        ivals = getattr(ident, "intervals", {})

        def within(key: str) -> str:
            return f" (95 % interval of {key} {ivals[key][0]:.4g} to {ivals[key][1]:.4g})" if key in ivals else ""

        rules += [("compensation.ff_stribeck", drop, F, f"{src}: Fs - Cf, the Stribeck drop of the feed-forward"
                   + within("Fs")),
                  ("compensation.ff_stribeck_velocity", vs, f"{L}/s", f"{src}: the Stribeck speed vs" + within("vs"))]
        # the simulated plant keeps the paper's friction (no Stribeck term): a LuGre plant from these levels with
        # default bristle constants integrated to NaN on a rotary axis of 2.5e-3 kg m^2
    cfg = Config(
        name=name,
        plant=PlantParams(m=m, K=gain, G=ident.offset, u_max=u_max),
        friction=FrictionParams(Cf=Cf, sigma=sigma, s=s, kappa=kappa),
        sensor=SensorSpec(noise_rms=ident.noise_rms, noise_bandwidth=nyquist, quantization=ident.quantization),
        observer=ObserverSpec(rho=float(rho), omega_co=omega_co, variant="static", dt=dt),
        pid=PIDSpec(max_S=max_S, phase_margin_deg=PHASE_MARGIN_DEG, tau=tau),
        sources={key: (f"{rule} [{unit}]" if unit else rule) + f"{WRITTEN_AS}{value!r}"
                 for key, value, unit, rule in rules},
        axis=units.axis_spec(ident.input_gain),
        compensation=compensation,
    )
    return with_drive_delay(cfg, delay), rules


def _delay_rule(ident) -> str:
    note = getattr(ident, "timing_note", "")
    if not note:
        return "not examined"
    return "given" if note.endswith("(given)") or "delay given" in note else "found from the record"

