"""Summary metrics of a simulated run (the ``metrics`` of a :class:`~obsdesign.sim.SimResult`).

=========================  =====================================================================
key                        meaning
=========================  =====================================================================
``rms_error``              RMS of ``e = x_ref - x`` over the run [m]
``max_error``              largest ``|e|`` [m]
``settling_time``          per positioning hold: time after the step until ``|e|`` stays within
                           ``settle_tol`` (``None``: never within the hold) [s]
``steady_state_error``     per hold: mean ``e`` over its last 10 % [m]
``overshoot``              per positioning step: largest excursion of ``x`` beyond the target in
                           the step direction, as a fraction of the step [-]
``rise_time``              per positioning step: 10 % to 90 % of the step [s] (``None``: not reached)
``observer_rms_error_v``   RMS of ``v_hat - v`` [m/s]
``observer_rms_error_f``   RMS of ``f_hat - f`` [N] (``f``: the plant's value of the estimated state)
``diverged``               the run stopped early because a state left its bounds
``sim_wall_s``             wall time of the kernel [s]
``rms_error_per_band``     tracking only: RMS of ``e`` per chirp-frequency band [m]
=========================  =====================================================================

Non-finite samples (after a divergence) are left out of the RMS values. ``overshoot`` and
``rise_time`` come from :func:`obsdesign.sim.step_metrics.step_metrics` on the plant's
displacement over each hold (``None`` for a hold the run did not reach).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from .scenarios import CHIRP_BAND_LABELS, Scenario, chirp_frequency
from .step_metrics import step_metrics

__all__ = ["loop_metrics", "METRIC_UNITS"]

#: Unit of each metric for text output ("-": dimensionless; lists and dicts: of their items).
METRIC_UNITS = {
    "rms_error": "m", "max_error": "m", "settling_time": "s", "steady_state_error": "m", "overshoot": "-",
    "rise_time": "s", "observer_rms_error_v": "m/s", "observer_rms_error_f": "N", "sim_wall_s": "s",
    "rms_error_per_band": "m",
}


@njit(cache=True, error_model="numpy")
def _rms_of_difference(a, b, n):
    """RMS of the finite values of ``a[:n] - b[:n]`` (NaN if there are none)."""
    total = 0.0
    count = 0
    for i in range(n):
        d = a[i] - b[i]
        if np.isfinite(d):
            total += d * d
            count += 1
    return np.sqrt(total / count) if count else np.nan


def _rms(x: np.ndarray) -> float | None:
    if not np.isfinite(x).all():
        x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if x.size else None


def _none_if_nan(value: float) -> float | None:
    return None if np.isnan(value) else float(value)


def _step_response(m: dict, sc: Scenario, x: np.ndarray, idx: np.ndarray, start: float, settle_tol: float,
                   reached: bool) -> None:
    """Append the overshoot and rise time of the step that starts the hold ``idx``."""
    y1 = float(sc.x_ref[idx[0]])
    y0 = float(sc.x_ref[idx[0] - 1]) if idx[0] > 0 else 0.0
    if not reached or y1 == y0:
        m["overshoot"].append(None)
        m["rise_time"].append(None)
        return
    sm = step_metrics(idx * sc.dt, x[idx], t_step=start, y0=y0, y1=y1, settle_band=settle_tol)
    m["overshoot"].append(sm["overshoot"])
    m["rise_time"].append(sm["rise_time"])


def loop_metrics(sc: Scenario, out: dict[str, np.ndarray], e: np.ndarray, n_written: int, settle_tol: float,
                 wall: float) -> dict[str, Any]:
    """The metrics of a run from the kernel's outputs (see the module docstring).

    Parameters
    ----------
    sc : Scenario
        The sampled scenario.
    out : dict of ndarray
        The kernel's outputs.
    e : ndarray
        Tracking error x_ref - x [m].
    n_written : int
        Samples the kernel wrote (fewer after a divergence).
    settle_tol : float
        Settling band [m].
    wall : float
        Wall time of the kernel [s].
    """
    dt = sc.dt
    valid = slice(0, n_written)
    e_valid = e[valid]
    m: dict[str, Any] = {
        "rms_error": _rms(e_valid),
        "max_error": float(max(np.max(e_valid), -np.min(e_valid))) if n_written else None,
        "settling_time": [],
        "steady_state_error": [],
        "overshoot": [],
        "rise_time": [],
        "observer_rms_error_v": _none_if_nan(_rms_of_difference(out["v_hat"], out["v"], n_written)),
        "observer_rms_error_f": _none_if_nan(_rms_of_difference(out["f_hat"], out["f"], n_written)),
        "diverged": bool(n_written < len(e)),
        "sim_wall_s": wall,
    }
    for start, end in sc.holds:
        i0, i1 = int(np.ceil(start / dt - 0.5)), int(np.ceil(end / dt - 0.5))
        idx = np.arange(max(i0, 0), min(i1, len(e)))
        seg = np.abs(e[idx])
        outside = np.nonzero(~(seg <= settle_tol))[0]
        if m["diverged"] and idx[-1] >= n_written:
            m["settling_time"].append(None)
        elif outside.size == 0:
            m["settling_time"].append(0.0)
        elif outside[-1] == len(seg) - 1:
            m["settling_time"].append(None)  # never settles within the hold
        else:
            m["settling_time"].append(float((outside[-1] + 1) * dt))
        _step_response(m, sc, out["x"], idx, start, settle_tol, reached=not (m["diverged"] and idx[-1] >= n_written))
        tail = idx[int(0.9 * len(idx)):]
        m["steady_state_error"].append(float(np.mean(e[tail])) if np.all(np.isfinite(e[tail])) else None)
    if sc.name == "tracking":
        # The chirp's frequency rises monotonically, so each band is a contiguous run of samples.
        freq = chirp_frequency(np.arange(len(e)) * dt, sc.duration, sc.spec)
        m["rms_error_per_band"] = {}
        for label, lo, hi in CHIRP_BAND_LABELS:
            i0, i1 = np.searchsorted(freq, (lo, hi), side="left")
            m["rms_error_per_band"][label] = _rms(e[i0:i1])
    return m
