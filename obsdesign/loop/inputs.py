"""The closed loop as the hardware runs it, built once from a config: :func:`prepare` -> :class:`LoopInputs`.

One object holds the whole loop around the one :class:`~obsdesign.sampled.SampledController`:

* the controller (:func:`obsdesign.sampled.sampled_controller`: observer or baseline, schedule,
  low-pass, PID with its derivative filter, compensation);
* the plant the simulator runs (the config's, or a mismatched plant's config; its friction by
  :func:`obsdesign.loop.plant.plant_friction_arrays`; its Heun substeps by
  :func:`obsdesign.loop.numerics.substeps_for`);
* the drive's delay ``[hardware] delay_samples`` between the sampled position and the applied command,
  with the command the drive holds before the first computed one arrives
  (:attr:`SampledController.held_command <obsdesign.sampled.SampledController.held_command>`): the plant
  side of the delay is :class:`~obsdesign.loop.args.PlantArgs` ``delay`` / ``delay_init``, the
  controller's side (its estimator is fed the applied command) ``ControllerArgs.delay``; both read the
  one config value, here and in :meth:`SampledController.kernel_args`;
* the sensor (band-limited noise of ``sensor.noise_rms``, encoder resolution ``sensor.quantization``);
* the reference and the open-loop force of a scenario (:mod:`obsdesign.loop.scenarios`), with the
  feed-forward's reference velocity and weight.

:func:`obsdesign.sim.run` runs it in the numba kernel, :func:`obsdesign.sim.external.run_external` runs its
plant, sensor and delay around a controller of your own (an exported one); ``simulate``, ``tune``, the
sweeps, the circle test, the comparison and the report's explorer all get their loop here.

Examples
--------
>>> import obsdesign as od
>>> loop = prepare(od.load_preset("vcm").override(delay_samples=1), "tracking", controller="pid", duration=0.5)
>>> loop.n_samples, loop.controller, loop.plant, loop.delay_samples
(5000, 'pid', 'physical', 1)
>>> plant = loop.kernel_args()[3]          # the drive's delay on the plant side, the controller's own ring
>>> plant.delay == loop.sampled.kernel_args()[2].delay == 1
True
>>> loop.quantization, loop.settle_rule
(1e-06, '2 x encoder resolution 1e-06 m')
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import POSITIVE, check_integer
from ..estimators import DiscreteEstimator
from ..params import Config
from ..sampled.choices import PLANTS
from ..sampled.controller import SampledController, sampled_controller
from .args import PlantArgs, Signals
from .bands import settle_band
from .numerics import substeps_for
from .plant import plant_friction_arrays
from .scenarios import Scenario, band_limited_noise, build_scenario, scenario_spec

__all__ = ["LoopInputs", "prepare"]


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
        Where the settling band comes from (:func:`obsdesign.loop.bands.settle_band`).
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
    def delay_samples(self) -> int:
        """The drive's delay [samples] between the sampled position and the applied command
        (``[hardware] delay_samples`` of the design, the one value both sides of the loop read)."""
        return self.sampled.delay_samples

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
        plant = PlantArgs(n_sub=self.n_sub, mode=self.mode, lag_model=self.lag_model,
                          m=self.m, K=self.K_plant, G=self.G_plant, friction_code=self.friction_code,
                          plant_params=self.plant_params, delay=self.delay_samples,
                          delay_init=self.sampled.held_command)  # until the first command arrives
        v_ref, w_ff = self.reference_feedforward()
        signals = Signals(x_ref=_read_only(self.x_ref), u_open=_read_only(self.u_open),
                          noise=_read_only(self.noise), quantization=self.quantization,
                          v_ref=_read_only(v_ref), w_ff=_read_only(w_ff))
        return (*self.sampled.kernel_args(), plant, signals)


def _read_only(a) -> np.ndarray:
    """A read-only view of an input signal of the kernel (no copy).

    numba types a read-only array apart from a writable one, so signals that are read-only in one
    scenario (the cached reference of :func:`obsdesign.loop.scenarios.build_scenario`) and writable in
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
        ``Positioning(step_size=2e-3)`` (see :mod:`obsdesign.loop.scenarios`).
    controller : str, optional
        A name of :data:`obsdesign.sampled.choices.CONTROLLERS`; default ``open-loop`` for
        ``excitation``/``constant``, ``pid+observer`` otherwise.
    stiffness : str
        Stiffness schedule of the observer, a name of :data:`obsdesign.sampled.choices.SCHEDULES`
        (``estimated``: with a reversal hysteresis of :data:`~obsdesign.sampled.controller.REVERSAL_NOISE_FACTOR` times
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
        :mod:`obsdesign.loop.bands`. None for an open-loop scenario, which has no reference.
    initial_estimate : (float, float)
        Observer's initial ``(v_hat, f_hat)``; the plant starts at rest.
    substeps : int
        Heun substeps of the plant per sample (default 10, at most 1000), raised where the
        explicit step would be unstable for the plant's time constants
        (:func:`obsdesign.loop.numerics.substeps_for`, which refuses a plant needing more than 1000).

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
        pf = plant_cfg.plant_friction
        raise ValueError(f"plant: the 'model' plant has the paper's friction, found [plant_friction] model "
                         f"{pf.model if pf is not None else 'paper'!r}")
    return LoopInputs(
        config=cfg, scenario=sc, plant=plant, settle_tol=None if band is None else band.value, sampled=ctrl,
        n_sub=substeps, settle_rule="given" if band is None else band.rule,
        mode=PLANTS.code(plant), m=plant_cfg.plant.m, K_plant=plant_cfg.plant.K, G_plant=plant_cfg.plant.G,
        friction_code=friction_code, plant_params=plant_params, x_ref=sc.x_ref, u_open=sc.u_open, noise=noise,
        quantization=sensor.quantization, plant_config=plant_cfg if plant_cfg is not cfg else None,
    )
