"""The simulated plant around a controller of your own: an exported controller, or one in C via ctypes.

:func:`run_external` runs the plant, the sensor and the drive's delay of a run of :func:`obsdesign.sim.prepare`
(the same functions as :func:`obsdesign.sim.kernel.run_loop`: :func:`~obsdesign.sim.kernel.measure`, the delay
ring of :func:`~obsdesign.sim.kernel.delay_buffer`, :func:`~obsdesign.sim.kernel.plant_interval`) around a
Python callable ``step(x_ref, x_meas) -> command`` called once per sample. An exported controller
(``obsdesign export --what controller``) has no delay of its own: put in the plant of a config with
``[hardware] delay_samples = d``, it runs the loop that ``simulate`` runs, to the bit (tests/test_delay.py).
It is a Python loop (tens of microseconds a sample): for tests of a controller, not for sweeps.

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.sim import prepare
>>> from obsdesign.sim.external import run_external
>>> cfg = od.load_preset("vcm").override(delay_samples=1)
>>> loop = prepare(cfg, od.sim.Positioning(step_size=1e-3, step_up=0.01, step_down=0.19), duration=0.2)
>>> run = run_external(loop, lambda x_ref, x_meas: 5.27 / 3.28 + 2000.0 * (x_ref - x_meas))  # P control
>>> run.x.shape, round(float(run.x[1800]) * 1e3, 2)   # [mm] at 0.18 s: near the 1 mm step
((2000,), 1.01)
>>> bool(run.u[1] == 3.28 * run.command[0] - 5.27)   # the drive's delay: one sample
True
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from . import kernel
from ..loop.inputs import LoopInputs

__all__ = ["run_external", "ExternalRun"]


@dataclass(frozen=True)
class ExternalRun:
    """The records of :func:`run_external`, one value per sample (SI units).

    Attributes
    ----------
    x, x_meas, v : ndarray
        Position [m], its measurement and the velocity [m/s] at the sample.
    command : ndarray
        The command [V] the controller returned at the sample.
    u : ndarray
        The net force [N] the plant felt from the sample on: ``K_plant`` times the command of
        ``delay_samples`` samples earlier, less ``G_plant``.
    """

    x: np.ndarray = field(repr=False)
    x_meas: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    command: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)


@njit(cache=True, error_model="numpy")
def _interval(ps, u, fst, h, plant, sc):
    return kernel.plant_interval(ps, u, fst, h, plant, sc)


def run_external(loop: LoopInputs, step: Callable[..., float]) -> ExternalRun:
    """Run the simulated plant of ``loop`` around the controller ``step``.

    Parameters
    ----------
    loop : LoopInputs
        A run of :func:`obsdesign.sim.prepare`: its plant, sensor (noise, encoder), drive delay
        (``[hardware] delay_samples``) and reference; its own controller is not run.
    step : callable
        ``step(x_ref, x_meas)`` [m] returning the command [V] of the sample (``step(x_ref, x_meas,
        v_ref, w_ff)`` for the compensation modes ``feedforward`` and ``blend``, as the exported
        controller's step).

    Returns
    -------
    ExternalRun

    Raises
    ------
    TypeError
        ``loop`` is not a LoopInputs or ``step`` is not callable.
    """
    if not isinstance(loop, LoopInputs):
        raise TypeError(f"loop: expected LoopInputs (obsdesign.sim.prepare), found {type(loop).__name__}")
    if not callable(step):
        raise TypeError(f"step: expected a callable step(x_ref, x_meas) -> command, found {type(step).__name__}")
    obs, _, _, plant, sig = loop.kernel_args()
    extra = loop.sampled.compensation.mode != "observer" and loop.controller == "pid+observer"
    n = loop.n_samples
    rec = {name: np.empty(n) for name in ("x", "x_meas", "v", "command", "u")}
    h = obs.dt / plant.n_sub
    ps = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    fst = np.zeros(max(kernel.friction_n_state(plant.friction_code, plant.plant_params), 1))
    ubuf = list(kernel.delay_buffer(plant))
    sc = kernel.paper_scalars.py_func(plant)
    for i in range(n):
        xm = kernel.measure.py_func(ps[0], sig.noise[i], sig.quantization)
        args = (sig.x_ref[i], xm, sig.v_ref[i], sig.w_ff[i]) if extra else (sig.x_ref[i], xm)
        command = float(step(*map(float, args)))
        applied = command
        if plant.delay > 0:  # the drive's delay, as run_loop
            slot = i % plant.delay
            applied, ubuf[slot] = ubuf[slot], command
        u = plant.K * applied - plant.G
        rec["x"][i], rec["x_meas"][i], rec["v"][i], rec["command"][i], rec["u"][i] = ps[0], xm, ps[1], command, u
        ps = _interval(ps, u, fst, h, plant, sc)
    return ExternalRun(**rec)
