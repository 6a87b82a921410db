"""Plant friction models (numba kernels), chosen by name.

* :mod:`~obsdesign.friction.presliding`: the paper's Coulomb friction with pre-sliding
  memory (eq:2:3:1-2:3:5), code :data:`PAPER` (``paper``), run by the simulator's own plant step;
* ``lugre``, ``dahl``, ``gms`` (+ asymmetric levels and an offset): flat parameter and state
  arrays, dispatched on an integer code (:mod:`~obsdesign.friction.kernels`); the registry
  (:mod:`~obsdesign.friction.registry`) turns named parameters into those arrays.
  See docs/friction-models.md.
"""

from __future__ import annotations

from .._lazy import lazy_names

__all__ = [
    "PAPER", "LUGRE", "DAHL", "GMS", "FRICTION_MODELS", "FrictionModelInfo", "ParameterSpec",
    "friction_code", "friction_n_state", "friction_init", "friction_force", "friction_advance",
    "friction_viscous", "friction_stiffness", "friction_plant_step", "stribeck", "simulate_block", "drive_displacement",
    "coulomb", "coulomb_along", "coulomb_normalized", "presliding_shape", "stiffness", "track_reversal",
]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'drive_displacement': '.driver',
    'simulate_block': '.driver',
    'friction_advance': '.kernels',
    'friction_force': '.kernels',
    'friction_init': '.kernels',
    'friction_n_state': '.kernels',
    'friction_plant_step': '.kernels',
    'friction_stiffness': '.kernels',
    'friction_viscous': '.kernels',
    'stribeck': '.kernels',
    'coulomb': '.presliding',
    'coulomb_along': '.presliding',
    'coulomb_normalized': '.presliding',
    'presliding_shape': '.presliding',
    'stiffness': '.presliding',
    'track_reversal': '.presliding',
    'DAHL': '.registry',
    'FRICTION_MODELS': '.registry',
    'FrictionModelInfo': '.registry',
    'GMS': '.registry',
    'LUGRE': '.registry',
    'PAPER': '.registry',
    'ParameterSpec': '.registry',
    'friction_code': '.registry',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
