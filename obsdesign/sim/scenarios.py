"""Scenarios: reference trajectories, open-loop inputs and band-limited noise.

=============  ===========  ============================================================
scenario       loop         signal
=============  ===========  ============================================================
excitation     open loop    band-limited random force, RMS ``input_force`` (default 1 N),
                            bandwidth ``excitation_bandwidth`` (default 5 Hz): the paper's
                            numerical illustration
constant       open loop    constant force ``input_force`` (default 1 N)
positioning    closed loop  steps ``0 -> step_size`` at ``step_up``, back to 0 at
                            ``step_down`` (defaults 1 mm, 0.5 s, 3.0 s, end 6.0 s),
                            like Fig. expref(a)
tracking       closed loop  linear up-chirp 0.01 -> 3 Hz over the run (default 60 s),
                            amplitude so that the peak reference velocity is 0.1 m/s,
                            like Fig. expref(b)
=============  ===========  ============================================================

Examples
--------
>>> sc = build_scenario("positioning", dt=1e-3)
>>> sc.duration, sc.steps, sc.holds
(6.0, (0.5, 3.0), ((0.5, 3.0), (3.0, 6.0)))
>>> float(sc.x_ref[1000])  # 1 mm after the first step
0.001
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..params import _Range

__all__ = ["SCENARIOS", "Scenario", "build_scenario", "band_limited_noise", "chirp_frequency", "CHIRP_BANDS",
           "CHIRP_BAND_LABELS"]

SCENARIOS = ("excitation", "constant", "positioning", "tracking")
OPEN_LOOP = ("excitation", "constant")
DEFAULT_DURATION = {"excitation": 10.0, "constant": 5.0, "positioning": 6.0, "tracking": 60.0}
EXCITATION_BANDWIDTH = 5.0  # Hz
CHIRP_F0, CHIRP_F1, CHIRP_PEAK_VELOCITY = 0.01, 3.0, 0.1
#: Edges [Hz] of the chirp-frequency bands in which tracking errors are reported.
CHIRP_BANDS = (0.01, 0.1, 0.3, 1.0, 3.0)
#: ``(label, low, high)`` of each band, e.g. ``("0.01-0.1 Hz", 0.01, 0.1)``.
CHIRP_BAND_LABELS = tuple((f"{lo:g}-{hi:g} Hz", lo, hi) for lo, hi in zip(CHIRP_BANDS[:-1], CHIRP_BANDS[1:]))

_POS = _Range(low=0.0)
_NONNEG = _Range(low=0.0, low_inclusive=True)
_FINITE = _Range()


@dataclass(frozen=True)
class Scenario:
    """Sampled signals of one scenario.

    Attributes
    ----------
    name : str
    dt, duration : float
        Sample time and length [s].
    x_ref : ndarray
        Reference displacement [m] per sample (zeros for open loop).
    u_open : ndarray
        Open-loop force [N] per sample (zeros for closed loop).
    steps : tuple of float
        Step times [s] (positioning).
    holds : tuple of (float, float)
        Hold intervals [s] after each step (positioning).
    """

    name: str
    dt: float
    duration: float
    x_ref: np.ndarray = field(repr=False)
    u_open: np.ndarray = field(repr=False)
    steps: tuple = ()
    holds: tuple = ()

    @property
    def open_loop(self) -> bool:
        return self.name in OPEN_LOOP


def band_limited_noise(n: int, dt: float, rms: float, bandwidth: float, seed) -> np.ndarray:
    """White Gaussian noise limited to ``[0, bandwidth]`` Hz by an ideal filter (FFT mask).

    The result has expected RMS ``rms`` (one-sided flat spectrum up to ``bandwidth``,
    or up to the Nyquist frequency if that is lower).

    Examples
    --------
    >>> x = band_limited_noise(200_000, 1e-4, 2.0, 50.0, seed=1)
    >>> round(float(np.sqrt(np.mean(x * x))), 1)
    2.0
    """
    if rms == 0.0:
        return np.zeros(n)
    rng = np.random.default_rng(seed)
    white = rng.standard_normal(n)
    nyquist = 0.5 / dt
    if bandwidth >= nyquist:
        return rms * white
    spec = np.fft.rfft(white)
    spec[np.fft.rfftfreq(n, dt) > bandwidth] = 0.0
    return np.fft.irfft(spec, n) * (rms / math.sqrt(bandwidth / nyquist))


def chirp_frequency(t: np.ndarray, duration: float) -> np.ndarray:
    """Instantaneous frequency [Hz] of the tracking chirp."""
    return CHIRP_F0 + (CHIRP_F1 - CHIRP_F0) * t / duration


def build_scenario(name: str, *, dt: float, duration: float | None = None, input_force: float | None = None,
                   step_size: float | None = None, step_up: float | None = None, step_down: float | None = None,
                   excitation_bandwidth: float | None = None, seed=0) -> Scenario:
    """Sample the signals of a scenario.

    Raises
    ------
    ValueError
        Unknown name, or inconsistent step times.
    """
    if not isinstance(name, str) or name not in SCENARIOS:
        raise ValueError(f"scenario: expected one of {', '.join(SCENARIOS)}, found {name!r}")
    duration = DEFAULT_DURATION[name] if duration is None else _POS.check("duration", duration)
    n = int(round(duration / dt))
    if n < 2:
        raise ValueError(f"duration: expected at least 2 samples of dt = {dt:g} s, found {duration!r} s")
    t = np.arange(n) * dt
    zeros = np.zeros(n)
    if name == "constant":
        force = 1.0 if input_force is None else _FINITE.check("input_force", input_force)
        return Scenario(name, dt, duration, zeros, np.full(n, force))
    if name == "excitation":
        force = 1.0 if input_force is None else _NONNEG.check("input_force", input_force)
        band = EXCITATION_BANDWIDTH if excitation_bandwidth is None else _POS.check("excitation_bandwidth", excitation_bandwidth)
        return Scenario(name, dt, duration, zeros, band_limited_noise(n, dt, force, band, seed))
    if name == "positioning":
        size = 1e-3 if step_size is None else _FINITE.check("step_size", step_size)
        up = 0.5 if step_up is None else _NONNEG.check("step_up", step_up)
        down = 3.0 if step_down is None else _NONNEG.check("step_down", step_down)
        if not up < down < duration:
            raise ValueError(
                f"step_down: expected step_up < step_down < duration, found {up:g} < {down:g} < {duration:g} s"
            )
        x_ref = np.where((t >= up - 0.5 * dt) & (t < down - 0.5 * dt), size, 0.0)
        return Scenario(name, dt, duration, x_ref, zeros, (up, down), ((up, down), (down, duration)))
    amplitude = CHIRP_PEAK_VELOCITY / (2 * math.pi * CHIRP_F1)
    phase = 2 * math.pi * (CHIRP_F0 * t + 0.5 * (CHIRP_F1 - CHIRP_F0) * t * t / duration)
    return Scenario(name, dt, duration, amplitude * np.sin(phase), zeros)
