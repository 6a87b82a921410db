"""Measured data: traces from CSV and MATLAB files, identification of the plant and friction.

``load_trace`` reads a displacement/force record and checks it; ``identify`` fits the
inverse dynamic model (mass, viscous and Coulomb friction, offset) and, where the data
resolve it, the pre-sliding factor ``s``; ``Identification.to_config`` turns the result
into a complete design config; ``observe`` runs the designed observer over a trace; ``refine`` fits dynamic
friction by output error; ``design_experiment`` plans a record that makes them identifiable. See
``docs/measured-data.md`` and ``docs/experiment.md``.
"""

from __future__ import annotations

from .._lazy import keep_functions, lazy_names


__all__ = ["Trace", "load_trace", "Identification", "identify", "config_from", "Observation", "observe",
           "model_friction_state", "refine", "Refinement", "design_experiment", "Experiment"]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'Identification': '.identify',
    'identify': '.identify',
    'config_from': '.rules',
    'Trace': '.trace',
    'load_trace': '.trace',
    'Observation': '.observe',
    'observe': '.observe',
    'model_friction_state': '.observe',
    'refine': '.output_error',
    'Refinement': '.output_error',
    'design_experiment': '.experiment',
    'Experiment': '.experiment',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
keep_functions(__name__, ('identify', 'observe'))
