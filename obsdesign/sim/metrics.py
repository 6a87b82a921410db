"""Summary metrics of a simulated run (the ``metrics`` of a :class:`~obsdesign.sim.SimResult`).

Lengths are in the axis's unit: m on a linear axis, rad on a rotary one (m/s or rad/s, N or N m).

=========================  =====================================================================
key                        meaning
=========================  =====================================================================
``rms_error``              RMS of ``e = x_ref - x`` over the run [m]
``max_error``              largest ``|e|`` [m]
``settle_band``            half-width of the settling band [m] (:mod:`obsdesign.loop.bands`:
                           ``max(2 x resolution, 3 x noise RMS)`` unless given; ``None`` for an
                           open-loop run)
``settle_band_rule``       where the band comes from (``'2 x encoder resolution 1e-06 m'``, ``'given'``)
``settling_time``          per positioning hold: time after the step from which ``|e|`` stays within
                           the band to the end of the hold, at least its last 10 %
                           (``None``: did not settle) [s]
``settled``                per hold: whether it settled (``False``: "did not settle")
``steady_state_error``     per hold: mean ``e`` over its last 10 % [m]
``steady_state_in_band``   per hold: ``|steady_state_error|`` within the band (``None``: not reached)
``overshoot``              per positioning step: largest excursion of ``x`` beyond the target in
                           the step direction, as a fraction of the step [-]
``rise_time``              per positioning step: 10 % to 90 % of the step [s] (``None``: not reached)
``observer_rms_error_v``   RMS of ``v_hat - v`` [m/s]
``observer_rms_error_f``   RMS of ``f_hat - f`` [N] (``f``: the plant's value of the estimated state)
``diverged``               the run stopped early because a state left the simulator's bounds, or ran
                           away from its task (``divergence`` ``'runaway'`` or ``'estimate'``)
``divergence``             ``None`` (no divergence), ``'numerical'`` (the plant's explicit step
                           ``dt / n_sub`` broke the rule of :mod:`obsdesign.loop.numerics`, so
                           the integrator, not the design, blew up), ``'measurement'`` (the
                           measured displacement left the bounds while the plant stayed within
                           them: the sensor noise or quantization is out of scale),
                           ``'physical'`` (the step was stable: the loop itself diverged),
                           ``'runaway'`` (the run went on, but ``|e|`` exceeded ``error_bound``)
                           or ``'estimate'`` (the filtered friction estimate exceeded
                           ``estimate_bound``)
``error_bound``            closed loop: 10 x (reference span + band) [m]; ``None`` in open loop
``estimate_bound``         10 x (``K u_max + |G| + Cf``) of the simulated plant [N]
``sim_wall_s``             wall time of the kernel [s]
``rms_error_per_band``     tracking only: RMS of ``e`` per chirp-frequency band [m]
=========================  =====================================================================

Non-finite samples (after a divergence) are left out of the RMS values. ``overshoot`` and
``rise_time`` come from :func:`obsdesign.sim.step_metrics.step_metrics` on the plant's
displacement over each hold (``None`` for a hold the run did not reach).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..loop.scenarios import CHIRP_BAND_LABELS, Scenario, chirp_frequency, hold_samples
from ..loop.bands import SETTLE_DWELL, error_bound
from .step_metrics import settling_sample, step_metrics

__all__ = ["loop_metrics", "METRIC_UNITS", "rms"]

#: Unit of each metric for text output ("-": dimensionless; lists and dicts: of their items).
METRIC_UNITS = {
    "rms_error": "m", "max_error": "m", "settle_band": "m", "settling_time": "s", "steady_state_error": "m",
    "overshoot": "-", "rise_time": "s", "observer_rms_error_v": "m/s", "observer_rms_error_f": "N", "sim_wall_s": "s",
    "rms_error_per_band": "m", "error_bound": "m", "estimate_bound": "N",
}


def rms(x: np.ndarray, *, finite: bool = False, scratch: np.ndarray | None = None) -> float | None:
    """RMS of the finite values of ``x``; None where there is none.

    Parameters
    ----------
    x : ndarray, shape (n,)
        The samples (NaN and inf are left out).
    finite : bool
        The caller knows every value is finite (no mask is built).
    scratch : ndarray, shape (>= n,), optional
        A buffer for the squares (with ``finite``), to spare an allocation per call.

    Examples
    --------
    >>> import numpy as np
    >>> rms(np.array([3.0, -4.0, np.nan]))          # sqrt((9 + 16) / 2)
    3.5355339059327378
    >>> rms(np.array([np.nan])) is None
    True
    """
    if not finite:
        x = x[np.isfinite(x)]
        scratch = None
    if not x.size:
        return None
    with np.errstate(over="ignore"):
        squares = np.multiply(x, x, out=None if scratch is None else scratch[:x.size])
        mean = float(np.mean(squares))
    if not np.isfinite(mean):  # values near 1e154 and above: their squares overflow, so scale first
        peak = float(np.max(np.abs(x)))
        return peak * float(np.sqrt(np.mean(np.square(x / peak))))
    return float(np.sqrt(mean))


def _rms_of_difference(a: np.ndarray, b: np.ndarray, finite: bool, scratch: np.ndarray) -> float | None:
    """RMS of ``a - b`` (as :func:`rms` of the difference), computed in ``scratch``."""
    if not finite:
        return rms(a - b)
    diff = np.subtract(a, b, out=scratch[:a.size])
    return rms(diff, finite=True, scratch=diff)


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


def _step_response(m: dict, sc: Scenario, x: np.ndarray, i0: int, i1: int, start: float, settle_tol: float,
                   reached: bool, scratch: np.ndarray) -> None:
    """Append the overshoot and rise time of the step that starts the hold of samples ``i0 .. i1 - 1``
    (``scratch``: two float buffers of at least ``i1 - i0`` samples each, as rows)."""
    y1 = float(sc.x_ref[i0])
    y0 = float(sc.x_ref[i0 - 1]) if i0 > 0 else 0.0
    if not reached or y1 == y0:
        m["overshoot"].append(None)
        m["rise_time"].append(None)
        return
    t = scratch[1, :i1 - i0]
    t[:] = np.arange(i0, i1)  # exact: the sample numbers are integers below 2**53
    t *= sc.dt  # the sample times, as np.arange(i0, i1) * dt
    sm = step_metrics(t, x[i0:i1], t_step=start, y0=y0, y1=y1, settle_band=settle_tol, scratch=scratch[0])
    m["overshoot"].append(sm["overshoot"])
    m["rise_time"].append(sm["rise_time"])


def _divergence(out: dict[str, np.ndarray], n_written: int, step_stable: bool) -> str:
    """The label of a diverged run: 'numerical', 'measurement' or 'physical' (see the module docstring)."""
    from .kernel import DIVERGED_F, DIVERGED_X

    if not step_stable:
        return "numerical"
    last = n_written - 1
    if last >= 0 and abs(out["x"][last]) < DIVERGED_X and abs(out["v"][last]) < DIVERGED_F \
            and not float(np.max(np.abs(out["x_meas"][:n_written]))) < DIVERGED_X:
        return "measurement"
    return "physical"


def loop_metrics(sc: Scenario, out: dict[str, np.ndarray], e: np.ndarray, n_written: int, settle_tol: float | None,
                 wall: float, *, step_stable: bool = True, settle_rule: str = "given",
                 force_bound: float = math.inf, span: float | None = None) -> dict[str, Any]:
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
    settle_tol : float or None
        Settling band [m] (None: an open-loop run, which has none).
    wall : float
        Wall time of the kernel [s].
    step_stable : bool
        Whether the plant's integration step met the numerical rule (labels a divergence).
    settle_rule : str
        Where the band comes from (:class:`obsdesign.loop.bands.SettleBand`), stated in the metrics.
    force_bound : float
        The estimate's runaway bound [N] (:func:`obsdesign.loop.bands.force_bound`).
    span : float, optional
        Peak-to-peak of the reference the run followed [m] (default: the scenario's ``x_ref``).
    """
    dt = sc.dt
    valid = slice(0, n_written)
    e_valid = e[valid]
    # The kernel stops at the first sample whose state is not finite and below its bounds, so a
    # run that did not diverge holds finite values only.
    finite = n_written == len(e)
    # The float intermediates of the run's length live in these two rows: fresh memory costs a page fault
    # per 4 KiB on Linux, more than the arithmetic of this function (most of a sweep's time per run beyond
    # the kernel).
    buffers = np.empty((2, len(e)))
    scratch = buffers[0]
    closed = not sc.spec.open_loop
    if span is None:
        span = float(np.max(sc.x_ref) - np.min(sc.x_ref)) if closed and len(sc.x_ref) else 0.0
    max_error = float(max(np.max(e_valid), -np.min(e_valid))) if n_written else None
    m: dict[str, Any] = {
        "rms_error": rms(e_valid, finite=finite, scratch=scratch),
        "max_error": max_error,
        "settle_band": settle_tol,
        "settle_band_rule": settle_rule if settle_tol is not None else None,
        "settling_time": [],
        "settled": [],
        "steady_state_error": [],
        "steady_state_in_band": [],
        "overshoot": [],
        "rise_time": [],
        "observer_rms_error_v": _rms_of_difference(out["v_hat"][valid], out["v"][valid], finite, scratch),
        "observer_rms_error_f": _rms_of_difference(out["f_hat"][valid], out["f"][valid], finite, scratch),
        "diverged": not finite,
        "divergence": None if finite else _divergence(out, n_written, step_stable),
        "error_bound": error_bound(span, settle_tol) if closed and settle_tol is not None else None,
        "estimate_bound": force_bound,
        "sim_wall_s": wall,
    }
    if finite:  # the run went on to the end: did it run away from its task?
        ff = out["f_hat_filtered"]
        if m["error_bound"] is not None and max_error is not None and max_error > m["error_bound"]:
            m["diverged"], m["divergence"] = True, "runaway"
        elif ff.size and float(max(np.max(ff), -np.min(ff))) > force_bound:
            m["diverged"], m["divergence"] = True, "estimate"
    if sc.holds and settle_tol is None:
        raise ValueError("settle_tol: expected a band > 0 for a scenario with holds, found None")
    band = math.inf if settle_tol is None else float(settle_tol)
    for start, end in sc.holds:
        i0, i1 = hold_samples(start, end, dt, len(e))  # at least 2 (build_scenario)
        seg = e[i0:i1]
        reached = finite or i1 - 1 < n_written
        settled = settling_sample(seg, 0.0, band, dwell=SETTLE_DWELL, scratch=scratch) if reached else None
        m["settling_time"].append(None if settled is None else (0.0 if settled == 0 else float(settled * dt)))
        m["settled"].append(settled is not None)
        _step_response(m, sc, out["x"], i0, i1, start, band, reached=reached, scratch=buffers)
        tail = seg[int((1.0 - SETTLE_DWELL) * len(seg)):]
        sse = float(np.mean(tail)) if np.all(np.isfinite(tail)) else None
        m["steady_state_error"].append(sse)
        m["steady_state_in_band"].append(None if sse is None else abs(sse) <= band)
    if sc.name == "tracking":
        # The chirp's frequency rises monotonically, so each band is a contiguous run of samples.
        m["rms_error_per_band"] = {}
        for label, lo, hi in CHIRP_BAND_LABELS:
            i0, i1 = (_first_at_or_above(sc, f, len(e)) for f in (lo, hi))
            m["rms_error_per_band"][label] = rms(e[i0:i1], finite=finite, scratch=scratch)
    return m
