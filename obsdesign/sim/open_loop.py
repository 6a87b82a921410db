"""Open-loop runs that share their plant: the plant simulated once, every estimator over its measurement.

In open loop the command is the scenario's force (``u_open / K``, with the load feed-forward, the
saturation and the computation delay): no estimate reaches the plant. Runs that differ only in their
estimator (the comparison's ``excitation`` rows, a sweep of observer designs on one plant) therefore
simulate the same plant, the same sensor noise and the same measurement. :func:`run_shared` simulates
it once, with the first run's estimator in the loop, and runs every other estimator over that run's
measurement and net force with :func:`obsdesign.sampled.kernel.observe_loop`, the same estimator step
the closed loop calls. Each result is the one :func:`obsdesign.sim.run` returns for its inputs, array
for array and bit for bit (``tests/test_open_loop.py``), including the early stop of a run whose
estimate diverges; runs that do not share a plant are simply run.

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

import time
from collections.abc import Sequence

import numpy as np

from ..sampled.choices import CONTROLLERS, SCHEDULES
from ..sampled.kernel import observe_loop
from . import kernel
from .result import SimResult
from .simulate import LoopInputs, loop_result, run, run_kernel

__all__ = ["run_shared", "shares_plant"]

#: The outputs of :func:`obsdesign.sim.kernel.run_loop` that the plant and the sensor write.
PLANT_OUTPUTS = ("x", "x_meas", "v", "f", "u")
#: The controller's fields an open-loop command reads (:func:`obsdesign.sampled.kernel.controller_sample`,
#: :func:`obsdesign.sampled.kernel.delay_buffer`).
_OPEN_LOOP_FIELDS = ("controller", "K", "G", "u_max", "delay", "delay_init")
_OPEN = CONTROLLERS.code("open-loop")
_TRUE = SCHEDULES.code("true")


def _standalone(loop: LoopInputs) -> bool:
    """Whether the plant of ``loop`` depends on its estimator (so it cannot be shared)."""
    obs, _, ctrl = loop.sampled.kernel_args()
    # The estimator is fed the net force ``K command - G`` of the controller's K and G, the plant's
    # output u is that of its own: the two agree only where the plant's gain and load are the design's.
    return (ctrl.controller != _OPEN or obs.schedule == _TRUE
            or loop.K_plant != ctrl.K or loop.G_plant != ctrl.G)


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
    if _standalone(a) or _standalone(b):
        return False
    pa, sa = a.kernel_args()[3:]
    pb, sb = b.kernel_args()[3:]
    ca, cb = a.sampled.kernel_args()[2], b.sampled.kernel_args()[2]
    return (a.dt == b.dt and a.n_samples == b.n_samples
            and all(getattr(ca, name) == getattr(cb, name) for name in _OPEN_LOOP_FIELDS)
            and all(_equal(x, y) for x, y in zip(pa, pb))
            and all(_equal(getattr(sa, name), getattr(sb, name)) for name in ("u_open", "noise", "quantization")))


def _equal(x, y) -> bool:
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        return np.array_equal(x, y)
    return bool(x == y)


def _observed(leader: dict[str, np.ndarray], loop: LoopInputs, keep_trace: bool) -> SimResult:
    """``run(loop)`` from the shared plant's outputs ``leader`` (a run that did not diverge)."""
    obs, est, _ = loop.sampled.kernel_args()
    n = loop.n_samples
    out = {name: leader[name].copy() for name in PLANT_OUTPUTS}
    vh, fh, ff, k = (np.empty(n) for _ in range(4))
    t0 = time.perf_counter()
    observe_loop(obs, est, out["x_meas"], out["u"], np.zeros(n), vh, fh, ff, k)
    wall = time.perf_counter() - t0
    out.update(v_hat=vh, f_hat=fh, f_hat_filtered=ff, stiffness=k)
    # the closed loop's stop rule (run_loop): the first sample whose estimate is not below the bound
    # ends the run after it is recorded (the plant's x and v stayed below theirs: the leader ran through)
    bound = kernel.DIVERGED_F
    ok = (np.abs(fh) < bound) & (np.abs(vh) < bound) & (np.abs(ff) < bound)
    n_written = n if ok.all() else int(np.argmin(ok)) + 1
    return loop_result(loop, {name: out[name] for name in kernel.OUTPUT_NAMES}, n_written, wall,
                       keep_trace=keep_trace)


def run_shared(loops: Sequence[LoopInputs], *, keep_trace: bool = True) -> list[SimResult]:
    """``[run(loop) for loop in loops]``, with the plant of open-loop runs that share it simulated once.

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
    A run leads a group of runs that share its plant (:func:`shares_plant`) and is run in the loop; the
    others are its estimator-only replays. Where the leader diverged (its run stopped early), the others
    are run in the loop too. Runs with the ``true`` stiffness schedule (it reads the plant's state) and
    closed-loop runs always run in the loop.
    """
    loops = list(loops)
    for i, loop in enumerate(loops):
        if not isinstance(loop, LoopInputs):
            raise TypeError(f"loops[{i}]: expected LoopInputs (from obsdesign.sim.prepare), found "
                            f"{type(loop).__name__}")
    results: list[SimResult | None] = [None] * len(loops)
    groups: list[list[int]] = []
    for i, loop in enumerate(loops):
        for group in groups:
            if shares_plant(loops[group[0]], loop):
                group.append(i)
                break
        else:
            groups.append([i])
    for first, *others in groups:
        if not others:
            results[first] = run(loops[first], keep_trace=keep_trace)
            continue
        lead = loops[first]
        leader, n_written, wall = run_kernel(lead)
        results[first] = loop_result(lead, leader, n_written, wall, keep_trace=keep_trace)
        diverged = n_written < lead.n_samples
        for i in others:
            results[i] = (run(loops[i], keep_trace=keep_trace) if diverged
                          else _observed(leader, loops[i], keep_trace))
    return results  # type: ignore[return-value]
