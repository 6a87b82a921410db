"""Fair tuning: each baseline's knob from the paper observer's noise or convergence rate.

The noise RMS of an estimate is the closed-form band integral of
:mod:`obsdesign.estimators.noise_rms` (:func:`estimate_noise_rms`: a discrete Lyapunov equation
and a matrix logarithm), so the knobs below are solved on an integral exact to rounding.

Rules (``rule``):

``"noise"`` (default)
    The knob (ESO ``omega_o``, Kalman ``q``, DOB ``omega_q``) is solved with ``brentq`` on
    its logarithm so that the RMS of the baseline's own friction estimate equals that of the
    paper observer's friction estimate after the low-pass eq:3:4:5, both at ``k = 0``
    (gross sliding) and both discrete at ``dt``. The baselines get no extra filter: each
    compares the signal used for compensation.
``"rate"``
    The slowest error pole equals the paper's dominant pole ``-sqrt(kappa/m)(rho - 1)`` at
    ``k = 0``: ``omega_o = omega_q = sqrt(kappa/m)(rho - 1)``; for the Kalman filter
    ``q`` is solved so that the largest discrete pole radius is ``exp(p_dom dt)``.
``"min-error"``
    The knob minimises the predicted error of the compensated estimate
    (:func:`obsdesign.estimators.prediction.predict_error`: noise propagation plus tracking lag
    of Coulomb reversals), independently of the paper's observer: a log grid of 33 points over
    the knob's range, then a bounded ``minimize_scalar`` between the best point's neighbours.

Both rules are independent of ``eta`` (every RMS is proportional to it; the Kalman gain
depends on ``q / eta^2`` and its knob scales with ``eta^2``), but depend on ``B`` and ``dt``.

Examples
--------
>>> import obsdesign as od
>>> cfg = od.load_preset("vcm")
>>> ref = reference_noise_rms(cfg)
>>> est = tune("eso", cfg)
>>> round(friction_noise_rms(est, *noise_level(cfg)) / ref, 6)
1.0
"""

from __future__ import annotations

import math

import numpy as np

from .._memo import config_key, memo
from ..params import Config
from .base import DiscreteEstimator, check_config, check_positive
from .kalman import noise_level
from .noise_rms import estimate_noise_rms, friction_noise_rms, velocity_noise_rms
from .paper import build_paper, paper_dominant_pole, with_lowpass
from .registry import ESTIMATORS, RULES

__all__ = ["RULES", "friction_noise_rms", "velocity_noise_rms", "estimate_noise_rms",
           "reference_noise_rms", "reference_estimator", "tune", "noise_level"]

#: Measurement RMS [m] the knobs' search ranges (``EstimatorInfo.knob_range``) are written for.
_RANGE_ETA = 1e-6
#: Relative tolerance of the solved knob (the RMS is a power of it: well inside 1 %).
_XTOL = 1e-9


def reference_estimator(cfg: Config) -> DiscreteEstimator:
    """The paper observer at ``k = 0`` followed by the discretized low-pass eq:3:4:5 (``nz = 4``).

    Parameters
    ----------
    cfg : Config
        The design.
    """
    cfg = check_config(cfg)
    _check_paper_stable(cfg)
    return with_lowpass(build_paper(cfg, stiffness=0.0), cfg.observer.omega_co)


def reference_noise_rms(cfg: Config) -> float:
    """RMS [N] of the paper's low-pass filtered friction estimate at ``k = 0``: the equal-noise target.

    A pure function of the design, kept on disk (:mod:`obsdesign._memo`) like the tuned knobs.

    Parameters
    ----------
    cfg : Config
        The design.
    """
    cfg = check_config(cfg)
    return memo("reference_noise_rms", (config_key(cfg),),
                lambda: friction_noise_rms(reference_estimator(cfg), *noise_level(cfg)),
                valid=lambda v: isinstance(v, float) and math.isfinite(v) and v >= 0.0)


def _check_paper_stable(cfg: Config) -> float:
    pole = paper_dominant_pole(cfg)
    if not pole < 0.0:
        raise ValueError(
            f"rho: the reference needs a stable paper observer at k = 0 (rho > 1), found rho = "
            f"{cfg.observer.rho!r} (dominant pole {pole:.4g} 1/s)")
    return pole


def _solve_log(fun, lo: float, hi: float, what: str) -> float:
    """Root of ``fun(log knob)`` on ``[log lo, log hi]`` (``fun`` increasing in the knob)."""
    a, b = math.log(lo), math.log(hi)
    fa, fb = fun(a), fun(b)
    if not (fa < 0.0 < fb):
        raise ValueError(f"{what}: no knob in [{lo:g}, {hi:g}] reaches the target "
                         f"(relative mismatch {fa:+.3g} at the low end, {fb:+.3g} at the high end)")
    import scipy.optimize  # only where a knob is solved (the memo keeps the solutions)

    return math.exp(scipy.optimize.brentq(fun, a, b, xtol=_XTOL, rtol=_XTOL, maxiter=200))


