"""Time-varying nonlinear simulation of plant, friction, observer and controller (numba).

Two public steps, :func:`prepare` (the closed loop of a run, built in :mod:`obsdesign.loop`;
re-exported here) and :func:`run` (the numba kernel and the metrics); :func:`simulate` is both in one call; :func:`run_shared` runs
runs that share their work (:mod:`obsdesign.sim.shared`). :func:`simulate_circle`
runs the two-axis circle (ballbar) test (:mod:`obsdesign.sim.circle`).
"""

from .._lazy import keep_functions, lazy_names


__all__ = ["CONTROLLERS", "ESTIMATORS", "PLANTS", "SCHEDULES", "COLUMNS", "SimResult",
           "SCENARIOS", "Chirp", "ConstantForce", "Excitation", "Positioning", "band_limited_noise",
           "LoopInputs", "prepare", "run", "run_shared", "simulate", "simulate_circle", "CircleResult"]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'CONTROLLERS': '..sampled.choices',
    'ESTIMATORS': '..sampled.choices',
    'PLANTS': '..sampled.choices',
    'SCHEDULES': '..sampled.choices',
    'COLUMNS': '.result',
    'SimResult': '.result',
    'SCENARIOS': '..loop.scenarios',
    'Chirp': '..loop.scenarios',
    'ConstantForce': '..loop.scenarios',
    'Excitation': '..loop.scenarios',
    'Positioning': '..loop.scenarios',
    'band_limited_noise': '..loop.scenarios',
    'LoopInputs': '..loop.inputs',
    'prepare': '..loop.inputs',
    'run': '.simulate',
    'simulate': '.simulate',
    'run_shared': '.shared',
    'simulate_circle': '.circle',
    'CircleResult': '.circle',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
keep_functions(__name__, ('simulate',))
