"""Offline rows of the estimator comparison on a measured trace (compute only).

The trace is identified (:func:`obsdesign.data.identify`, ``coulomb-viscous``), a design config
is built from it (:meth:`~obsdesign.data.Identification.to_config`), and every estimator runs
offline over the measured displacement and force: the paper observers through the simulator's
estimator step (:func:`obsdesign.data.observe` of the one sampled controller,
:func:`obsdesign.sampled.sampled_controller`, ``estimated`` schedule with its hysteresis), the
baselines tuned by the fair noise rule for the identified sensor. There is no true friction on measured data: the
reference is the identified model along the measured motion, the Coulomb part
``Cf coulomb(x, v)`` (pre-sliding with the identified ``s``) with ``v`` the zero-phase filtered
velocity, and ``v`` itself for the velocity error. The rows say how far each estimate is from the
identified model, not from the truth.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .comparison import not_tuned_row, paper_design
from .data import Trace, identify, observe
from .data.trace import zero_phase_velocity
from .estimators import friction_noise_rms, noise_level, reference_noise_rms, tune
from .friction.presliding import coulomb_along
from .sampled.choices import ESTIMATORS
from .sampled.controller import sampled_controller
from .sim.metrics import rms

__all__ = ["compare_data", "TRANSIENT_SAMPLES_S"]

#: Start-up interval [s] left out of the errors.
TRANSIENT_SAMPLES_S = 1.0


def compare_data(trace: Trace, *, estimators=tuple(ESTIMATORS), cutoff_hz: float | None = None,
                 rule: str = "noise") -> list[dict[str, Any]]:
    """One row per estimator on a measured trace (``plant = 'data:<source>'``, ``scenario = 'data'``).

    Parameters
    ----------
    trace : obsdesign.data.Trace
        The measurement (displacement and actuator force).
    estimators : sequence of str
        Names of :data:`obsdesign.sampled.choices.ESTIMATORS`.
    cutoff_hz : float, optional
        Cut-off of the zero-phase velocity of the reference (default that of the identification).
    rule : str
        Tuning rule of the baselines (:data:`obsdesign.estimators.RULES`), as in
        :func:`obsdesign.comparison.compare`.

    Returns
    -------
    list of dict
        Rows with the columns of :data:`obsdesign.comparison.COLUMNS`; a baseline the rule cannot tune for
        the identified config has the status ``"not tuned: <reason>"`` (:func:`obsdesign.comparison.not_tuned_row`).
    """
    if not isinstance(trace, Trace):
        raise TypeError(f"trace: expected an obsdesign.data.Trace, found {type(trace).__name__}")
    ident = identify(trace)
    cfg = ident.to_config(name=f"identified from {trace.source}")
    dt = cfg.observer.dt
    fr = cfg.friction
    x = np.ascontiguousarray(trace.position, dtype=np.float64)
    v_ref = zero_phase_velocity(x, dt, cutoff_hz if cutoff_hz is not None else ident.filter_hz)
    f_ref = coulomb_along(x, v_ref, fr.Cf, fr.s)
    keep = trace.t - trace.t[0] >= TRANSIENT_SAMPLES_S
    eta, band = noise_level(cfg)
    rows = []
    for name in estimators:
        ESTIMATORS.check(name)
        row: dict[str, Any] = {"plant": f"data:{trace.source}", "estimator": name, "scenario": "data", "seed": 0,
                               "settling_time": None, "overshoot": None, "tracking_rms_error": None}
        try:
            estimator = tune(name, cfg, rule=rule) if ESTIMATORS[name].baseline else name
            own = cfg if ESTIMATORS[name].baseline else paper_design(cfg, rule)
        except ValueError as e:  # a row with its reason, and the others run (issue 17 item 8)
            rows.append(not_tuned_row(row, e))
            continue
        try:
            ctrl = sampled_controller(own, estimator=estimator)
            result = observe(ctrl, trace)
            # the compensation signal, as in the closed loop: the paper entries' low-pass output,
            # a baseline's own estimate
            v_hat, f_hat = result.v_hat, result.f_hat_filtered
            if ctrl.baseline is None:
                noise = reference_noise_rms(own) if eta > 0 else 0.0
            else:
                noise = friction_noise_rms(ctrl.baseline, eta, band)
        except (ValueError, TypeError, ArithmeticError) as e:
            row.update(friction_rms_error=None, velocity_rms_error=None, friction_noise_rms=None,
                       status="failed: " + f"{type(e).__name__}: {e}".splitlines()[0])
            rows.append(row)
            continue
        row["friction_rms_error"] = rms((f_hat - f_ref)[keep])
        row["velocity_rms_error"] = rms((v_hat - v_ref)[keep])
        row["friction_noise_rms"] = noise
        ok = all(math.isfinite(v) for v in (row["friction_rms_error"] or math.nan, row["velocity_rms_error"] or math.nan))
        row["status"] = "ok" if ok else "diverged"
        rows.append(row)
    return rows

