"""The default low-pass cut-off of :func:`obsdesign.data.identify`, read from the record itself.

Rule: the position's spectrum of a moving axis falls steeply with frequency from the lowest
frequencies on (it is the integral of the velocity: at least ``f^-2``), its
noise (sensor noise, encoder steps, the noise a loop feeds back) is flat or nearly so. The
*noise crossing* ``f_n`` is the lowest frequency from which the spectrum has stopped falling for an octave:
the median power spectral density over the quarter-octave-spaced band ``[f/sqrt 2, f sqrt 2]`` is less
than :data:`FALL_RATIO` times that of the band one octave above, there and in the next
:data:`FLAT_BANDS` - 1 bands, and by less than :data:`FLAT_RATIO` on average over them (white noise: 1). The octave keeps a motion whose spectrum falls slowly from being read as its
noise: a closed loop's answer to friction's sharp edges (a Stribeck drop, 4 kHz, the position falling by
1.85 in the octave above 26 Hz but by 2 to 60 in the octaves above 31 to 150 Hz) had put the crossing at
26 Hz and the cut-off at 52 Hz, and biased the inertia by +0.07 % and the Stribeck level by -2.6 % (400 Hz
on the same axis: -0.003 % and -0.3 %). A noise floor of the floor's own height is not required: on the
VCM axis in closed loop the measurement noise is a plateau 240 times above the encoder's floor from 46 to
440 Hz (band-limited), and it is the noise. The cut-off is one octave above the
crossing, ``2 f_n`` (the 4th-order Butterworth passes the motion below ``f_n`` with a gain
above 0.996 and attenuates the noise beyond ``2 f_n`` by 24 dB per octave), and never above a
tenth of the sampling rate (the EMPS benchmark's 100 Hz at 1 kHz, the previous fixed default). The
lowest band centre is four frequency bins, at least ``16 / duration``, so a cut-off is at least
``32 / duration``, which :func:`obsdesign.data.identify`'s border and rows (``30 fs / filter_hz``
samples) always fit into. A spectrum that never stops falling (a record without noise) keeps a tenth of the
sampling rate. The rule assumes the motion's spectrum has no flat part of its own: a position
held at one point (a stationary, regulated record) would read its own plateau as the floor.

The spectrum is Welch's (Hann segments, half overlap, at most 0.5 Hz resolution, at least 7
segments) of the first difference of the position divided by ``|2 sin(pi f dt)|^2``: the
position's spectrum without the leakage of its large low-frequency content into the high bands.

Examples
--------
>>> import numpy as np
>>> dt = 1e-3
>>> t = np.arange(30_000) * dt
>>> x = 0.01 * np.sin(2 * np.pi * 0.7 * t) + 0.004 * np.sin(2 * np.pi * 3.1 * t)
>>> cut = noise_cutoff(x, dt)
>>> cut.filter_hz, cut.crossing_hz                          # no noise: the fixed tenth
(100.0, None)
>>> noisy = x + np.random.default_rng(0).normal(0.0, 1e-5, t.size)
>>> cut = noise_cutoff(noisy, dt)
>>> bool(cut.crossing_hz < 100), cut.filter_hz == 2 * cut.crossing_hz
(True, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["CutOff", "noise_cutoff", "choose_filter", "position_psd", "FALL_RATIO", "MAX_FRACTION", "OCTAVES_ABOVE",
           "force_bandwidth", "FORCE_POWER", "FLAT_BANDS", "FLAT_RATIO"]

#: A band whose median PSD is below this many times the next octave's has stopped falling
#: (a motion spectrum falling as ``f^-2`` or steeper drops by 4 or more per octave, white noise by 1).
FALL_RATIO = 2.0
#: The cut-off never exceeds this fraction of the sampling rate (the benchmark's 100 Hz at 1 kHz).
MAX_FRACTION = 0.1
#: The noise is flat: the crossing is the first band from which this many quarter-octave bands (an octave)
#: have all stopped falling, so a motion spectrum that merely falls slowly (by less than FALL_RATIO in one
#: octave, more in the next) is not taken for it.
FLAT_BANDS = 5
#: ... and over that octave the spectrum falls by less than this factor per octave (geometric mean of the
#: bands' ratios; white noise 1, a motion falling as f^-0.5 sqrt(2)).
FLAT_RATIO = 1.3
#: The cut-off lies this many octaves above the noise crossing.
OCTAVES_ABOVE = 1.0
_STEP = 2.0 ** 0.25  # quarter-octave spacing of the band centres


@dataclass(frozen=True, kw_only=True)
class CutOff:
    """The chosen cut-off and why.

    Attributes
    ----------
    filter_hz : float
        The cut-off [Hz].
    crossing_hz : float or None
        Where the position's spectrum meets its noise floor [Hz], ``None`` if it never does.
    rule : str
        The rule as applied, for the identification's output.
    """

    filter_hz: float
    crossing_hz: float | None
    rule: str


def position_psd(position: np.ndarray, sample_time: float) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] (without 0) and the position's power spectral density [m^2/Hz].

    Welch's estimate of the first difference, divided by ``|2 sin(pi f dt)|^2``.

    Parameters
    ----------
    position : ndarray
        Position samples (at least 64).
    sample_time : float
        Sample time [s].
    """
    from scipy import signal

    fs = 1.0 / sample_time
    d = np.diff(np.asarray(position, dtype=float))
    nper = int(min(2.0 ** math.floor(math.log2(d.size / 4)), 2.0 ** math.ceil(math.log2(2.0 * fs))))
    f, p = signal.welch(d, fs=fs, nperseg=nper, detrend="constant")
    return f[1:], p[1:] / (2.0 * np.sin(np.pi * f[1:] * sample_time)) ** 2


