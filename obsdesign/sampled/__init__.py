"""The sampled controller as it runs: one definition for the simulator, measured data and the exports.

* :mod:`obsdesign.sampled.choices`: the choices (controller, stiffness schedule, plant, estimator)
  with the integer codes the numba kernels branch on;
* :mod:`obsdesign.sampled.controller`: :func:`sampled_controller` builds the frozen
  :class:`SampledController` (observer or baseline estimator, schedule with its reversal hysteresis,
  low-pass, PID with its derivative filter, compensation) from a config;
* :mod:`obsdesign.sampled.kernel`: its per-sample step (numba), shared by the closed-loop simulator
  and by :func:`obsdesign.data.observe`.
"""

from .._lazy import lazy_names

__all__ = ["SampledController", "sampled_controller", "REVERSAL_NOISE_FACTOR", "CONTROLLERS", "SCHEDULES",
           "ESTIMATORS", "PLANTS"]

_LAZY = {
    "SampledController": ".controller",
    "sampled_controller": ".controller",
    "REVERSAL_NOISE_FACTOR": ".controller",
    "CONTROLLERS": ".choices",
    "SCHEDULES": ".choices",
    "ESTIMATORS": ".choices",
    "PLANTS": ".choices",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
