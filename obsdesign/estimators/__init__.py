"""Estimators of velocity and friction by registry, with a fair tuning rule.

Every estimator is a :class:`DiscreteEstimator` in one discrete form, run per sample by
:func:`estimator_step` (numba). ``ESTIMATORS`` (:mod:`~obsdesign.estimators.registry`, light)
maps names to codes, knobs, tuning rules and builders;
:func:`tune` sets a baseline's knob so that its friction-noise RMS equals that of the
paper's filtered estimate (``rule="noise"``) or its slowest pole equals the paper's
dominant pole (``rule="rate"``).

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.estimators import tune, friction_noise_rms, reference_noise_rms, noise_level
>>> cfg = od.load_preset("vcm")
>>> est = tune("dob", cfg)
>>> round(friction_noise_rms(est, *noise_level(cfg)) / reference_noise_rms(cfg), 6)
1.0
"""

from .._lazy import lazy_names

__all__ = [
    "MAX_STATES", "DiscreteEstimator", "discretize_observer", "estimator_output", "estimator_step",
    "foh_matrices", "run_offline", "build_dob", "dob_continuous", "q_filter", "build_eso", "eso_gains", "build_kalman",
    "noise_level", "build_paper", "build_paper_k0", "paper_dominant_pole", "with_lowpass", "ESTIMATORS",
    "EstimatorInfo", "FIRST_BASELINE_CODE", "build", "estimator_names", "RULES", "friction_noise_rms", "reference_estimator",
    "reference_noise_rms", "tune", "velocity_noise_rms",
]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'MAX_STATES': '.base',
    'DiscreteEstimator': '.base',
    'discretize_observer': '.base',
    'estimator_output': '.base',
    'estimator_step': '.base',
    'foh_matrices': '.base',
    'run_offline': '.base',
    'build_dob': '.dob',
    'dob_continuous': '.dob',
    'q_filter': '.dob',
    'build_eso': '.eso',
    'eso_gains': '.eso',
    'build_kalman': '.kalman',
    'noise_level': '.kalman',
    'build_paper': '.paper',
    'build_paper_k0': '.paper',
    'paper_dominant_pole': '.paper',
    'with_lowpass': '.paper',
    'ESTIMATORS': '.registry',
    'EstimatorInfo': '.registry',
    'FIRST_BASELINE_CODE': '.registry',
    'build': '.registry',
    'estimator_names': '.registry',
    'RULES': '.registry',
    'friction_noise_rms': '.tuning',
    'reference_estimator': '.tuning',
    'reference_noise_rms': '.tuning',
    'tune': '.tuning',
    'velocity_noise_rms': '.tuning',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
