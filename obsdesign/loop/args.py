"""The kernel's argument groups of the loop around the sampled controller: the plant and the signals.

The sampled controller's own groups (``ObserverArgs``, ``EstimatorArgs``, ``ControllerArgs``) are
built by :meth:`obsdesign.sampled.SampledController.kernel_args`; the loop adds :class:`PlantArgs` (the
simulated plant and the drive's delay) and :class:`Signals` (reference and sensor), built by
:meth:`obsdesign.loop.LoopInputs.kernel_args` and read by :func:`obsdesign.sim.kernel.run_loop` and
:func:`obsdesign.sim.external.run_external`. Plain named tuples (numba reads them as records).

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.loop import prepare
>>> plant, signals = prepare(od.load_preset("vcm").override(delay_samples=2), "positioning").kernel_args()[3:]
>>> plant.delay, round(plant.delay_init, 4), signals.quantization    # G / K = 5.27 / 3.28 V; 1 um encoder
(2, 1.6067, 1e-06)
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["PlantArgs", "Signals"]


class PlantArgs(NamedTuple):
    """The simulated plant of :func:`obsdesign.sim.kernel.run_loop`.

    Attributes
    ----------
    n_sub : int
        Heun substeps per sample.
    mode : int
        Plant structure code (:data:`obsdesign.sampled.choices.PLANTS`).
    lag_model : bool
        Whether the observer's variant is ``lag`` (what the estimated state w3 contains).
    m, K, G : float
        Mass [kg], actuator gain [N/V] and load force [N] of the plant.
    friction_code : int
        Plant friction model (:data:`obsdesign.friction.FRICTION_MODELS` code).
    plant_params : ndarray
        Its parameters (paper: the ``PP_*`` layout; others: :meth:`~obsdesign.friction.FrictionModelInfo.pack`).
    delay : int
        The drive's delay [samples] between the sampled position and the applied command
        (``[hardware] delay_samples``): the command computed at sample ``n`` acts from ``n + delay``.
    delay_init : float
        The command [V] the drive applies before the first computed one arrives: the design's saturated
        feed-forward ``G / K``.
    """

    n_sub: int
    mode: int
    lag_model: bool
    m: float
    K: float
    G: float
    friction_code: int
    plant_params: np.ndarray
    delay: int
    delay_init: float


class Signals(NamedTuple):
    """The sampled inputs of :func:`obsdesign.sim.kernel.run_loop`: reference [m], open-loop force [N], sensor noise [m],
    encoder resolution [m] (0: none), reference velocity [m/s] and feed-forward weight
    (:func:`obsdesign.sampled.reference.reference_feedforward`).

    Attributes
    ----------
    x_ref, u_open, noise : ndarray
    quantization : float
    v_ref, w_ff : ndarray
    """

    x_ref: np.ndarray
    u_open: np.ndarray
    noise: np.ndarray
    quantization: float
    v_ref: np.ndarray
    w_ff: np.ndarray
