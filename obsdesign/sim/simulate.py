"""Simulation in two public steps: :func:`prepare` the kernel's inputs, :func:`run` the kernel.

``simulate(cfg, scenario, ...)`` is ``run(prepare(cfg, scenario, ...))``. Splitting
the two lets a caller inspect or edit the sampled inputs (a measured force
sequence, a reference of their own) before the run, and lets benchmarks time the
kernel apart from the set-up.

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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import POSITIVE, check_integer
from ..estimators import DiscreteEstimator
from ..params import Config
from ..sampled.choices import PLANTS
from ..sampled.controller import REVERSAL_NOISE_FACTOR, SampledController, sampled_controller
from . import kernel
from .bands import force_bound, settle_band
from .metrics import loop_metrics
from .numerics import step_is_stable, substeps_for
from ..friction.registry import FRICTION_MODELS
from .result import SimResult
from .scenarios import Scenario, band_limited_noise, build_scenario, scenario_spec

__all__ = ["LoopInputs", "REVERSAL_NOISE_FACTOR", "prepare", "run", "simulate", "plant_friction_arrays", "loop_result", "run_kernel"]


@dataclass(frozen=True, eq=False)
class LoopInputs:
    """Everything one run needs: the sampled controller, the plant and the sampled signals, and
    what the result reports about them. Built by :func:`prepare`; edit with ``dataclasses.replace``.

    Attributes
    ----------
    config : Config
        The design.
    scenario : Scenario
        The sampled scenario.
    plant : str
        ``physical`` or ``model``.
    settle_tol : float or None
        Settling band [m] (None: an open-loop run).
    sampled : SampledController
        The controller that runs (:func:`obsdesign.sampled.sampled_controller`).
    n_sub : int
        Heun substeps of the plant per sample.
    mode : int
        Plant structure code.
    m, K_plant, G_plant : float
        The plant's mass [kg], actuator gain [N/V] and load [N].
    friction_code : int
        The plant friction model's code.
    plant_params : ndarray
        Its parameters (:func:`plant_friction_arrays`).
    x_ref, u_open, noise : ndarray
        Reference [m], open-loop force [N] and sensor noise [m] per sample.
    quantization : float
        Encoder resolution [m] (0: none).
    plant_config : Config or None
        The plant's own config under model mismatch.
    settle_rule : str
        Where the settling band comes from (:func:`obsdesign.sim.bands.settle_band`).
    """

    config: Config
    scenario: Scenario = field(repr=False)
    plant: str
    settle_tol: float | None
    sampled: SampledController = field(repr=False)
    n_sub: int
    mode: int
    m: float
    K_plant: float
    G_plant: float
    friction_code: int
    plant_params: np.ndarray = field(repr=False)
    x_ref: np.ndarray = field(repr=False)
    u_open: np.ndarray = field(repr=False)
    noise: np.ndarray = field(repr=False)
    quantization: float
    plant_config: Config | None = field(repr=False, default=None)
    settle_rule: str = "given"

    @property
    def n_samples(self) -> int:
        """Number of samples of the run."""
        return len(self.x_ref)

    @property
    def dt(self) -> float:
        """Sample time [s]."""
        return self.sampled.dt

    @property
    def controller(self) -> str:
        """The controller's name."""
        return self.sampled.controller

    @property
    def stiffness(self) -> str:
        """The stiffness schedule's name."""
        return self.sampled.schedule

    @property
    def estimator(self) -> str:
        """The estimator's name."""
        return self.sampled.estimator

    @property
    def lag_model(self) -> bool:
        """Whether the observer's variant is ``lag`` (its estimated state w3 holds Fc + Fv)."""
        return self.config.observer.variant == "lag"

    def reference_feedforward(self) -> tuple[np.ndarray, np.ndarray]:
        """The reference velocity [m/s] and feed-forward weight of every sample
        (:func:`obsdesign.sampled.reference.reference_feedforward` of ``x_ref`` with the config's
        ``lookahead``, ``buildup`` and, with ``ff_presliding``, the pre-sliding curve of ``[friction] s``); zeros and ones when the compensation mode is ``observer``
        (the kernel does not read them)."""
        comp = self.sampled.compensation
        if comp.mode == "observer":
            return np.zeros(self.n_samples), np.ones(self.n_samples)
        from ..sampled.reference import reference_feedforward

        return reference_feedforward(self.x_ref, self.dt, lookahead=comp.lookahead, buildup=comp.buildup,
                                     presliding=self.config.friction.s if comp.ff_presliding else None)

    def kernel_args(self) -> tuple:
        """The groups of :func:`obsdesign.sim.kernel.run_loop` before its outputs: the controller's
        ``(ObserverArgs, EstimatorArgs, ControllerArgs)``, then ``PlantArgs`` and ``Signals``."""
        plant = kernel.PlantArgs(n_sub=self.n_sub, mode=self.mode, lag_model=self.lag_model,
                                 m=self.m, K=self.K_plant, G=self.G_plant, friction_code=self.friction_code,
                                 plant_params=self.plant_params, delay=self.config.hardware.delay_samples,
                                 delay_init=self.sampled.held_command)  # until the first command arrives
        v_ref, w_ff = self.reference_feedforward()
        signals = kernel.Signals(x_ref=_read_only(self.x_ref), u_open=_read_only(self.u_open),
                                 noise=_read_only(self.noise), quantization=self.quantization,
                                 v_ref=_read_only(v_ref), w_ff=_read_only(w_ff))
        return (*self.sampled.kernel_args(), plant, signals)