def _min_error(make, cfg: Config, lo: float, hi: float) -> float:
    """The knob in ``[lo, hi]`` of least :func:`~obsdesign.estimators.prediction.predict_error` (total)."""
    from .prediction import predict_error

    def cost(log_knob: float) -> float:
        try:
            return predict_error(make(math.exp(log_knob)), cfg).total
        except (ValueError, ArithmeticError, np.linalg.LinAlgError):
            return math.inf

    grid = np.linspace(math.log(lo), math.log(hi), 33)
    values = [cost(x) for x in grid]
    i = int(np.argmin(values))
    if not math.isfinite(values[i]):
        raise ValueError(f"min-error rule: no knob in [{lo:g}, {hi:g}] gives a stable estimator")
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    import scipy.optimize

    res = scipy.optimize.minimize_scalar(cost, bounds=(a, b), method="bounded", options={"xatol": 1e-4})
    return math.exp(float(res.x)) if res.fun < values[i] else math.exp(float(grid[i]))


def tune(name: str, cfg: Config, *, rule: str = "noise", sigma_model: float | None = None) -> DiscreteEstimator:
    """An estimator of the registry with its knob set by the fair tuning rule.

    The knob, its search range and the rules come from the entry of
    :data:`~obsdesign.estimators.ESTIMATORS` (:class:`~obsdesign.estimators.EstimatorInfo`).

    Parameters
    ----------
    name : str
        A name of :data:`~obsdesign.estimators.ESTIMATORS`. The paper entries are the reference
        and are returned as designed (``k = 0``).
    cfg : Config
        The design.
    rule : str
        One of :data:`RULES`: equal friction-noise RMS with the paper's filtered estimate
        (``"noise"``), equal slowest pole (``"rate"``), or least predicted error (``"min-error"``).
    sigma_model : float, optional
        Viscous coefficient of the baselines' model (default: ``sigma`` for ``static``, 0 for ``lag``).

    Raises
    ------
    ValueError
        Unknown name or rule; unstable reference (``rho <= 1``); no sensor noise for ``"noise"``
        or for the Kalman filter; no knob in the search range reaches the target.
    """
    info = ESTIMATORS[ESTIMATORS.check(name, kind="name")]
    if not isinstance(rule, str) or rule not in info.rules:
        raise ValueError(f"rule: expected one of {', '.join(info.rules)}, found {rule!r}")
    cfg = check_config(cfg)
    if not info.baseline:
        return info.build(cfg, sigma_model=sigma_model)
    pole = _check_paper_stable(cfg) if rule != "min-error" else math.nan
    knob, (lo, hi), build = info.knob, info.knob_range, info.build

    def make(value: float) -> DiscreteEstimator:
        return build(cfg, **{knob: value}, sigma_model=sigma_model, tuning=rule)

    if rule == "rate" and info.knob_is_rate:
        return make(-pole)
    eta, B = noise_level(cfg)
    if info.knob_noise_power:
        check_positive("measurement_rms (sensor noise_rms or quantization)", eta, "m")
        for _ in range(info.knob_noise_power):   # lo eta^p / eta_range^p, in this order of operations
            lo, hi = lo * eta, hi * eta
        lo, hi = lo / _RANGE_ETA ** info.knob_noise_power, hi / _RANGE_ETA ** info.knob_noise_power
    if rule == "noise" and eta == 0.0:
        raise ValueError("sensor: the noise rule needs noise_rms > 0 or quantization > 0, found both 0")

    def knob_value() -> float:
        if rule == "min-error":
            return _min_error(make, cfg, lo, hi)
        if rule == "rate":
            target = pole * cfg.observer.dt          # log of the target pole radius

            def mismatch(log_q: float) -> float:     # > 0 when faster than the target
                return target - math.log(float(np.max(np.abs(make(math.exp(log_q)).poles()))))

            return _solve_log(mismatch, lo, hi, "rate rule")
        ref = reference_noise_rms(cfg)

        def mismatch(log_knob: float) -> float:
            return friction_noise_rms(make(math.exp(log_knob)), eta, B) / ref - 1.0

        return _solve_log(mismatch, lo, hi, "noise rule")

    # the knob is a pure function of the estimator, the rule and the design: kept on disk (obsdesign._memo)
    return make(memo("tune", (name, rule, sigma_model, lo, hi, config_key(cfg)), knob_value,
                     valid=lambda v: isinstance(v, float) and math.isfinite(v)))