def noise_cutoff(position: np.ndarray, sample_time: float) -> CutOff:
    """The default cut-off of :func:`obsdesign.data.identify` for this position record (module docstring).

    Parameters
    ----------
    position : ndarray
        Position samples [m or rad], uniform in time.
    sample_time : float
        Sample time [s].

    Returns
    -------
    CutOff
    """
    fs = 1.0 / sample_time
    high = MAX_FRACTION * fs
    f, p = position_psd(position, sample_time)
    first = 4.0 * f[0]
    count = int(math.floor(math.log(0.25 * fs / first) / math.log(_STEP))) + 1 if 0.25 * fs > first else 0
    crossing = None
    centres = first * _STEP ** np.arange(count)
    ratio = []  # per band: its median PSD over the octave above's (inf where a band is empty)
    for c in centres:
        here = p[(f >= c / math.sqrt(2)) & (f < c * math.sqrt(2))]
        above = p[(f >= c * math.sqrt(2)) & (f < 2 * c * math.sqrt(2))]
        ratio.append(float(np.median(here) / np.median(above)) if here.size and above.size else math.inf)
    for i, c in enumerate(centres):
        octave = ratio[i:i + FLAT_BANDS]
        # flat for an octave (the noise), not a motion that falls slowly: no band falls by FALL_RATIO, and
        # the octave falls by less than FLAT_RATIO on average (white noise: 1)
        if max(octave) < FALL_RATIO and math.exp(np.mean(np.log(octave))) < FLAT_RATIO:
            crossing = float(c)
            break
    tenth = f"a tenth of the sampling rate, {high:g} Hz"
    if crossing is None:
        return CutOff(filter_hz=float(high), crossing_hz=None,
                      rule=f"auto: {tenth} (the position spectrum does not meet a noise floor below {0.25 * fs:g} Hz)")
    wanted = crossing * 2.0**OCTAVES_ABOVE
    chosen = float(min(high, wanted))
    why = "" if chosen == wanted else f", limited to {tenth}"
    return CutOff(filter_hz=chosen, crossing_hz=crossing,
                  rule=f"auto: twice the {crossing:.3g} Hz where the position spectrum meets its noise floor{why}")


#: The fraction of the force's varying power below the force bandwidth that floors the default cut-off.
FORCE_POWER = 0.99


