"""Runs that share their work: identical runs made once, open-loop plants simulated once.

Two kinds of runs of a batch repeat work that :func:`run_shared` does once:

* **Identical runs.** The kernel is deterministic: runs whose inputs are equal, every float by its bits
  (:func:`same_run`: the controller, the plant, the reference, the force and the sensor noise), write
  the same arrays. A comparison's seeds of a closed-loop scenario on an axis without random sensor
  noise (the ``vcm`` preset: quantization only) are such runs; the circle test of the report already
  runs one seed there for the same reason. The run is made once and each of the others gets its own
  copy of the arrays and its own metrics.
* **Open-loop runs that share their plant.** In open loop the command is the scenario's force
  (``u_open / K``, with the load feed-forward, the saturation and the computation delay): no estimate
  reaches the plant. Runs that differ only in their estimator (the comparison's ``excitation`` rows, a
  sweep of observer designs on one plant) simulate the same plant, the same sensor noise and the same
  measurement (:func:`shares_plant`). The plant is simulated once, with the first run's estimator in the
  loop, and every other estimator runs over that run's measurement and net force with
  :func:`obsdesign.sampled.kernel.observe_loop`, the same estimator step the closed loop calls.

Each result is the one :func:`obsdesign.sim.run` returns for its inputs, array for array and bit for bit
(``tests/test_shared_runs.py``), including the early stop of a run whose estimate diverges; runs that
share nothing are simply run.

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.sim import prepare, run
>>> cfg = od.load_preset("vcm")
>>> loops = [prepare(cfg, "excitation", estimator=e, duration=0.5, seed=3) for e in ("paper", "paper-k0")]
>>> shared = run_shared(loops)
>>> alone = [run(loop) for loop in loops]
>>> all((a.f_hat == b.f_hat).all() and (a.x == b.x).all() for a, b in zip(shared, alone))
True
"""

from __future__ import annotations

import struct
import time
from collections.abc import Sequence

import numpy as np

from ..sampled.choices import CONTROLLERS, SCHEDULES
from ..sampled.kernel import observe_loop
from . import kernel
from .result import SimResult
from ..loop.inputs import LoopInputs
from .simulate import loop_result, run_kernel

__all__ = ["run_shared", "shares_plant", "same_run"]

#: The outputs of :func:`obsdesign.sim.kernel.run_loop` that the plant and the sensor write.
PLANT_OUTPUTS = ("x", "x_meas", "v", "f", "u")
#: The controller's fields an open-loop command reads (:func:`obsdesign.sampled.kernel.controller_sample`;
#: the drive's delay is the plant's, :class:`obsdesign.sim.kernel.PlantArgs`).
_OPEN_LOOP_FIELDS = ("controller", "K", "G", "u_max")
_OPEN = CONTROLLERS.code("open-loop")
_TRUE = SCHEDULES.code("true")


def _keys(loop: LoopInputs) -> tuple[tuple, tuple | None]:
    """What a run reads (its kernel's inputs and the metrics' bookkeeping), and what its open-loop plant
    reads (``None`` where the plant depends on the estimator, so it cannot be shared); compared by
    :func:`_same_bits`. The kernel's inputs are built once per run here."""
    obs, est, ctrl, plant, signals = args = loop.kernel_args()
    sc, fr = loop.scenario, loop.config.friction
    run = (loop.n_samples, sc.spec, sc.dt, sc.duration, tuple(sc.steps), tuple(sc.holds), loop.settle_tol,
           fr.sigma, fr.kappa, fr.beta, tuple(args))
    # The estimator is fed the net force ``K command - G`` of the controller's K and G, the plant's output
    # u is that of its own: the two agree only where the plant's gain and load are the design's.
    if (ctrl.controller != _OPEN or obs.schedule == _TRUE
            or loop.K_plant != ctrl.K or loop.G_plant != ctrl.G):
        return run, None
    return run, (loop.dt, loop.n_samples, tuple(plant), signals.u_open, signals.noise, signals.quantization,
                 tuple(getattr(ctrl, name) for name in _OPEN_LOOP_FIELDS))


def shares_plant(a: LoopInputs, b: LoopInputs) -> bool:
    """Whether two runs simulate the same open-loop plant (equal plant, signals, sampling and command).

    Parameters
    ----------
    a, b : LoopInputs
        Inputs of :func:`obsdesign.sim.prepare`.

    Examples
    --------
    >>> import obsdesign as od
    >>> from obsdesign.sim import prepare
    >>> cfg = od.load_preset("vcm")
    >>> shares_plant(prepare(cfg, "excitation", estimator="eso", duration=0.1),
    ...              prepare(cfg, "excitation", estimator="kalman", duration=0.1))
    True
    >>> shares_plant(prepare(cfg, "excitation", duration=0.1), prepare(cfg, "excitation", duration=0.1, seed=1))
    False
    """
    return _same_plant(_keys(a)[1], _keys(b)[1])


def _same_plant(pa: tuple | None, pb: tuple | None) -> bool:
    """Whether two plant keys of :func:`_keys` are one shareable plant."""
    return pa is not None and pb is not None and _same_bits(pa, pb)


def _same_bits(x, y) -> bool:
    """Equal to the bit: floats by their representation (``-0.0`` is not ``0.0``, NaN equals itself),
    arrays by dtype, shape and bytes, tuples (the kernel's argument groups) item by item; ``None`` and
    other values (a scenario's spec) by ``==``."""
    if isinstance(x, tuple) or isinstance(y, tuple):
        return (isinstance(x, tuple) and isinstance(y, tuple) and len(x) == len(y)
                and all(_same_bits(a, b) for a, b in zip(x, y)))
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        return (isinstance(x, np.ndarray) and isinstance(y, np.ndarray) and x.dtype == y.dtype
                and x.shape == y.shape and x.tobytes() == y.tobytes())
    if isinstance(x, float) or isinstance(y, float):
        return type(x) is type(y) and struct.pack("<d", x) == struct.pack("<d", y)
    return type(x) is type(y) and x == y


