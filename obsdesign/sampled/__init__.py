"""The sampled controller as it runs: one definition for the simulator, measured data and the exports.

:mod:`obsdesign.sampled.choices` names the choices (controller, stiffness schedule, plant,
estimator) with the integer codes the numba kernels branch on.
"""
