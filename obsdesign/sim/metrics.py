"""Summary metrics of a simulated run (the ``metrics`` of a :class:`~obsdesign.sim.SimResult`).

=========================  =====================================================================
key                        meaning
=========================  =====================================================================
``rms_error``              RMS of ``e = x_ref - x`` over the run [m]
``max_error``              largest ``|e|`` [m]
``settling_time``          per positioning hold: time after the step until ``|e|`` stays within
                           ``settle_tol`` (``None``: never within the hold) [s]
``steady_state_error``     per hold: mean ``e`` over its last 10 % [m]
``observer_rms_error_v``   RMS of ``v_hat - v`` [m/s]
``observer_rms_error_f``   RMS of ``f_hat - f`` [N] (``f``: the plant's value of the estimated state)
``diverged``               the run stopped early because a state left its bounds
``divergence``             ``None`` (no divergence), ``'numerical'`` (the plant's explicit step
                           ``dt / n_sub`` broke the rule of :mod:`obsdesign.sim.numerics`, so
                           the integrator, not the design, blew up) or ``'physical'`` (the
                           step was stable: the loop itself diverged)
``sim_wall_s``             wall time of the kernel [s]
``rms_error_per_band``     tracking only: RMS of ``e`` per chirp-frequency band [m]
=========================  =====================================================================

Non-finite samples (after a divergence) are left out of the RMS values.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .scenarios import CHIRP_BAND_LABELS, Scenario, chirp_frequency

__all__ = ["loop_metrics"]


def _rms(x: np.ndarray, finite: bool = False, scratch: np.ndarray | None = None) -> float | None:
    """RMS of the finite values of ``x`` (``finite``: the caller knows they all are; ``scratch``:
    a buffer at least as long as ``x`` for the squares, to spare an allocation per call)."""
    if not finite:
        x = x[np.isfinite(x)]
        scratch = None
    if not x.size:
        return None
    squares = np.multiply(x, x, out=None if scratch is None else scratch[:x.size])
    return float(np.sqrt(np.mean(squares)))


def _rms_of_difference(a: np.ndarray, b: np.ndarray, finite: bool, scratch: np.ndarray) -> float | None:
    """RMS of ``a - b`` (as :func:`_rms` of the difference), computed in ``scratch``."""
    if not finite:
        return _rms(a - b)
    diff = np.subtract(a, b, out=scratch[:a.size])
    return _rms(diff, True, diff)


def _first_at_or_above(sc: Scenario, frequency: float, n: int) -> int:
    """First sample whose chirp frequency (:func:`chirp_frequency`, evaluated exactly as there) is
    at least ``frequency``: found near its closed-form estimate, not by a pass over the run."""
    spec = sc.spec
    guess = int((frequency - spec.f0) * sc.duration / ((spec.f1 - spec.f0) * sc.dt))
    lo, hi = max(guess - 4, 0), min(guess + 5, n)
    if lo >= hi:
        return min(max(guess, 0), n)
    idx = np.arange(lo, hi)
    freq = chirp_frequency(idx * sc.dt, sc.duration, spec)
    above = np.nonzero(freq >= frequency)[0]
    if above.size == 0:
        return hi
    first = lo + int(above[0])
    if first == lo and lo > 0:  # the window started too late; fall back to a full search
        freq = chirp_frequency(np.arange(n) * sc.dt, sc.duration, spec)
        return int(np.searchsorted(freq, frequency, side="left"))
    return first


def loop_metrics(sc: Scenario, out: dict[str, np.ndarray], e: np.ndarray, n_written: int, settle_tol: float,
                 wall: float, *, step_stable: bool = True) -> dict[str, Any]:
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
    step_stable : bool
        Whether the plant's integration step met the numerical rule (labels a divergence).
    """
    dt = sc.dt
    valid = slice(0, n_written)
    e_valid = e[valid]
    # The kernel stops at the first sample whose state is not finite and below its bounds, so a
    # run that did not diverge holds finite values only.
    finite = n_written == len(e)
    scratch = np.empty(n_written)
    m: dict[str, Any] = {
        "rms_error": _rms(e_valid, finite, scratch),
        "max_error": float(max(np.max(e_valid), -np.min(e_valid))) if n_written else None,
        "settling_time": [],
        "steady_state_error": [],
        "observer_rms_error_v": _rms_of_difference(out["v_hat"][valid], out["v"][valid], finite, scratch),
        "observer_rms_error_f": _rms_of_difference(out["f_hat"][valid], out["f"][valid], finite, scratch),
        "diverged": not finite,
        "divergence": None if finite else ("physical" if step_stable else "numerical"),
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
        tail = idx[int(0.9 * len(idx)):]
        m["steady_state_error"].append(float(np.mean(e[tail])) if np.all(np.isfinite(e[tail])) else None)
    if sc.name == "tracking":
        # The chirp's frequency rises monotonically, so each band is a contiguous run of samples.
        m["rms_error_per_band"] = {}
        for label, lo, hi in CHIRP_BAND_LABELS:
            i0, i1 = (_first_at_or_above(sc, f, len(e)) for f in (lo, hi))
            m["rms_error_per_band"][label] = _rms(e[i0:i1], finite, scratch)
    return m