def same_run(a: LoopInputs, b: LoopInputs) -> bool:
    """Whether two runs are the same run: every input of the kernel equal to the bit, and the same
    scenario, settling band and plant bookkeeping for the metrics (the kernel is deterministic).

    Parameters
    ----------
    a, b : LoopInputs
        Inputs of :func:`obsdesign.sim.prepare`.

    Examples
    --------
    >>> import obsdesign as od
    >>> from obsdesign.sim import prepare
    >>> cfg = od.load_preset("vcm")   # quantization, no random noise: the seed changes nothing here
    >>> same_run(prepare(cfg, "positioning", seed=0), prepare(cfg, "positioning", seed=1))
    True
    >>> noisy = cfg.override(noise_rms=1e-7)
    >>> same_run(prepare(noisy, "positioning", seed=0), prepare(noisy, "positioning", seed=1))
    False
    """
    return _same_bits(_keys(a)[0], _keys(b)[0])


def _observed(leader: dict[str, np.ndarray], loop: LoopInputs) -> tuple[dict[str, np.ndarray], int, float]:
    """What :func:`obsdesign.sim.simulate.run_kernel` returns for ``loop``, from the shared plant's arrays
    ``leader`` (a run that did not diverge): its plant arrays and this estimator over its measurement."""
    obs, est, _ = loop.sampled.kernel_args()
    n = loop.n_samples
    out = {name: leader[name].copy() for name in PLANT_OUTPUTS}
    vh, fh, ff, k = (np.empty(n) for _ in range(4))
    t0 = time.perf_counter()
    # the estimator is fed the force the plant felt (with the drive's delay, the delayed command: the controller
    # keeps its last d commands), K applied - G with the design's K and G, which _keys requires the plant's to be
    observe_loop(obs, est, out["x_meas"], out["u"], np.zeros(n), vh, fh, ff, k)
    wall = time.perf_counter() - t0
    out.update(v_hat=vh, f_hat=fh, f_hat_filtered=ff, stiffness=k)
    # the closed loop's stop rule (run_loop): the first sample whose estimate is not below the bound
    # ends the run after it is recorded (the plant's x and v stayed below theirs: the leader ran through)
    bound = kernel.DIVERGED_F
    ok = (np.abs(fh) < bound) & (np.abs(vh) < bound) & (np.abs(ff) < bound)
    n_written = n if ok.all() else int(np.argmin(ok)) + 1
    return {name: out[name] for name in kernel.OUTPUT_NAMES}, n_written, wall


def _groups(indices: list[int], together) -> list[list[int]]:
    """``indices`` in groups whose members are ``together`` with the group's first, in order."""
    groups: list[list[int]] = []
    for i in indices:
        for group in groups:
            if together(group[0], i):
                group.append(i)
                break
        else:
            groups.append([i])
    return groups


def run_shared(loops: Sequence[LoopInputs], *, keep_trace: bool = True) -> list[SimResult]:
    """``[run(loop) for loop in loops]``, with identical runs made once and the plant of open-loop runs
    that share it simulated once.

    Parameters
    ----------
    loops : sequence of LoopInputs
        Inputs of :func:`obsdesign.sim.prepare`, in any order and mix.
    keep_trace : bool
        False returns the metrics only.

    Returns
    -------
    list of SimResult
        In the order of ``loops``; each equal to ``run(loop)``.

    Notes
    -----
    Runs equal to an earlier one (:func:`same_run`) get copies of its arrays. Of the others, a run leads
    a group of runs that share its plant (:func:`shares_plant`) and is run in the loop; the others are
    its estimator-only replays. Where the leader diverged (its run stopped early), the others are run in
    the loop too. Runs with the ``true`` stiffness schedule (it reads the plant's state) and closed-loop
    runs that are not repeats run in the loop.
    """
    loops = list(loops)
    for i, loop in enumerate(loops):
        if not isinstance(loop, LoopInputs):
            raise TypeError(f"loops[{i}]: expected LoopInputs (from obsdesign.sim.prepare), found "
                            f"{type(loop).__name__}")
    keys = [_keys(loop) for loop in loops]
    same = _groups(list(range(len(loops))), lambda i, j: _same_bits(keys[i][0], keys[j][0]))
    kernel_out: dict[int, tuple[dict[str, np.ndarray], int, float]] = {}
    for first, *others in _groups([g[0] for g in same], lambda i, j: _same_plant(keys[i][1], keys[j][1])):
        leader, n_written, wall = run_kernel(loops[first])
        kernel_out[first] = leader, n_written, wall
        diverged = n_written < loops[first].n_samples
        for i in others:
            kernel_out[i] = run_kernel(loops[i]) if diverged else _observed(leader, loops[i])
    results: list[SimResult] = [None] * len(loops)  # type: ignore[list-item]
    for first, *copies in same:
        out, n_written, wall = kernel_out[first]
        for i in copies:  # the same arrays, each result its own
            results[i] = loop_result(loops[i], {k: v.copy() for k, v in out.items()}, n_written, wall,
                                     keep_trace=keep_trace)
        results[first] = loop_result(loops[first], out, n_written, wall, keep_trace=keep_trace)
    return results
