"""The simulation of the segment fit (:mod:`obsdesign.data.oe_segments`): the segments, their plant (numba) and
the Heun sub-step rule.

Examples
--------
>>> segment_bounds(1000, 400, skip=50).tolist()
[[50, 400], [450, 400]]
>>> substeps(2e5, 2.5e-3, 2.5e-4), substeps(1e6, 1.8, 1e-3)     # omega dt = 2.24 and 0.75
(36, 12)
"""

from __future__ import annotations

import math
import time

import numpy as np
from numba import njit

from ..friction.kernels import friction_plant_step
from ..friction.registry import FRICTION_MODELS

__all__ = ["SUBSTEP_RULE", "BudgetExceeded", "segment_bounds", "simulate_segments", "substeps"]

_LUGRE = FRICTION_MODELS.code("lugre")
_LAYOUT = FRICTION_MODELS["lugre"]._layout

#: The sub-step rule ``omega h <= 1 / SUBSTEP_RULE`` (``omega = sqrt(sigma0 / m)``, ``h`` a sub-step). Measured on
#: the rotary 4 kHz benchmark axis (``omega dt = 2.24``), each 0.1 s segment replayed from the true states against
#: the generator's 128-sub-step log: at 4 (the rule before, 9 sub-steps) up to 3.2 times the position noise off
#: near reversals, and a noise-free fit read it as sigma1 +17 %, sigma0 -1.4 %; at 8 (18) 0.82 times, +5.3 %,
#: -0.5 %; at 16 (36) 0.20 times, +1.6 %, -0.06 % (m within 4e-5 %, Cf 2e-4 % at every rule). The error is second
#: order in ``h`` and is measured against the position noise, so a log with a noise 10 times lower needs about 3
#: times the sub-steps for the same margin.
SUBSTEP_RULE = 16.0


class BudgetExceeded(Exception):
    """The time budget ran out (internal: the fit returns its best so far)."""


def segment_bounds(n: int, length: int, *, skip: int) -> np.ndarray:
    """``[start, length]`` rows of consecutive segments of ``length`` samples in ``n``, ``skip`` left at both ends.

    Parameters
    ----------
    n, length, skip : int
        Samples of the record, of a segment, and left out at each end.
    """
    starts = np.arange(skip, n - skip - length + 1, length, dtype=np.int64)
    return np.column_stack([starts, np.full(starts.size, length, dtype=np.int64)])


@njit(cache=True, error_model="numpy")
def simulate_segments(pp, force, starts, length, x0, v0, fz0, m, dt, n_sub, hold, out):
    """Simulate each segment from ``(x0, v0, sigma0 z0 = fz0)``; write ``x`` to ``out`` (segments x length).

    ``force[k]`` is held over ``[k, k+1)`` when ``hold``, else interpolated linearly to ``force[k+1]``.
    Returns False if a simulation diverged (its samples NaN).
    """
    h = dt / n_sub
    st = np.zeros(3)
    sigma0 = pp[8]
    ok = True
    for i in range(starts.shape[0]):
        x, v = x0[i], v0[i]
        st[0] = fz0[i] / sigma0
        st[1] = x
        st[2] = 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)
        for k in range(length):
            out[i, k] = x
            if not (abs(x) < 1e6 and abs(v) < 1e9):
                for j in range(k, length):
                    out[i, j] = np.nan
                ok = False
                break
            j = starts[i] + k
            if hold:
                x, v = friction_plant_step(_LUGRE, pp, st, x, v, force[j], m, h, n_sub)
            else:
                u1 = force[j + 1] if j + 1 < force.shape[0] else force[j]
                for s in range(n_sub):
                    a = (s + 0.5) / n_sub
                    x, v = friction_plant_step(_LUGRE, pp, st, x, v, (1.0 - a) * force[j] + a * u1, m, h, 1)
    return ok


