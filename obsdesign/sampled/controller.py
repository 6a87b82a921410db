"""The one definition of the sampled controller: observer or baseline, schedule, low-pass, PID, compensation.

:func:`sampled_controller` builds a frozen :class:`SampledController` from a :class:`~obsdesign.Config`
and the choices (controller, stiffness schedule, estimator). It is the only place that designs the
observer (``design_observer(cfg).affine()``), the low-pass eq:3:4:5, the PID with its derivative
filter, the compensation law, the reversal hysteresis of the ``estimated`` schedule and a baseline
estimator for a run. The simulator (:func:`obsdesign.sim.prepare`), the observer over a log
(:func:`obsdesign.data.observe`), the comparison on measured data and the exports
(:mod:`obsdesign.export.controller`) all take this object, so what is simulated is what is observed
and exported.

Examples
--------
>>> import obsdesign as od
>>> ctrl = sampled_controller(od.load_preset("table1"))
>>> ctrl.controller, ctrl.schedule, ctrl.estimator
('pid+observer', 'estimated', 'paper')
>>> ctrl.reversal_threshold  # 4 x sensor.noise_rms of table1 (1 um)
4e-06
>>> obs, est, pid = ctrl.kernel_args()
>>> round(obs.L1, 3), round(pid.kp, 2)
(248.762, 428.97)
>>> sampled_controller(od.load_preset("table1"), schedule="often")
Traceback (most recent call last):
...
ValueError: stiffness: expected one of estimated, true, constant, estimated-raw, found 'often'
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .._validate import FINITE
from ..compensation import COMPENSATION_MODES, CompensationSpec
from ..params import Config
from .choices import CONTROLLERS, ESTIMATORS, SCHEDULES

if TYPE_CHECKING:  # pragma: no cover
    from ..design.observer import ObserverArrays
    from ..estimators.base import DiscreteEstimator

__all__ = ["SampledController", "sampled_controller", "ObserverArgs", "EstimatorArgs", "ControllerArgs",
           "REVERSAL_NOISE_FACTOR", "reversal_threshold"]

#: Hysteresis of the ``estimated`` schedule in units of the sensor's noise RMS (docs/comparison.md).
REVERSAL_NOISE_FACTOR = 4.0


def reversal_threshold(cfg: Config) -> float:
    """Hysteresis [m] of the ``estimated`` schedule: :data:`REVERSAL_NOISE_FACTOR` x ``sensor.noise_rms``.

    The one definition, read by :func:`sampled_controller` and by the observer export (which must not
    build the controller: it imports nothing heavy).

    Parameters
    ----------
    cfg : Config
        The design; its ``sensor.noise_rms`` [m].

    Returns
    -------
    float
        The threshold [m]; 0 where the sensor has no noise (reversals at sign changes of ``v_hat``).

    Examples
    --------
    >>> import obsdesign as od
    >>> reversal_threshold(od.load_preset("table1"))  # 4 x 1 um
    4e-06
    """
    return REVERSAL_NOISE_FACTOR * cfg.sensor.noise_rms


class ObserverArgs(NamedTuple):
    """The paper observer's arguments of :func:`obsdesign.sampled.kernel.observer_sample`.

    Attributes
    ----------
    dt : float
        Sample time [s].
    Cf, s, kappa : float
        The design's Coulomb level [N], pre-sliding scale [1/m] and stiffness bound [N/m].
    A0, A1, b0, b1, g0, g1 : ndarray
        Affine-in-stiffness observer arrays (:class:`obsdesign.design.ObserverArrays`).
    L1, L2 : float
        Observer gains (eq:3:3:3-4).
    schedule : int
        Stiffness schedule code (:data:`obsdesign.sampled.choices.SCHEDULES`).
    estimator : int
        Estimator code (:data:`obsdesign.sampled.choices.ESTIMATORS`).
    v_hat0, f_hat0 : float
        Initial estimates [m/s], [N].
    lp_phi, lp_g0, lp_g1 : ndarray
        FOH recursion of the low-pass eq:3:4:5.
    reversal_threshold : float
        Hysteresis [m] of the ``estimated`` schedule (0: none).
    """

    dt: float
    Cf: float
    s: float
    kappa: float
    A0: np.ndarray
    A1: np.ndarray
    b0: np.ndarray
    b1: np.ndarray
    g0: np.ndarray
    g1: np.ndarray
    L1: float
    L2: float
    schedule: int
    estimator: int
    v_hat0: float
    f_hat0: float
    lp_phi: np.ndarray
    lp_g0: np.ndarray
    lp_g1: np.ndarray
    reversal_threshold: float


class EstimatorArgs(NamedTuple):
    """A linear baseline's arrays (:class:`obsdesign.estimators.DiscreteEstimator`); placeholders of
    one state when the paper observer runs.

    Attributes
    ----------
    Phi, gu, g0, g1 : ndarray
        ``z[n] = Phi z[n-1] + gu u[n-1] + g0 y[n-1] + g1 y[n]``.
    Cz, d : ndarray
        ``(v_hat, f_hat) = Cz z + d y``.
    init : ndarray
        ``z0 = init @ (x0, v_hat0, f_hat0)``.
    """

    Phi: np.ndarray
    gu: np.ndarray
    g0: np.ndarray
    g1: np.ndarray
    Cz: np.ndarray
    d: np.ndarray
    init: np.ndarray


class ControllerArgs(NamedTuple):
    """The controller's arguments of :func:`obsdesign.sampled.kernel.controller_sample`.

    Attributes
    ----------
    controller : int
        Controller code (:data:`obsdesign.sampled.choices.CONTROLLERS`).
    dt : float
        Sample time [s].
    K, G : float
        Actuator gain [N/V] and load force [N] of the design.
    sigma : float
        Viscous coefficient of the design [N s/m] (viscous compensation term).
    kp, ki, kd : float
        Parallel PID gains eq:PIDparallel [V/m, V/(m s), V s/m].
    alpha_d : float
        Pole ``exp(-dt / tau_d)`` of the derivative filter (0: none).
    u_max : float
        Saturation of the command [V].
    comp_gain, comp_viscous, comp_deadzone : float, bool, float
        The compensation law of :class:`obsdesign.params.CompensationSpec`.
    comp_mode : int
        Compensation mode code (:data:`obsdesign.compensation.COMPENSATION_MODES`).
    ff_cf, ff_stribeck, ff_vs, ff_offset : float
        The feed-forward model: Coulomb level ``friction.Cf`` [N], Stribeck force [N] and velocity
        [m/s], constant force [N] (``[compensation]``).
    blend_viscous : bool
        Whether the observer's estimate contains the viscous force (variant ``lag``): the model
        part ``blend`` subtracts.
    delay : int
        The drive's delay [samples] (``[hardware] delay_samples``): the estimator is fed the command
        the drive applies, that of ``delay`` samples earlier (a ring of the last ``delay`` commands);
        the command returned is not delayed.
    held_command : float
        The command [V] the drive applies before the first computed one arrives (the ring's start):
        :attr:`SampledController.held_command`.
    """

    controller: int
    dt: float
    K: float
    G: float
    sigma: float
    kp: float
    ki: float
    kd: float
    alpha_d: float
    u_max: float
    comp_gain: float
    comp_viscous: bool
    comp_deadzone: float
    comp_mode: int
    ff_cf: float
    ff_stribeck: float
    ff_vs: float
    ff_offset: float
    blend_viscous: bool
    delay: int
    held_command: float


@dataclass(frozen=True, eq=False)
class SampledController:
    """The controller as it runs at ``config.observer.dt``; build with :func:`sampled_controller`.

    Attributes
    ----------
    config : Config
        The design.
    controller : str
        ``open-loop``, ``pid`` or ``pid+observer`` (:data:`~obsdesign.sampled.choices.CONTROLLERS`).
    schedule : str
        Stiffness schedule of the paper observer (:data:`~obsdesign.sampled.choices.SCHEDULES`).
    estimator : str
        Estimator name (:data:`~obsdesign.sampled.choices.ESTIMATORS`).
    observer : ObserverArrays
        The designed observer in affine-in-stiffness form (it also runs beside a baseline, unused).
    lowpass : tuple of ndarray
        ``(Phi, g0, g1)`` of the low-pass eq:3:4:5.
    kp, ki, kd, tau_d : float
        PID gains and the derivative filter's time constant ``kd / (kp N)`` [s] (all 0 open loop).
    compensation : CompensationSpec
        The compensation law (``pid+observer`` only; the default elsewhere).
    reversal_threshold : float
        Hysteresis [m] of the ``estimated`` schedule: :data:`REVERSAL_NOISE_FACTOR` x ``sensor.noise_rms``.
    baseline : DiscreteEstimator or None
        The linear estimator that runs instead of the paper observer (``estimator`` not a paper entry).
    initial_estimate : tuple of float
        ``(v_hat0, f_hat0)`` at the first sample.
    """

    config: Config
    controller: str
    schedule: str
    estimator: str
    observer: "ObserverArrays" = field(repr=False)
    lowpass: tuple = field(repr=False)
    kp: float
    ki: float
    kd: float
    tau_d: float
    compensation: CompensationSpec
    reversal_threshold: float
    baseline: "DiscreteEstimator | None" = field(repr=False)
    initial_estimate: tuple

    @property
    def dt(self) -> float:
        """Sample time [s]."""
        return self.config.observer.dt

    @property
    def delay_samples(self) -> int:
        """The drive's delay [samples] (``config.hardware.delay_samples``): the estimator is fed the
        command of that many samples earlier, the one the drive applies; the output is not delayed."""
        return self.config.hardware.delay_samples

    @property
    def held_command(self) -> float:
        """The command [V] the drive applies before the first computed one arrives: the design's
        feed-forward ``G / K`` saturated at ``u_max`` (the simulated drive's ring starts there too)."""
        pl = self.config.plant
        return min(max(pl.G / pl.K, -pl.u_max), pl.u_max)

    @property
    def alpha_d(self) -> float:
        """Pole of the first-order derivative filter per sample, ``exp(-dt / tau_d)`` (0 without one)."""
        from ..design.sampled_loop import derivative_pole

        return derivative_pole(self.dt, self.tau_d)

    def kernel_args(self) -> tuple[ObserverArgs, EstimatorArgs, ControllerArgs]:
        """The named argument groups of :func:`obsdesign.sampled.kernel.controller_sample`."""
        cfg, obs = self.config, self.observer
        fr, pl = cfg.friction, cfg.plant
        lp_phi, lp_g0, lp_g1 = self.lowpass
        v_hat0, f_hat0 = self.initial_estimate
        o = ObserverArgs(dt=self.dt, Cf=fr.Cf, s=fr.s, kappa=fr.kappa, A0=obs.A0, A1=obs.A1, b0=obs.b0, b1=obs.b1,
                         g0=obs.g0, g1=obs.g1, L1=obs.design.L1, L2=obs.design.L2,
                         schedule=SCHEDULES.code(self.schedule), estimator=ESTIMATORS.code(self.estimator),
                         v_hat0=v_hat0, f_hat0=f_hat0, lp_phi=lp_phi, lp_g0=lp_g0, lp_g1=lp_g1,
                         reversal_threshold=self.reversal_threshold)
        b = self.baseline
        if b is None:
            e = EstimatorArgs(Phi=np.zeros((1, 1)), gu=np.zeros(1), g0=np.zeros(1), g1=np.zeros(1),
                              Cz=np.zeros((2, 1)), d=np.zeros(2), init=np.zeros((1, 3)))
        else:
            e = EstimatorArgs(Phi=b.Phi, gu=b.gu, g0=b.g0, g1=b.g1, Cz=b.Cz, d=b.d, init=b.init)
        comp = self.compensation
        c = ControllerArgs(controller=CONTROLLERS.code(self.controller), dt=self.dt, K=pl.K, G=pl.G, sigma=fr.sigma,
                           kp=self.kp, ki=self.ki, kd=self.kd, alpha_d=self.alpha_d, u_max=pl.u_max,
                           comp_gain=comp.gain, comp_viscous=comp.viscous, comp_deadzone=comp.deadzone,
                           comp_mode=COMPENSATION_MODES.code(comp.mode), ff_cf=fr.Cf, ff_stribeck=comp.ff_stribeck,
                           ff_vs=comp.ff_stribeck_velocity, ff_offset=comp.ff_offset,
                           blend_viscous=cfg.observer.variant == "lag", delay=self.delay_samples,
                           held_command=self.held_command)
        return o, e, c


def sampled_controller(cfg: Config, *, controller: str = "pid+observer", schedule: str = "estimated",
                       estimator: "str | DiscreteEstimator" = "paper",
                       initial_estimate: tuple[float, float] = (0.0, 0.0)) -> SampledController:
    """Build the sampled controller of a design: the one place each of its parts is computed.

    Parameters
    ----------
    cfg : Config
        The design (change parameters with :meth:`obsdesign.Config.override` before); its
        ``[compensation]`` section sets the law of ``pid+observer``.
    controller : str
        A name of :data:`~obsdesign.sampled.choices.CONTROLLERS`; ``pid`` runs the estimator for
        monitoring without compensating.
    schedule : str
        A name of :data:`~obsdesign.sampled.choices.SCHEDULES`: the stiffness schedule of the paper
        observer (``estimated``: a reversal hysteresis of :data:`REVERSAL_NOISE_FACTOR` times
        ``sensor.noise_rms``; ``estimated-raw``: none).
    estimator : str or DiscreteEstimator
        A name of :data:`~obsdesign.sampled.choices.ESTIMATORS`; a baseline named here is tuned by the fair noise rule (:func:`obsdesign.estimators.tune`);
        a :class:`~obsdesign.estimators.DiscreteEstimator` (another tuning) runs as given.
    initial_estimate : (float, float)
        The observer's ``(v_hat, f_hat)`` at the first sample.

    Returns
    -------
    SampledController

    Raises
    ------
    TypeError
        ``cfg`` is not a Config.
    ValueError
        An unknown choice, or a DiscreteEstimator at another sample time.
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    controller = CONTROLLERS.check(controller)
    schedule = SCHEDULES.check(schedule)
    baseline = None
    if not isinstance(estimator, str):
        from ..estimators import DiscreteEstimator

        if not isinstance(estimator, DiscreteEstimator):
            raise TypeError(f"estimator: expected a name or a DiscreteEstimator, found {type(estimator).__name__}")
        baseline, estimator = estimator, estimator.name
    estimator = ESTIMATORS.check(estimator)
    if isinstance(initial_estimate, (str, bytes)) or not hasattr(initial_estimate, "__len__") \
            or len(initial_estimate) != 2:
        raise ValueError(f"initial_estimate: expected a pair (v_hat, f_hat) of finite numbers, "
                         f"found {initial_estimate!r}")
    initial_estimate = tuple(FINITE.check("initial_estimate", x) for x in initial_estimate)
    dt = cfg.observer.dt
    if not ESTIMATORS[estimator].baseline:
        baseline = None  # the paper entries run in the observer kernel, with the schedule
    elif baseline is None:
        from ..estimators import tune

        baseline = tune(estimator, cfg)
    if baseline is not None and baseline.dt != dt:
        raise ValueError(f"estimator: expected a DiscreteEstimator named {estimator!r} at dt = {dt!r} s, "
                         f"found dt = {baseline.dt!r} s")
    from ..design.discretize import lowpass_arrays
    from ..design.observer import design_observer

    observer = design_observer(cfg).affine()
    lowpass = lowpass_arrays(cfg.observer.omega_co, dt)
    if controller == "open-loop":
        kp = ki = kd = tau_d = 0.0
    else:
        from ..design.pid_sampled import sampled_pid_gains

        kp, ki, kd, tau_d = sampled_pid_gains(cfg)
    compensation = cfg.compensation if controller == "pid+observer" else CompensationSpec()
    if compensation.mode == "blend" and baseline is not None:
        raise ValueError(f"compensation.mode: 'blend' needs the paper observer's low-passed estimate; expected "
                         f"estimator paper or paper-k0, found {estimator!r}")
    return SampledController(config=cfg, controller=controller, schedule=schedule, estimator=estimator,
                             observer=observer, lowpass=lowpass, kp=kp, ki=ki, kd=kd, tau_d=tau_d,
                             compensation=compensation,
                             reversal_threshold=reversal_threshold(cfg),
                             baseline=baseline, initial_estimate=initial_estimate)

