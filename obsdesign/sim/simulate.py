"""Simulation: :func:`run` the closed loop of :func:`obsdesign.loop.prepare` in the numba kernel and score it.

The loop (the sampled controller, the simulated plant, the drive's delay, the sensor and the reference) is
built once, by :func:`obsdesign.loop.prepare` (:class:`obsdesign.loop.LoopInputs`); this module runs it
(:func:`run_kernel`: :func:`obsdesign.sim.kernel.run_loop`) and summarises it (:func:`loop_result`).
``simulate(cfg, scenario, ...)`` is ``run(prepare(cfg, scenario, ...))``. Splitting the two lets a caller
inspect or edit the sampled inputs (a measured force sequence, a reference of their own) before the run,
and lets benchmarks time the kernel apart from the set-up.

Examples
--------
>>> import dataclasses, numpy as np
>>> import obsdesign as od
>>> from obsdesign.sim import prepare, run
>>> loop = prepare(od.load_preset("vcm"), "constant", duration=0.5)
>>> loop.n_samples, loop.controller
(5000, 'open-loop')
>>> res = run(dataclasses.replace(loop, u_open=np.full(5000, 2.0)), keep_trace=False)
>>> res.metrics["diverged"]
False
>>> res = od.simulate(od.load_preset("vcm"), "positioning", controller="pid+observer", duration=4.0)
>>> res.metrics["diverged"], len(res.metrics["settling_time"])
(False, 2)
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..loop.bands import force_bound
from ..loop.inputs import LoopInputs, prepare
from ..loop.numerics import step_is_stable
from ..params import Config
from ..sampled.controller import REVERSAL_NOISE_FACTOR
from . import kernel
from .metrics import loop_metrics
from .result import SimResult

__all__ = ["REVERSAL_NOISE_FACTOR", "run", "simulate", "loop_result", "run_kernel"]


def run(loop: LoopInputs, keep_trace: bool = True) -> SimResult:
    """Run the closed loop of :func:`prepare`'s inputs and summarise it.

    Parameters
    ----------
    loop : LoopInputs
    keep_trace : bool
        False returns the metrics only (no per-sample arrays).

    Returns
    -------
    SimResult
    """
    if not isinstance(loop, LoopInputs):
        raise TypeError(f"loop: expected LoopInputs (from obsdesign.sim.prepare), found {type(loop).__name__}")
    out, n_written, wall = run_kernel(loop)
    return loop_result(loop, out, n_written, wall, keep_trace=keep_trace)


def run_kernel(loop: LoopInputs) -> tuple[dict[str, np.ndarray], int, float]:
    """The kernel :func:`obsdesign.sim.kernel.run_loop` over ``loop``: its arrays, the samples it wrote and
    its wall time [s] (what :func:`loop_result` summarises).

    Parameters
    ----------
    loop : LoopInputs
    """
    outputs = kernel.Outputs(*(np.empty(loop.n_samples) for _ in kernel.OUTPUT_NAMES))
    args = loop.kernel_args()
    t0 = time.perf_counter()
    n_written = kernel.run_loop(*args, outputs)
    return outputs._asdict(), n_written, time.perf_counter() - t0


def loop_result(loop: LoopInputs, out: dict[str, np.ndarray], n_written: int, wall: float, *,
                keep_trace: bool = True) -> SimResult:
    """The result of a run of ``loop`` from the arrays the kernel wrote (what :func:`run` returns).

    Parameters
    ----------
    loop : LoopInputs
        The run's inputs.
    out : dict of ndarray
        :data:`obsdesign.sim.kernel.OUTPUT_NAMES` -> the kernel's arrays (NaN is written past ``n_written``).
    n_written : int
        Samples written (fewer than ``loop.n_samples`` after a divergence).
    wall : float
        Wall time of the kernel [s] (the metric ``sim_wall_s``).
    keep_trace : bool
        False returns the metrics only.

    Returns
    -------
    SimResult
    """
    n = loop.n_samples
    if n_written < n:
        for arr in out.values():
            arr[n_written:] = np.nan
    e = loop.x_ref - out["x"]
    fr = loop.config.friction
    stable_step = step_is_stable(dt=loop.dt, n_sub=loop.n_sub, m=loop.m, sigma=fr.sigma, kappa=fr.kappa,
                                 beta=fr.beta if fr.beta is not None else 0.0,
                                 model_lag=loop.mode == kernel.PLANT_MODEL and loop.lag_model)
    metrics = loop_metrics(loop.scenario, out, e, n_written, loop.settle_tol, wall, step_stable=stable_step,
                           settle_rule=loop.settle_rule, force_bound=force_bound(loop.plant_config or loop.config),
                           span=float(np.max(loop.x_ref) - np.min(loop.x_ref)) if n else 0.0)
    traces = {}
    if keep_trace:
        traces = dict(out, t=np.arange(n) * loop.dt, x_ref=loop.x_ref, e=e)
    return SimResult(scenario=loop.scenario.name, controller=loop.controller, plant=loop.plant,
                     stiffness_schedule=loop.stiffness, estimator=loop.estimator, config=loop.config,
                     metrics=metrics, **traces)


def simulate(cfg: Config, scenario: Any, *, keep_trace: bool = True, **options: Any) -> SimResult:
    """Simulate plant, sensor, observer, filter and controller at the sampling rate.

    ``simulate(cfg, scenario, **options)`` is ``run(prepare(cfg, scenario, **options))``.

    Parameters
    ----------
    cfg : Config
        The design; change parameters with :meth:`obsdesign.Config.override`.
    scenario : str or scenario spec
        See :func:`prepare`.
    keep_trace : bool
        False returns the metrics only.
    **options
        The keyword options of :func:`prepare` (controller, stiffness, plant, estimator,
        duration, seed, settle_tol, initial_estimate, substeps).

    Returns
    -------
    SimResult
    """
    return run(prepare(cfg, scenario, **options), keep_trace=keep_trace)

