"""Registries of the sampled controller's choices: name -> integer code of the kernels, parameters, docs.

The numba kernels branch on small integers; everything above them (the API, the
command line's choices, the docs and the report) names the choices. Each kind of choice
is one :class:`~obsdesign._registry.Registry`, written once: :data:`CONTROLLERS`,
:data:`SCHEDULES` and :data:`PLANTS` here, :data:`ESTIMATORS` in its own room
(:mod:`obsdesign.estimators.registry`, the same object), the compensation modes with their
section (:data:`obsdesign.compensation.COMPENSATION_MODES`), the plant friction models in
:data:`obsdesign.friction.FRICTION_MODELS`. Every code is a plain ``int`` a numba module
can read at import time, e.g. ``SCHEDULES.code("true")``.

Examples
--------
>>> ESTIMATORS.names()
('paper', 'paper-k0', 'eso', 'kalman', 'dob')
>>> SCHEDULES.code("true")
1
>>> SCHEDULES.code("guess")
Traceback (most recent call last):
...
ValueError: stiffness: expected one of estimated, true, constant, estimated-raw, found 'guess'
"""

from __future__ import annotations

from .._registry import Entry, Registry
from ..estimators.registry import ESTIMATORS

__all__ = ["Entry", "Registry", "ESTIMATORS", "SCHEDULES", "CONTROLLERS", "PLANTS"]

#: Stiffness schedules of the paper's observer.
SCHEDULES = Registry("stiffness", [
    Entry("estimated", 0, "pre-sliding branch driven by the measured displacement; a reversal is accepted once "
          "the displacement has come back from its extreme by more than 4 noise RMS (sensor.noise_rms)"),
    Entry("true", 1, "the simulated plant's stiffness (for analysis)"),
    Entry("constant", 2, "kappa always"),
    Entry("estimated-raw", 3, "pre-sliding branch with reversals at every sign change of v_hat (no hysteresis; "
          "the paper's reproductions)"),
])

#: Controllers of the loop.
CONTROLLERS = Registry("controller", [
    Entry("open-loop", 0, "the scenario's force, no feedback"),
    Entry("pid", 1, "parallel PID eq:PIDparallel with filtered derivative and conditional integration"),
    Entry("pid+observer", 2, "the PID plus the filtered friction estimate as compensation"),
])

#: Plant structures.
PLANTS = Registry("plant", [
    Entry("physical", 0, "the plant friction model (Coulomb with pre-sliding memory, viscous, optional lag)"),
    Entry("model", 1, "the 3-state LTV model eq:3:1 of the observer's variant"),
])
