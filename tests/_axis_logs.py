"""Synthetic axis logs for the identification tests: a known inverse model along an analytic path.

The path is a sum of sines (exact velocity and acceleration), the force the model
``m a + sigma v + Cf sign(v) + (Fs - Cf) sign(v) exp(-(v/vs)^2) + offset`` plus white force noise,
the position plus white noise and 0.5 um encoder steps. ``slow``: speeds up to 22 mm/s with
vs = 2 mm/s (the Stribeck drop dominates the friction); ``fast``: up to 0.19 m/s.
"""

from __future__ import annotations

import numpy as np

TRUTH = {"m": 1.8, "sigma": 12.0, "Cf": 2.4, "offset": 0.3, "Fs": 3.0, "vs": 2e-3}
DT = 5e-4
GAIN = 6.5  # N/A


def axis_log(kind: str, *, seed: int = 0, noise: float = 2e-7, duration: float = 24.0) -> dict:
    """Columns ``t`` [s], ``x`` [m], ``i`` [A] of a synthetic log (``kind`` 'slow' or 'fast')."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration / DT))) * DT
    peak = {"slow": 0.022, "fast": 0.19}[kind]
    freqs = np.array([0.15, 0.41, 0.93, 1.7])
    amps = np.array([1.0, 0.6, 0.35, 0.2])
    phases = rng.uniform(0, 2 * np.pi, freqs.size)
    w = 2 * np.pi * freqs
    v_raw = (amps[:, None] * w[:, None] * np.cos(w[:, None] * t + phases[:, None])).sum(axis=0)
    k = peak / np.max(np.abs(v_raw))
    x = k * (amps[:, None] * np.sin(w[:, None] * t + phases[:, None])).sum(axis=0)
    v = k * v_raw
    a = -k * (amps[:, None] * w[:, None] ** 2 * np.sin(w[:, None] * t + phases[:, None])).sum(axis=0)
    p = TRUTH
    u = (p["m"] * a + p["sigma"] * v + p["Cf"] * np.sign(v)
         + (p["Fs"] - p["Cf"]) * np.sign(v) * np.exp(-((v / p["vs"]) ** 2)) + p["offset"])
    u = u + rng.normal(0.0, 0.02, t.size)
    x_meas = np.round((x + rng.normal(0.0, noise, t.size)) / 5e-7) * 5e-7
    return {"t": t, "x": x_meas, "i": u / GAIN}


def write_mm_ms(path, log: dict) -> None:
    """The log as ``time_ms;pos_mm;i_A`` with a ``#`` comment line above the header."""
    rows = np.column_stack([log["t"] * 1e3, log["x"] * 1e3, log["i"]])
    with open(path, "w") as f:
        f.write("# synthetic axis log: time in ms, position in mm, motor current in A\n")
        np.savetxt(f, rows, delimiter=";", header="time_ms;pos_mm;i_A", comments="", fmt="%.17g")


def write_si(path, log: dict) -> None:
    """The log as ``t,x,i`` (s, m, A)."""
    np.savetxt(path, np.column_stack([log["t"], log["x"], log["i"]]), delimiter=",", header="t,x,i", comments="",
               fmt="%.17g")
