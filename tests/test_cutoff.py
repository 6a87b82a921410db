"""The default cut-off of identify from the record's own spectrum (obsdesign.data.cutoff)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, signal

from obsdesign.data.cutoff import noise_cutoff, position_psd

FS = 1000.0


def _record(f0: float, ratio: float, n: int = 200_000, seed: int = 1) -> np.ndarray:
    """A moving position: the running sum of a 2nd-order Butterworth-filtered white velocity, plus white noise.

    Position PSD ``(2 ratio^2 / FS) |H(f)|^2 / (2 sin(pi f / FS))^2``, noise PSD ``2 / FS``.
    """
    rng = np.random.default_rng(seed)
    b, a = signal.butter(2, f0, fs=FS)
    return ratio * np.cumsum(signal.lfilter(b, a, rng.standard_normal(n))) + rng.standard_normal(n)


def _closed_form_crossing(f0: float, ratio: float) -> float:
    b, a = signal.butter(2, f0, fs=FS)

    def excess(f):  # log of the motion's PSD over the noise's
        _, h = signal.freqz(b, a, worN=[f], fs=FS)
        return math.log(ratio**2 * abs(h[0]) ** 2 / (2 * math.sin(math.pi * f / FS)) ** 2)

    return optimize.brentq(excess, 0.01, 0.49 * FS)


@pytest.mark.parametrize("f0, ratio", [(5.0, 30.0), (2.0, 100.0), (10.0, 3.0)])
def test_crossing_where_the_spectra_meet(f0, ratio):
    crossing = _closed_form_crossing(f0, ratio)
    cut = noise_cutoff(_record(f0, ratio), 1.0 / FS)
    assert crossing / 2**0.5 <= cut.crossing_hz <= crossing * 2**0.5, (cut, crossing)
    assert cut.filter_hz == pytest.approx(min(2.0 * cut.crossing_hz, 0.1 * FS))
    assert cut.rule.startswith("auto: twice the")


def test_position_psd_is_the_spectrum_of_the_position():
    """White noise of variance s^2 at fs: the one-sided PSD is 2 s^2 / fs at every frequency."""
    x = np.random.default_rng(2).normal(0.0, 3.0, 100_000)
    f, p = position_psd(x, 1.0 / FS)
    band = (f > 20) & (f < 400)
    assert np.median(p[band]) == pytest.approx(2 * 9.0 / FS, rel=0.05)


def test_no_noise_and_low_noise_keep_a_tenth_of_the_rate():
    t = np.arange(50_000) / FS
    clean = 0.01 * np.sin(2 * np.pi * 0.7 * t) + 0.004 * np.sin(2 * np.pi * 3.1 * t)
    cut = noise_cutoff(clean, 1.0 / FS)
    assert cut.crossing_hz is None and cut.filter_hz == 100.0
    low = noise_cutoff(_record(40.0, 3e4), 1.0 / FS)  # the spectra meet far above a tenth of the rate
    assert low.filter_hz == 100.0 and (low.crossing_hz is None or "limited to a tenth" in low.rule)


def test_a_short_record_sees_no_crossing_below_four_bins():
    x = _record(0.5, 0.3, n=3000)  # the spectra meet below 1 Hz; the bins of 3000 samples are 1.95 Hz wide
    cut = noise_cutoff(x, 1.0 / FS)
    f, _ = position_psd(x, 1.0 / FS)
    assert cut.crossing_hz == pytest.approx(4 * f[0]) and cut.filter_hz == pytest.approx(8 * f[0])
    assert 30.0 * FS / cut.filter_hz < x.size  # identify's border and rows fit


def test_a_slowly_falling_motion_far_above_the_noise_is_not_its_floor():
    """A motion whose spectrum falls by only sqrt(2) per octave up to 20 Hz (a loop's answer to friction's edges),
    then as f^-6, at 1000 times the white noise at 20 Hz: the spectra meet at 20 * 1000^(1/6) = 63 Hz (closed form),
    not where the slow fall starts (the rule without the floor condition stopped at its first band)."""
    n, fk, level = 2**18, 20.0, 1000.0
    rng = np.random.default_rng(3)
    f = np.fft.rfftfreq(n, 1.0 / FS)
    g = np.maximum(f, f[1]) / fk
    shape = np.where(g < 1.0, g**-0.5, g**-6.0)  # the motion's PSD relative to its value at fk
    spec = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) * np.sqrt(shape)
    # irfft of X has the one-sided PSD 2 |X|^2 / (n FS), E|X|^2 = 2 shape: scaled to level x the noise's 2 / FS at fk
    motion = math.sqrt(level * n / 2.0) * np.fft.irfft(spec, n)
    x = motion + rng.standard_normal(n)  # white noise: PSD 2 / FS
    crossing = fk * level ** (1.0 / 6.0)
    cut = noise_cutoff(x, 1.0 / FS)
    assert crossing / 2**0.5 <= cut.crossing_hz <= crossing * 2**0.5, (cut, crossing)
    f_psd, p = position_psd(x, 1.0 / FS)
    low = (f_psd > 5.0) & (f_psd < 10.0)
    high = (f_psd > 10.0) & (f_psd < 20.0)
    assert np.median(p[low]) < 2.0 * np.median(p[high])  # the slow fall the old rule took for the floor