class _Segments:
    """The data, the parameter vector and the residual of one segment length."""

    def __init__(self, x_meas, force, x_f, v_f, dt, length, skip, hold, noise, n_sub, budget):
        rows = segment_bounds(x_meas.size, length, skip=skip)
        if rows.shape[0] < 2:
            raise ValueError(f"trace: expected at least 2 segments of {length} samples, found {rows.shape[0]} "
                             f"(the record has {x_meas.size} samples)")
        self.starts, self.length = rows[:, 0], int(length)
        self.meas = x_meas[self.starts[:, None] + np.arange(length)]
        self.force, self.dt, self.hold, self.noise, self.n_sub = force, dt, hold, noise, n_sub
        self.x0, self.v0 = x_f[self.starts], v_f[self.starts]
        self.out = np.empty_like(self.meas)
        self.budget = budget

    def pack(self, q):
        """The kernel array: the registry's LuGre layout, without its ranges (written in N/m and m/s: a rotary
        axis's N m/rad and rad/s fall outside them); a Stribeck level below Cf is taken as Cf."""
        fs = max(q["Fs"], q["Cf"])
        if not (q["Cf"] > 0 and q["vs"] > 0 and q["sigma0"] > 0 and q["m"] > 0):
            raise ValueError("a positive parameter at or below 0")
        return np.array(_LAYOUT({"Cf": q["Cf"], "Cf_neg": q["Cf"], "sigma": q["sigma"], "sigma_neg": q["sigma"],
                                 "offset": q["offset"], "Fs": fs, "vs": q["vs"], "sigma0": q["sigma0"],
                                 "sigma1": max(q["sigma1"], 0.0)}), dtype=np.float64)

    def residual(self, q, nu):
        """Weighted residual (segments x L) at global values ``q`` and nuisances ``nu`` (segments x 3)."""
        try:
            self.simulate(q, nu, self.n_sub, self.out)
        except ValueError:
            return np.full(self.meas.shape, 1e6)
        r = (self.meas - self.out) / self.noise
        return np.where(np.isfinite(r), r, 1e6)

    def simulate(self, q, nu, n_sub, out):
        """The segments' positions at ``q``, ``nu`` with ``n_sub`` sub-steps a sample, into ``out``."""
        self.budget.tick()
        pp = self.pack(q)
        simulate_segments(pp, self.force, self.starts, self.length, self.x0 + nu[:, 0] * self.noise,
                          self.v0 + nu[:, 1] * self.noise / self.dt, nu[:, 2] * q["Cf"], q["m"], self.dt,
                          n_sub, self.hold, out)


class _Budget:
    """Counts simulations, drives the progress bar and stops at the time budget."""

    def __init__(self, seconds, bar):
        self.t0 = time.perf_counter()
        self.seconds = seconds
        self.bar = bar
        self.count = 0

    def tick(self):
        self.count += 1
        if self.bar is not None:
            self.bar.update(1)
        if self.seconds is not None and time.perf_counter() - self.t0 > self.seconds:
            raise BudgetExceeded


def substeps(sigma0: float, m: float, dt: float) -> int:
    """Heun substeps a sample for a bristle resonance ``omega = sqrt(sigma0/m)`` [rad/s]:
    ``omega h <= 1/``:data:`SUBSTEP_RULE`, 4 to ``4 SUBSTEP_RULE`` (the profile's stiffest bristle, ``omega dt = 4``).

    Parameters
    ----------
    sigma0, m, dt : float
        Bristle stiffness, mass (inertia), sample time.

    Examples
    --------
    >>> substeps(2e5, 2.5e-3, 2.5e-4)        # omega dt = 2.24: the rotary 4 kHz benchmark axis
    36
    >>> substeps(1e6, 1.8, 1e-3)             # omega dt = 0.75: the linear 1 kHz one
    12
    """
    return int(min(max(math.ceil(SUBSTEP_RULE * math.sqrt(sigma0 / m) * dt), 4), 4 * SUBSTEP_RULE))