def force_bandwidth(force: np.ndarray, sample_time: float) -> float:
    """The frequency [Hz] below which :data:`FORCE_POWER` of the force's varying power lies (Welch, 0.5 Hz bins).

    The power is counted above the force's noise floor (the median density over the upper half of the band),
    so white current noise does not widen it.

    Parameters
    ----------
    force : ndarray
    sample_time : float
        [s]

    Examples
    --------
    >>> t = np.arange(20_000) * 1e-3
    >>> round(force_bandwidth(np.sin(2 * np.pi * 3.0 * t) + 0.5 * np.sin(2 * np.pi * 40.0 * t), 1e-3))
    40
    """
    from scipy import signal

    fs = 1.0 / sample_time
    f, p = signal.welch(force - np.mean(force), fs=fs, nperseg=min(force.size, int(round(2.0 * fs))))
    p = np.maximum(p - float(np.median(p[f >= 0.25 * fs])), 0.0)  # less the noise floor (the upper half band)
    total = np.cumsum(p)
    if not total[-1] > 0:
        return 0.0
    return float(f[min(int(np.searchsorted(total / total[-1], FORCE_POWER)), f.size - 1)])


def choose_filter(position: np.ndarray, sample_time: float, filter_hz: float | None,
                  decimation: int | None, force: np.ndarray | None = None) -> tuple[float, str, int]:
    """``(filter_hz, filter_rule, decimation)`` of :func:`obsdesign.data.identify`, each given or by its default.

    Parameters
    ----------
    position : ndarray
        Position samples of the fit.
    sample_time : float
        Sample time [s].
    filter_hz : float or None
        A given cut-off in (0, Nyquist) [Hz], or ``None`` for :func:`noise_cutoff`.
    decimation : int or None
        A given factor >= 1, or ``None`` for ``round(fs / filter_hz)``.
    force : ndarray, optional
        The force: the default cut-off is at least an octave above its :func:`force_bandwidth` (at most a
        tenth of the rate). A force with sharp edges (moves that saturate the drive: 11 % of the samples at
        the limit, minimum-jerk moves whose position spectrum met the noise at 2.3 Hz) needs them: with the
        position's 4.6 Hz the filtered sign(v) column no longer matched the force, and the viscous
        coefficient came out 11 times too large and the Coulomb level 0; with 228 Hz both within 5 %. Since the
        octave condition of :func:`noise_cutoff` (:data:`FLAT_BANDS`) the position rule gives 400 Hz on that log
        itself; the force's floor stays for a record whose position noise is high.

    Examples
    --------
    >>> choose_filter(np.zeros(1000), 1e-3, 50.0, None)
    (50.0, 'given', 20)
    >>> choose_filter(np.zeros(1000), 1e-3, 600.0, None)
    Traceback (most recent call last):
    ...
    ValueError: filter_hz: expected a cut-off in (0, 500) Hz (below Nyquist), found 600.0
    """
    from ._idim import check_int

    fs = 1.0 / sample_time
    if filter_hz is None:
        cut = noise_cutoff(position, sample_time)
        filter_hz, rule = cut.filter_hz, cut.rule
        if force is not None:
            band = force_bandwidth(force, sample_time)
            floor = min(2.0 * band, MAX_FRACTION * fs)
            if floor > filter_hz:
                filter_hz, rule = floor, (f"{rule}; raised to an octave above the force's bandwidth {band:.4g} Hz "
                                          f"({100 * FORCE_POWER:g} % of its power; at most a tenth of the rate)")
    elif isinstance(filter_hz, bool) or not isinstance(filter_hz, (int, float)) or not 0 < filter_hz < 0.5 * fs:
        raise ValueError(f"filter_hz: expected a cut-off in (0, {0.5 * fs:g}) Hz (below Nyquist), found {filter_hz!r}")
    else:
        rule = "given"
    q = max(1, round(fs / filter_hz)) if decimation is None else check_int("decimation", decimation, 1)
    return float(filter_hz), rule, q
