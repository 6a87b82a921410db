"""The closed loop as the hardware runs it: the one sampled controller, the plant, the drive's delay, the sensor, the reference.

Above :mod:`obsdesign.sampled` (the controller) and below :mod:`obsdesign.sim` (which runs the loop in its
numba kernel and scores it):

* :mod:`obsdesign.loop.inputs`: :func:`prepare` builds the frozen :class:`LoopInputs` from a config and a
  scenario, the one place the loop is assembled (``simulate``, ``tune``, the sweeps, the circle test, the
  comparison, the report's explorer and :func:`obsdesign.sim.external.run_external` all take it);
* :mod:`obsdesign.loop.args`: the kernel's plant and signal argument groups (``PlantArgs``, ``Signals``);
* :mod:`obsdesign.loop.plant`: the simulated plant's friction model as the kernel reads it;
* :mod:`obsdesign.loop.numerics`: how many Heun substeps the plant needs;
* :mod:`obsdesign.loop.scenarios`: the references and open-loop forces (and the sensor's band-limited noise);
* :mod:`obsdesign.loop.bands`: the settling band and runaway bounds, scaled to the sensor.

The frequency-domain views of the same loop stay in :mod:`obsdesign.design` (below the controller, which
designs from them): :func:`obsdesign.design.sampled_loop.sampled_loop` (the PID's design model) and
:func:`obsdesign.design.plant_loop.plant_loop` (the linearised simulated plant), both with the drive's delay.
"""

from .._lazy import lazy_names

__all__ = ["LoopInputs", "prepare", "plant_friction_arrays", "PlantArgs", "Signals", "SCENARIOS", "Scenario",
           "settle_band", "substeps_for"]

_LAZY = {
    "LoopInputs": ".inputs",
    "prepare": ".inputs",
    "plant_friction_arrays": ".plant",
    "PlantArgs": ".args",
    "Signals": ".args",
    "SCENARIOS": ".scenarios",
    "Scenario": ".scenarios",
    "settle_band": ".bands",
    "substeps_for": ".numerics",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
