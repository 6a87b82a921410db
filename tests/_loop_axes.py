"""Test axes of the sampled loop, shared by the loop, plant-loop and PID-design tests (not shipped)."""

from __future__ import annotations

import dataclasses
import math

import obsdesign as od
from obsdesign.axis import AxisSpec


def config_2khz(delay=0, **override):
    """loop2k: the new-user trial's identified axis, 2 kHz, tau = m / sigma, crossover at a tenth of Nyquist."""
    m, sigma, K, dt = 1.8042, 11.922, 6.5, 5e-4
    wc = 0.1 * math.pi / dt
    return od.load_preset("vcm").override(m=m, sigma=sigma, K=K, dt=dt, tau=m / sigma, delay_samples=delay,
                                          max_S=K / sigma / (wc * math.sin(math.radians(60.0))), **override)


def rotary_4khz(delay=1):
    """A 4 kHz rotary axis (inertia 2e-4 kg m^2, 0.1 N m/A, 8 A), 2^20 counts/rev, PID for 200 Hz."""
    J, sigma, K, dt = 2.0e-4, 2.0e-3, 0.1, 2.5e-4
    wc = 2 * math.pi * 200
    cfg = od.load_preset("vcm").override(
        m=J, sigma=sigma, K=K, G=0.0, u_max=8.0, Cf=0.02, s=2000.0, kappa=100.0, dt=dt, tau=J / sigma,
        max_S=K / sigma / (wc * math.sin(math.radians(60.0))), quantization=2 * math.pi / 2**20, delay_samples=delay)
    return dataclasses.replace(cfg, name="rotary-4k", axis=AxisSpec(kind="rotary", input="A"), sources={})
