"""The bands a simulated run is judged by, scaled to the axis: settling band and runaway bounds.

A settling band says when the axis is "there". A fixed band means nothing across axes (2 urad is a
third of a count of a 2^20 counts/rev encoder, and 2 um is a hundredth of a count of a 0.2 mm
scale), so the default follows what the sensor can tell apart:

``band = max(2 q, 3 eta)``

* ``q`` the encoder resolution ``[sensor] quantization``: with integral action and friction the
  loop rests, or hunts by one count, anywhere in the count of the target; two counts hold that;
* ``eta`` the noise RMS ``[sensor] noise_rms``: the loop passes the measurement noise to the
  position (through ``T``, at most about its RMS within the loop's bandwidth); three times its RMS
  holds a Gaussian sample 99.7 % of the time;
* an ideal sensor (``q = eta = 0``) resolves everything: ``band = 1e-3 x`` the reference's span
  (0.1 % of the move, the tight end of the textbook 2 % / 5 % bands).

A step has *settled* when the error stays within the band from some sample to the end of its hold
and for at least the last :data:`SETTLE_DWELL` of the hold (the window of the steady-state error):
a response that only passes through the band near the end of the hold "did not settle".

A run has *run away* (``diverged``, ``divergence = 'runaway'``) when, with every state still within the
simulator's absolute bounds, ``|e|`` exceeds :data:`RUNAWAY_FACTOR` times the reference's span plus the
band (ten times farther from the target than the whole task moves), and (``'estimate'``) when the
filtered friction estimate exceeds :data:`RUNAWAY_FACTOR` times the largest force that can act on the
plant, ``K u_max + |G| + Cf``: no friction of the plant can balance that.

Examples
--------
>>> import obsdesign as od
>>> b = settle_band(od.load_preset("vcm"), span=1e-3)          # 1 um encoder, no noise
>>> b.value, b.rule
(2e-06, '2 x encoder resolution 1e-06 m')
>>> settle_band(od.load_preset("table1"), span=1e-3).rule       # 1 um noise RMS, no encoder
'3 x noise RMS 1e-06 m'
>>> settle_band(od.load_preset("table1").override(noise_rms=0.0), span=1e-3).rule
'0.1 % of the reference span 0.001 m (ideal sensor)'
>>> round(force_bound(od.load_preset("table1")), 6)             # 10 (K u_max + |G| + Cf)
331.5
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["SettleBand", "settle_band", "force_bound", "error_bound", "RESOLUTION_COUNTS", "NOISE_SIGMAS",
           "IDEAL_SPAN_FRACTION", "RUNAWAY_FACTOR", "SETTLE_DWELL"]

#: Encoder counts in the default settling band.
RESOLUTION_COUNTS = 2.0
#: Noise RMS multiples in the default settling band.
NOISE_SIGMAS = 3.0
#: Fraction of the reference's span that is the band of an ideal sensor.
IDEAL_SPAN_FRACTION = 1e-3
#: How many times the task's scale (span + band; the force that can act) a run must exceed to have run away.
RUNAWAY_FACTOR = 10.0
#: Fraction of a hold at its end that a settled response must spend within the band.
SETTLE_DWELL = 0.1


@dataclass(frozen=True)
class SettleBand:
    """A settling band and the rule that gave it.

    Attributes
    ----------
    value : float
        Half-width of the band [m] (rad on a rotary axis).
    rule : str
        Where it comes from, with the unit of the axis (``'2 x encoder resolution 1e-06 m'``, ``'given'``).
    """

    value: float
    rule: str


def settle_band(cfg, *, span: float, given: float | None = None) -> SettleBand:
    """The settling band of a run of ``cfg`` whose reference moves over ``span`` (module docstring).

    Parameters
    ----------
    cfg : Config
        The design (its ``[sensor]`` and its axis's units).
    span : float
        Peak-to-peak of the reference [m] (rad), >= 0.
    given : float, optional
        A band the user chose [m] (> 0): returned with the rule ``'given'``.

    Returns
    -------
    SettleBand

    Raises
    ------
    ValueError
        An ideal sensor (no quantization, no noise) and a reference that does not move: nothing sets
        a scale, give the band.

    Examples
    --------
    >>> import dataclasses, obsdesign as od
    >>> from obsdesign.axis import AxisSpec
    >>> rot = dataclasses.replace(od.load_preset("vcm").override(quantization=2 * math.pi / 2**20),
    ...                           axis=AxisSpec(kind="rotary", input="A"))
    >>> b = settle_band(rot, span=1e-3)
    >>> round(b.value * 1e6, 3), b.rule                              # 2 counts of a 2^20 counts/rev encoder
    (11.984, '2 x encoder resolution 5.992e-06 rad')
    >>> settle_band(rot, span=1e-3, given=2e-6)
    SettleBand(value=2e-06, rule='given')
    """
    if given is not None:
        return SettleBand(float(given), "given")
    unit = cfg.units.unit("m")
    q, eta = cfg.sensor.quantization, cfg.sensor.noise_rms
    by_q, by_noise = RESOLUTION_COUNTS * q, NOISE_SIGMAS * eta
    if by_q > 0.0 or by_noise > 0.0:
        if by_q >= by_noise:
            return SettleBand(by_q, f"{RESOLUTION_COUNTS:g} x encoder resolution {q:.4g} {unit}")
        return SettleBand(by_noise, f"{NOISE_SIGMAS:g} x noise RMS {eta:.4g} {unit}")
    if not (math.isfinite(span) and span > 0.0):
        raise ValueError("settle_tol: no default band for an ideal sensor (quantization 0, noise_rms 0) and a "
                         f"reference that does not move (span {span!r} {unit}); give settle_tol > 0 [{unit}]")
    return SettleBand(IDEAL_SPAN_FRACTION * span,
                      f"{100 * IDEAL_SPAN_FRACTION:g} % of the reference span {span:.4g} {unit} (ideal sensor)")


def error_bound(span: float, band: float) -> float:
    """The largest ``|e|`` [m] of a run that has not run away: :data:`RUNAWAY_FACTOR` x (span + band).

    Parameters
    ----------
    span : float
        Peak-to-peak of the reference [m].
    band : float
        The settling band [m].

    Examples
    --------
    >>> round(error_bound(1e-3, 2e-6), 9)
    0.01002
    """
    return RUNAWAY_FACTOR * (span + band)


def force_bound(cfg) -> float:
    """The largest ``|f_hat_filtered|`` [N] of a run that has not run away:
    :data:`RUNAWAY_FACTOR` x (``K u_max + |G| + Cf``) of the simulated plant's config.

    Parameters
    ----------
    cfg : Config
        The simulated plant's config (the design's, or the plant's own under model mismatch).

    Examples
    --------
    >>> import obsdesign as od
    >>> pl = od.load_preset("vcm").plant
    >>> force_bound(od.load_preset("vcm")) == 10 * (pl.K * pl.u_max + abs(pl.G) + 0.35)
    True
    """
    pl = cfg.plant
    return RUNAWAY_FACTOR * (abs(pl.K) * pl.u_max + abs(pl.G) + cfg.friction.Cf)