def _read_only(a) -> np.ndarray:
    """A read-only view of an input signal of the kernel (no copy).

    numba types a read-only array apart from a writable one, so signals that are read-only in one
    scenario (the cached reference of :func:`obsdesign.sim.scenarios.build_scenario`) and writable in
    another (an excitation's random force, a circle's reference) made :func:`~obsdesign.sim.kernel.run_loop`
    compile once per combination (three on a first report, 5 s of CPU each): all read-only, one signature.

    Examples
    --------
    >>> a = np.zeros(3)
    >>> v = _read_only(a)
    >>> v.flags.writeable, a.flags.writeable, np.shares_memory(a, v)
    (False, True, True)
    """
    view = np.asarray(a).view()
    view.flags.writeable = False
    return view


def prepare(
    cfg: Config,
    scenario: Any,
    *,
    controller: str | None = None,
    stiffness: str = "estimated",
    plant: "str | Config" = "physical",
    estimator: "str | DiscreteEstimator" = "paper",
    duration: float | None = None,
    seed: int = 0,
    settle_tol: float | None = None,
    initial_estimate: tuple[float, float] = (0.0, 0.0),
    substeps: int = 10,
) -> LoopInputs:
    """Design the observer and the PID of a config and sample a scenario: the inputs of one run.

    Parameters
    ----------
    cfg : Config
        The design; change parameters with :meth:`obsdesign.Config.override` before. Its
        ``[compensation]`` section sets the compensation law of ``pid+observer``.
    scenario : str or scenario spec
        A name of :data:`obsdesign.sim.SCENARIOS` (its default options) or a spec such as
        ``Positioning(step_size=2e-3)`` (see :mod:`obsdesign.sim.scenarios`).
    controller : str, optional
        A name of :data:`obsdesign.sampled.choices.CONTROLLERS`; default ``open-loop`` for
        ``excitation``/``constant``, ``pid+observer`` otherwise.
    stiffness : str
        Stiffness schedule of the observer, a name of :data:`obsdesign.sampled.choices.SCHEDULES`
        (``estimated``: with a reversal hysteresis of :data:`REVERSAL_NOISE_FACTOR` times
        ``sensor.noise_rms``; ``estimated-raw``: none).
    plant : str or Config
        A name of :data:`obsdesign.sampled.choices.PLANTS`, or a Config. ``physical``: the friction model of ``cfg``'s ``[plant_friction]`` (default: Coulomb with
        pre-sliding memory and viscous friction, with lag when ``friction.beta`` is set).
        ``model``: the 3-state LTV model eq:3:1 of the variant. A Config: a ``physical`` plant
        with that config's mass, actuator gain, load and friction (model mismatch); the observer
        and the controller are still designed from ``cfg``.
    estimator : str or DiscreteEstimator
        A name of :data:`obsdesign.sampled.choices.ESTIMATORS`; the baselines are tuned by
        the fair noise rule (:func:`obsdesign.estimators.tune`). A
        :class:`~obsdesign.estimators.DiscreteEstimator` (other tuning) runs as given.
    duration : float, optional
        Length [s] (the scenario's default).
    seed : int
        Seed of the measurement noise and the excitation (``numpy.random.SeedSequence``), an
        integer >= 0 (``None`` is refused: a run is reproducible from its arguments).
    settle_tol : float, optional
        Band [m] for the settling time; default: scaled to the sensor, ``max(2 x quantization,
        3 x noise_rms)`` (0.1 % of the reference's span for an ideal sensor), see
        :mod:`obsdesign.sim.bands`. None for an open-loop scenario, which has no reference.
    initial_estimate : (float, float)
        Observer's initial ``(v_hat, f_hat)``; the plant starts at rest.
    substeps : int
        Heun substeps of the plant per sample (default 10, at most 1000), raised where the
        explicit step would be unstable for the plant's time constants
        (:func:`obsdesign.sim.numerics.substeps_for`, which refuses a plant needing more than 1000).

    Returns
    -------
    LoopInputs
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    spec = scenario_spec(scenario)
    plant_cfg = cfg
    if isinstance(plant, Config):
        plant_cfg, plant = plant, "physical"
    PLANTS.check(plant)
    if controller is None:
        controller = "open-loop" if spec.open_loop else "pid+observer"
    if settle_tol is not None:
        settle_tol = POSITIVE.check("settle_tol", settle_tol)
    seed = check_integer("seed", seed, minimum=0)
    ctrl = sampled_controller(cfg, controller=controller, schedule=stiffness, estimator=estimator,
                              initial_estimate=initial_estimate)
    if spec.open_loop != (ctrl.controller == "open-loop"):
        expected = "'open-loop'" if spec.open_loop else "'pid' or 'pid+observer'"
        raise ValueError(f"controller: scenario {spec.name!r} needs {expected}, found {controller!r}")
    if plant == "model" and cfg.observer.variant == "lag" and cfg.friction.beta is None:
        raise ValueError("plant: the 'model' plant of variant 'lag' needs friction.beta")
    dt = cfg.observer.dt
    substeps = substeps_for(plant_cfg, dt, substeps, plant=plant)  # the simulated plant's own time constants
    noise_seed, signal_seed = np.random.SeedSequence(seed).spawn(2)
    sc = build_scenario(spec, dt=dt, duration=duration, seed=signal_seed)
    sensor = cfg.sensor
    noise = band_limited_noise(len(sc.x_ref), dt, sensor.noise_rms, sensor.noise_bandwidth, noise_seed)
    band = None
    if settle_tol is not None or not spec.open_loop:
        band = settle_band(cfg, span=float(np.max(sc.x_ref) - np.min(sc.x_ref)), given=settle_tol)
    friction_code, plant_params = plant_friction_arrays(plant_cfg)
    if plant == "model" and friction_code != 0:
        raise ValueError(f"plant: the 'model' plant has the paper's friction, found [plant_friction] model "
                         f"{plant_cfg.plant_friction.model!r}")
    return LoopInputs(
        config=cfg, scenario=sc, plant=plant, settle_tol=None if band is None else band.value, sampled=ctrl,
        n_sub=substeps, settle_rule="given" if band is None else band.rule,
        mode=PLANTS.code(plant), m=plant_cfg.plant.m, K_plant=plant_cfg.plant.K, G_plant=plant_cfg.plant.G,
        friction_code=friction_code, plant_params=plant_params, x_ref=sc.x_ref, u_open=sc.u_open, noise=noise,
        quantization=sensor.quantization, plant_config=plant_cfg if plant_cfg is not cfg else None,
    )


def plant_friction_arrays(cfg: Config) -> tuple[int, np.ndarray]:
    """The kernel's plant friction code and parameter array for a config's ``[plant_friction]``.

    Parameters
    ----------
    cfg : Config
        The plant's config; without ``[plant_friction]`` its plant is the paper's model.

    Returns
    -------
    code : int
        ``0`` paper, ``1`` lugre, ``2`` dahl, ``3`` gms (:mod:`obsdesign.friction`).
    params : ndarray
        ``paper``: ``(Cf, Cf_neg, sigma, sigma_neg, offset, s, beta, kappa)``; the others: the
        array of :meth:`obsdesign.friction.FrictionModelInfo.pack`.

    Notes
    -----
    ``Cf`` and ``sigma`` (for ``paper`` also ``s`` and ``beta``) default to ``[friction]``; the
    stiction level ``Fs`` of ``lugre``/``gms`` defaults to ``1.5 Cf`` (the ratio of the
    published LuGre set), so the models keep their shape at any friction level.

    Examples
    --------
    >>> import obsdesign as od
    >>> code, pp = plant_friction_arrays(od.load_preset("table1"))
    >>> code, pp.tolist()
    (0, [0.35, 0.35, 21.1, 21.1, 0.0, 3000.0, 0.001, 8000.0])
    """
    fr = cfg.friction
    spec = cfg.plant_friction
    model = spec.model if spec is not None else "paper"
    given = dict(spec.parameters) if spec is not None else {}
    if model == "paper":
        q = {"Cf": fr.Cf, "sigma": fr.sigma, "s": fr.s, "beta": fr.beta or 0.0, "offset": 0.0, **given}
        if given:  # the values of [friction] are validated by the config; check only what the table sets
            FRICTION_MODELS["paper"].resolve({k: q[k] for k in ("Cf", "sigma", "s", "beta")})
        return 0, np.array([q["Cf"], q.get("Cf_neg", q["Cf"]), q["sigma"], q.get("sigma_neg", q["sigma"]),
                            q["offset"], q["s"], q["beta"], fr.kappa], dtype=np.float64)
    info = FRICTION_MODELS[model]
    q = {"Cf": fr.Cf, "sigma": fr.sigma, **given}
    if "Fs" in {spec.name for spec in info.parameters} and "Fs" not in given:
        q["Fs"] = 1.5 * q["Cf"]
    return info.code, info.pack(q)


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

