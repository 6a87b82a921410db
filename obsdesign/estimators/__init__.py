"""Estimators of velocity and friction by registry, with a fair tuning rule.

Every estimator is a :class:`DiscreteEstimator` in one discrete form, run per sample by
:func:`estimator_step` (numba). ``ESTIMATORS`` maps names to codes, knobs and builders;
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

from .base import MAX_STATES as MAX_STATES
from .base import DiscreteEstimator as DiscreteEstimator
from .base import discretize_observer as discretize_observer
from .base import estimator_output as estimator_output
from .base import estimator_step as estimator_step
from .base import foh_matrices as foh_matrices
from .base import run_offline as run_offline
from .dob import build_dob as build_dob
from .dob import dob_continuous as dob_continuous
from .dob import q_filter as q_filter
from .eso import build_eso as build_eso
from .eso import eso_gains as eso_gains
from .kalman import build_kalman as build_kalman
from .kalman import noise_level as noise_level
from .paper import build_paper as build_paper
from .paper import build_paper_k0 as build_paper_k0
from .paper import paper_dominant_pole as paper_dominant_pole
from .paper import with_lowpass as with_lowpass
from .registry import ESTIMATORS as ESTIMATORS
from .registry import EstimatorInfo as EstimatorInfo
from .registry import build as build
from .registry import estimator_names as estimator_names
from .tuning import RULES as RULES
from .tuning import friction_noise_rms as friction_noise_rms
from .tuning import reference_estimator as reference_estimator
from .tuning import reference_noise_rms as reference_noise_rms
from .tuning import tune as tune
from .tuning import velocity_noise_rms as velocity_noise_rms

__all__ = [
    "MAX_STATES", "DiscreteEstimator", "discretize_observer", "estimator_output", "estimator_step",
    "foh_matrices", "run_offline", "build_dob", "dob_continuous", "q_filter", "build_eso", "eso_gains", "build_kalman",
    "noise_level", "build_paper", "build_paper_k0", "paper_dominant_pole", "with_lowpass", "ESTIMATORS",
    "EstimatorInfo", "build", "estimator_names", "RULES", "friction_noise_rms", "reference_estimator",
    "reference_noise_rms", "tune", "velocity_noise_rms",
]
