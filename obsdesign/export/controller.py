"""Export the whole sampled controller (estimator, schedule, low-pass, PID, compensation) as code.

One call of the generated ``step(x_ref, x_meas)`` per sample does what
:func:`obsdesign.sampled.kernel.controller_sample` does from the measurement to the command, in its order:

1. estimator. ``paper``/``paper-k0``: at the first sample the observer's state is set from
   the first measurement; after that the exact recursion advances it with the net force ``u``
   of the previous sample (held) and the previous and new measurements; ``v_hat``, ``f_hat``
   by eq:3:1:3. A linear baseline (``eso``, ``kalman``, ``dob``, tuned by
   :func:`obsdesign.estimators.tune` as the simulator tunes it) runs its common discrete form
   ``z = Phi z + gu u + g0 x_prev + g1 x_meas``, ``(v_hat, f_hat) = Cz z + d x_meas``
   (:func:`obsdesign.estimators.estimator_step`), started at ``z = init (x_meas, 0, 0)``;
2. ``paper``/``paper-k0``: low-pass eq:3:4:5 of ``f_hat`` (the simulator's FOH state-space
   recursion; it starts at zero and is first advanced at the second sample); a baseline
   compensates with its ``f_hat`` unfiltered;
3. ``paper``: the stiffness schedule for the coming interval (``estimated``: a new
   pre-sliding branch once the measurement has come back from its extreme by more than the
   reversal threshold :data:`REVERSAL_NOISE_FACTOR` x ``sensor.noise_rms``, or at every sign
   change of ``v_hat`` when that is 0; ``estimated-raw``: at every sign change of ``v_hat``;
   ``constant``: ``kappa``); ``paper-k0``: ``k = 0``. The recursion is recomputed only when
   the stiffness changed;
4. parallel PID on ``e = x_ref - x_meas``: first-order filtered derivative (``e_prev = e``
   at the first sample), integral by conditional integration (kept only when the
   unsaturated command is within the limit), compensation ``comp / K`` (``pid+observer``),
   load feed-forward ``G / K``, saturation at ``u_max``; the net force ``K command - G``
   is kept for the next estimator step.

The returned command [V] is after saturation and includes the feed-forward, so the
simulator's ``u`` column is ``K * command - G``.

Compensation law (the config's ``[compensation]`` section, :class:`~obsdesign.params.CompensationSpec`;
the defaults give the paper's law ``f_hat_filtered / K`` with exactly its operations)::

    fade = min(1, |v_hat| / deadzone)  if deadzone > 0 else 1
    comp = gain * (f_hat_filtered + (sigma * v_hat if viscous else 0)) * fade
    u_volt += comp / K

Compensation modes ``feedforward`` and ``blend`` (``[compensation] mode``): the step takes two more
inputs, ``step(x_ref, x_meas, v_ref, w_ff)``, the reference velocity [m/s] and the feed-forward
weight in [-1, 1] of :func:`obsdesign.sampled.reference.reference_feedforward` (the trajectory
generator's numbers: the look-ahead needs the path ahead), and compensates
:func:`obsdesign.sampled.kernel.reference_compensation` in its order (docs/compensation-modes.md).

Examples
--------
>>> import obsdesign as od
>>> files = controller_files(od.load_preset("vcm"), "c")
>>> sorted(files)
['obsdesign_controller.c', 'obsdesign_controller.h']
>>> sorted(controller_files(od.load_preset("vcm"), "octave"))
['obsdesign_controller.m', 'obsdesign_controller_init.m', 'obsdesign_controller_step.m']
>>> consts = controller_constants(od.load_preset("vcm").override(gain=0.5, deadzone=1e-4))
>>> consts["COMP_GAIN"], consts["COMP_DEADZONE"]
(0.5, 0.0001)
>>> table1 = od.load_preset("table1")  # sensor.noise_rms = 1e-6 m
>>> controller_constants(table1)["REVERSAL_THRESHOLD"] == REVERSAL_NOISE_FACTOR * 1e-6
True
>>> controller_constants(table1, schedule="true")
Traceback (most recent call last):
...
ValueError: schedule: 'true' (the simulated plant's stiffness) cannot run on an axis; expected one of estimated, constant, estimated-raw, found 'true'
"""

from __future__ import annotations

import dataclasses
import math

from .._validate import check_choice
from ..design import discretize
from ..friction import presliding as friction
from ..params import CompensationSpec, Config
from ..sampled.choices import CONTROLLERS, ESTIMATORS, SCHEDULES
from ..sampled.controller import REVERSAL_NOISE_FACTOR, SampledController, sampled_controller
from ..axis import LINEAR
from .codegen import _plain_source, axis_note
from .literals import NAME_MAX as _NAME_MAX
from .literals import comment_text

__all__ = ["CompensationSpec", "controller_files", "controller_constants", "check_waits", "exported_controller", "sanitize_comment",
           "LANGUAGES", "EXPORTED_CONTROLLERS", "SCHEDULE_NAMES", "SCHEDULE_ZERO", "REVERSAL_NOISE_FACTOR"]

#: The controllers that run on an axis (``open-loop`` is a simulation scenario's).
EXPORTED_CONTROLLERS = tuple(name for name in CONTROLLERS.names() if name != "open-loop")
#: The stiffness schedules the generated code runs: the simulator's, less ``true`` (it needs the
#: simulated plant). The generated constant ``SCHEDULE`` holds the registry's code.
SCHEDULE_NAMES = tuple(name for name in SCHEDULES.names() if name != "true")
#: ``SCHEDULE`` of ``paper-k0``: the stiffness is 0 whatever the schedule (a code no schedule has).
SCHEDULE_ZERO = -1
#: Longest sanitized config name placed in a comment or docstring.
NAME_MAX = _NAME_MAX


def sanitize_comment(text: str, *, limit: int = NAME_MAX) -> str:
    """A user string made safe for any comment or docstring of the generated code.

    The one function for comments of every export (:func:`obsdesign.export.literals.comment_text`).

    Parameters
    ----------
    text : str
        User text (e.g. a config name).
    limit : int
        Longest result.

    Keeps ``[A-Za-z0-9 _.,+-]``, replaces every other character with ``_`` and caps the length.

    >>> sanitize_comment("a */ b" + chr(10) + "c" + chr(0x2028) + "d")
    'a __ b_c_d'
    """
    return comment_text(text, limit=limit)


def _check_schedule(schedule) -> str:
    if schedule == "true":
        raise ValueError(f"schedule: 'true' (the simulated plant's stiffness) cannot run on an axis; expected one of "
                         f"{', '.join(SCHEDULE_NAMES)}, found 'true'")
    return check_choice("schedule", schedule, SCHEDULE_NAMES)


def exported_controller(cfg, *, controller: str | None = None, compensation: CompensationSpec | None = None,
                        schedule: str | None = None, estimator: str | None = None) -> SampledController:
    """The one :class:`~obsdesign.sampled.SampledController` an export generates: the object the simulator runs.

    Parameters
    ----------
    cfg : Config or SampledController
        The design, or the controller itself (then no other argument may be given).
    controller : str, optional
        A name of :data:`EXPORTED_CONTROLLERS` (default ``pid+observer``).
    compensation : CompensationSpec, optional
        Replaces the config's ``[compensation]`` section (``pid+observer`` only).
    schedule : str, optional
        A name of :data:`obsdesign.sampled.choices.SCHEDULES` but ``true`` (default ``estimated``).
    estimator : str, optional
        A name of :data:`obsdesign.sampled.choices.ESTIMATORS` (default ``paper``).

    Returns
    -------
    SampledController

    Examples
    --------
    >>> import obsdesign as od
    >>> exported_controller(od.load_preset("table1")).reversal_threshold   # 4 x sensor.noise_rms
    4e-06
    """
    given = {"controller": controller, "compensation": compensation, "schedule": schedule, "estimator": estimator}
    if isinstance(cfg, SampledController):
        extra = [k for k, v in given.items() if v is not None]
        if extra:
            raise ValueError(f"{extra[0]}: a SampledController has its own; expected None, found {given[extra[0]]!r}")
        ctrl = cfg
        check_choice("controller", ctrl.controller, EXPORTED_CONTROLLERS)
        _check_schedule(ctrl.schedule)
        return ctrl
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config or a SampledController, found {type(cfg).__name__}")
    controller = check_choice("controller", "pid+observer" if controller is None else controller, EXPORTED_CONTROLLERS)
    schedule = _check_schedule("estimated" if schedule is None else schedule)
    estimator = ESTIMATORS.check("paper" if estimator is None else estimator)
    if compensation is not None:
        if not isinstance(compensation, CompensationSpec):
            raise TypeError(f"compensation: expected a CompensationSpec, found {type(compensation).__name__}")
        if controller == "pid" and compensation != CompensationSpec():
            raise ValueError("compensation: only the controller 'pid+observer' compensates friction; "
                             "leave the default CompensationSpec() for 'pid'")
        cfg = dataclasses.replace(cfg, compensation=compensation)
    return sampled_controller(cfg, controller=controller, schedule=schedule, estimator=estimator)


def check_waits(waits, ctrl: SampledController) -> int:
    """The ring length of the generated controller (the drive's delay d); ``waits`` checked against it.

    Parameters
    ----------
    waits : bool
        Whether the generated controller waits (a bench without the drive's delay).
    ctrl : SampledController
        The controller exported.

    Returns
    -------
    int
        ``ctrl.delay_samples``.

    Raises
    ------
    TypeError
        ``waits`` is not a bool.
    ValueError
        ``waits`` with ``[hardware] delay_samples = 0`` (nothing to wait for).

    Examples
    --------
    >>> import obsdesign as od
    >>> check_waits(True, exported_controller(od.load_preset("vcm")))
    Traceback (most recent call last):
    ...
    ValueError: waits: the controller that waits delays its command by [hardware] delay_samples; expected delay_samples >= 1, found 0
    """
    if not isinstance(waits, bool):
        raise TypeError(f"waits: expected a bool, found {type(waits).__name__}")
    d = ctrl.delay_samples
    if waits and d == 0:
        raise ValueError("waits: the controller that waits delays its command by [hardware] delay_samples; "
                         "expected delay_samples >= 1, found 0")
    return d


def controller_constants(cfg, *, controller: str | None = None, compensation: CompensationSpec | None = None,
                         schedule: str | None = None, estimator: str | None = None) -> dict[str, float]:
    """Every number of the generated controller: those of the simulator's own sampled controller.

    The numbers are read from :meth:`obsdesign.sampled.SampledController.kernel_args` of
    :func:`exported_controller`, the groups the simulator's kernel runs, so what is exported is
    what is simulated.

    Parameters
    ----------
    cfg : Config or SampledController
        The design, or the controller (see :func:`exported_controller` for the other arguments).
    controller, compensation, schedule, estimator : optional
        As in :func:`exported_controller`.

    Returns
    -------
    dict of str to float
        Keys are the constant names of the generated code. Always: ``DT``, ``K``, ``G``, ``U_MAX``,
        ``SIGMA``, ``V_HAT0``, ``F_HAT0``, the PID (``KP``, ``KI``, ``KD``, ``ALPHA_D``), the
        compensation (``COMP_ON``, ``COMP_GAIN``, ``COMP_VISCOUS``, ``COMP_DEADZONE``; flags are
        0.0 or 1.0; modes ``feedforward``/``blend`` add ``COMP_MODE``, the model ``FF_CF``,
        ``FF_STRIBECK``, ``FF_VS``, ``FF_OFFSET`` and ``BLEND_VISCOUS``). With the drive's delay
        (``[hardware] delay_samples`` d > 0; the command is not delayed, the estimator is fed the
        command the drive applies): ``DRIVE_DELAY`` (d) and ``DRIVE_HOLD`` [V], the command the drive
        applies before the first one arrives. ``paper``/``paper-k0``: ``CF``, ``S``, ``KAPPA``, ``L1``, ``L2``, the affine observer arrays ``A0_i`` ... ``G1_i``, the low-pass
        ``LP_*``, ``SCHEDULE`` (the registry's code; :data:`SCHEDULE_ZERO` for ``paper-k0``) and
        ``REVERSAL_THRESHOLD`` [m]. A baseline: ``E_NZ`` and its arrays ``E_PHI_i_j``, ``E_GU_i``,
        ``E_G0_i``, ``E_G1_i``, ``E_CZ_r_j``, ``E_D_r``, ``E_INIT_i_c``.

    Raises
    ------
    TypeError
        ``cfg`` is not a Config or SampledController, or ``compensation`` not a CompensationSpec.
    ValueError
        Unknown controller, schedule or estimator; ``schedule='true'``; knobs other than the
        default with ``pid``.

    Examples
    --------
    >>> import obsdesign as od
    >>> c = controller_constants(od.load_preset("vcm"), controller="pid")
    >>> c["COMP_ON"], round(c["KP"], 2), round(c["G"] / c["K"], 4)
    (0.0, 428.97, 1.6067)
    >>> c["SCHEDULE"] == SCHEDULES.code("estimated-raw")  # vcm has no random noise: no hysteresis
    True
    >>> controller_constants(od.load_preset("vcm"), estimator="paper-k0")["SCHEDULE"] == SCHEDULE_ZERO
    True
    >>> controller_constants(od.load_preset("vcm"), estimator="dob")["E_NZ"]
    2.0
    """
    ctrl = exported_controller(cfg, controller=controller, compensation=compensation, schedule=schedule,
                               estimator=estimator)
    obs, est, c = ctrl.kernel_args()
    consts = {
        "DT": c.dt, "K": c.K, "G": c.G, "U_MAX": c.u_max, "SIGMA": c.sigma, "V_HAT0": obs.v_hat0,
        "F_HAT0": obs.f_hat0, "KP": c.kp, "KI": c.ki, "KD": c.kd, "ALPHA_D": c.alpha_d,
        "COMP_ON": 1.0 if ctrl.controller == "pid+observer" else 0.0, "COMP_GAIN": c.comp_gain,
        "COMP_VISCOUS": 1.0 if c.comp_viscous else 0.0, "COMP_DEADZONE": c.comp_deadzone,
    }
    if c.delay > 0:
        consts.update({"DRIVE_DELAY": c.delay, "DRIVE_HOLD": c.held_command})
    if ctrl.controller == "pid+observer" and ctrl.compensation.mode != "observer":
        consts.update({"COMP_MODE": c.comp_mode, "FF_CF": c.ff_cf, "FF_STRIBECK": c.ff_stribeck, "FF_VS": c.ff_vs,
                       "FF_OFFSET": c.ff_offset, "BLEND_VISCOUS": 1.0 if c.blend_viscous else 0.0})
    if ctrl.baseline is None:
        if ctrl.estimator == "paper-k0":
            code = SCHEDULE_ZERO
        elif ctrl.schedule == "estimated" and obs.reversal_threshold == 0.0:
            code = SCHEDULES.code("estimated-raw")  # the simulator's kernel does the same
        else:
            code = obs.schedule
        consts.update({"CF": obs.Cf, "S": obs.s, "KAPPA": obs.kappa, "L1": obs.L1, "L2": obs.L2,
                       "SCHEDULE": code, "REVERSAL_THRESHOLD": obs.reversal_threshold})
        arrays = (("A0", obs.A0), ("A1", obs.A1), ("B0", obs.b0), ("B1", obs.b1), ("G0", obs.g0), ("G1", obs.g1),
                  ("LP_PHI", obs.lp_phi), ("LP_G0", obs.lp_g0), ("LP_G1", obs.lp_g1))
        for name, values in arrays:  # flat, row-major: A0_0 .. A0_3
            consts.update({f"{name}_{i}": float(v) for i, v in enumerate(values.ravel())})
    else:
        consts["E_NZ"] = ctrl.baseline.nz
        for name, values in (("E_PHI", est.Phi), ("E_GU", est.gu), ("E_G0", est.g0), ("E_G1", est.g1),
                             ("E_CZ", est.Cz), ("E_D", est.d), ("E_INIT", est.init)):
            for index, v in zip(_indices(values.shape), values.ravel()):
                consts[f"{name}_{index}"] = float(v)
    return {key: float(value) for key, value in consts.items()}


def _indices(shape: tuple[int, ...]) -> list[str]:
    """Suffixes ``i`` or ``i_j`` of the elements of an array of ``shape``, row-major."""
    if len(shape) == 1:
        return [str(i) for i in range(shape[0])]
    return [f"{i}_{j}" for i in range(shape[0]) for j in range(shape[1])]


def _literal(value: float) -> str:
    """A floating-point literal valid in C, Python, Octave and JavaScript that round-trips exactly."""
    if not math.isfinite(value):
        raise ValueError(f"constant: expected a finite number, found {value!r}")
    return repr(float(value))


def _environment(units=LINEAR):
    from jinja2 import Environment, PackageLoader, StrictUndefined

    env = Environment(loader=PackageLoader("obsdesign.export", "templates"), undefined=StrictUndefined,
                      keep_trailing_newline=True, autoescape=False, trim_blocks=True, lstrip_blocks=True)
    env.filters["unit"] = units.unit  # the templates' units, written for a linear axis in V
    return env


def _c_core() -> str:
    from importlib import resources

    return resources.files("obsdesign.export").joinpath("c/obsdesign_core.inc").read_text(encoding="utf-8")


def _python_helpers(baseline: bool) -> str:
    if baseline:
        from ..estimators import base  # python-control: loaded only for a baseline

        fns = (base.estimator_step, base.estimator_output)
    else:
        fns = (friction.presliding_shape, friction.coulomb_normalized, friction.stiffness, friction.track_reversal,
               friction.track_reversal_hysteresis, discretize._mul, discretize.coefficients)
    return "\n\n".join(_plain_source(fn) for fn in fns)


_TEMPLATES = {
    "c": ("obsdesign_controller.h", "obsdesign_controller.c"),
    "python": ("obsdesign_controller.py",),
    "octave": ("obsdesign_controller_init.m", "obsdesign_controller_step.m", "obsdesign_controller.m"),
    "js": ("obsdesign_controller.mjs",),
}
#: The languages of the generated controller: :data:`obsdesign.export.CONTROLLER_FORMATS`, in the
#: order of their templates (a test holds the two sets equal).
LANGUAGES = tuple(_TEMPLATES)


def controller_files(cfg, language: str, *, controller: str | None = None,
                     compensation: CompensationSpec | None = None, schedule: str | None = None,
                     estimator: str | None = None, waits: bool = False) -> dict[str, str]:
    """The sampled controller of the simulator's closed loop as source files of one language.

    Parameters
    ----------
    cfg : Config or SampledController
        The design (its ``name`` appears in comments only in sanitized form, :func:`sanitize_comment`),
        or the sampled controller itself (:func:`obsdesign.sampled.sampled_controller`; then none of
        the choices below).
    language : str
        The language of the files, a name of :data:`LANGUAGES`.
    controller : str, optional
        A name of :data:`EXPORTED_CONTROLLERS` (default ``pid+observer``), as in
        :func:`obsdesign.simulate`; ``pid`` still runs the estimator (for monitoring) but does not
        compensate.
    compensation : CompensationSpec, optional
        Knobs of the compensation law (``pid+observer`` only; default: the config's
        ``[compensation]`` section, as the simulator reads it).
    schedule : str, optional
        A name of :data:`SCHEDULE_NAMES` (default ``estimated``, with the reversal hysteresis of
        :data:`REVERSAL_NOISE_FACTOR` x ``sensor.noise_rms``), as the simulator's ``stiffness``;
        ``true`` is refused (it needs the simulated plant). Without effect for ``paper-k0`` and the
        baselines.
    estimator : str, optional
        A name of :data:`obsdesign.sampled.choices.ESTIMATORS` (default ``paper``), as the
        simulator's ``estimator``; a baseline is tuned by :func:`obsdesign.estimators.tune`.
    waits : bool
        The controller that waits, for a bench WITHOUT the drive's delay: the step returns the command
        of ``[hardware] delay_samples`` samples earlier, so that the bench runs the loop that
        ``simulate`` runs with the delay. Hardware that has the delay must not run it (the loop would
        have twice the delay, docs/delay.md); the CLI warns (``export --controller-waits``).

    Returns
    -------
    dict of str to str
        File name to text: ``c``: ``obsdesign_controller.h``, ``obsdesign_controller.c``;
        ``python``: ``obsdesign_controller.py``; ``octave``: ``obsdesign_controller_init.m``,
        ``obsdesign_controller_step.m`` (state in/out), ``obsdesign_controller.m`` (persistent state,
        for a Simulink MATLAB Function block); ``js``: ``obsdesign_controller.mjs``.

    Raises
    ------
    TypeError
        ``cfg`` is not a Config, ``compensation`` not a CompensationSpec or ``waits`` not a bool.
    ValueError
        Unknown language, controller, schedule or estimator; ``schedule='true'``; knobs other than
        the default with ``pid``; ``waits`` with a drive delay of 0.

    Examples
    --------
    >>> import obsdesign as od
    >>> text = controller_files(od.load_preset("vcm"), "python")["obsdesign_controller.py"]
    >>> namespace = {}
    >>> exec(compile(text, "obsdesign_controller.py", "exec"), namespace)
    >>> ctrl = namespace["Controller"]()
    >>> round(ctrl.step(1e-3, 0.0), 6)  # 1 mm error: kp e + ki e dt + G/K [V]
    2.036116
    >>> text = controller_files(od.load_preset("vcm"), "python", estimator="eso")["obsdesign_controller.py"]
    >>> exec(compile(text, "obsdesign_controller.py", "exec"), namespace)
    >>> round(namespace["Controller"]().step(1e-3, 0.0), 6)  # the first step: no estimate yet
    2.036116
    """
    language = check_choice("language", language, LANGUAGES)
    ctrl = exported_controller(cfg, controller=controller, compensation=compensation, schedule=schedule,
                               estimator=estimator)
    consts = controller_constants(ctrl)
    delay = check_waits(waits, ctrl)
    cfg, compensation = ctrl.config, ctrl.compensation
    controller, schedule, estimator = ctrl.controller, ctrl.schedule, ctrl.estimator
    baseline = ctrl.baseline is not None
    codes = {"SCHEDULE_" + name.upper().replace("-", "_"): SCHEDULES.code(name) for name in SCHEDULE_NAMES}
    codes["SCHEDULE_ZERO"] = SCHEDULE_ZERO
    ctx = {
        "name": sanitize_comment(cfg.name), "variant": cfg.observer.variant, "controller": controller,
        "estimator": estimator, "schedule": schedule, "baseline": baseline,
        "nz": int(consts["E_NZ"]) if baseline else 0,
        "compensation": compensation, "consts": {k: _literal(v) for k, v in consts.items()},
        "codes": {k: _literal(v) for k, v in codes.items()} if not baseline else {},
        "core": _c_core() if language == "c" and not baseline else "",
        "helpers": _python_helpers(baseline) if language == "python" else "",
        "terms": discretize._TERMS,
        "ffmode": compensation.mode != "observer" and controller == "pid+observer",
        "blend": compensation.mode == "blend" and controller == "pid+observer",
        "blend_viscous": cfg.observer.variant == "lag",
        "axis": axis_note(cfg), "delay": delay, "waits": waits,
    }
    env = _environment(cfg.units)
    return {name: env.get_template(name + ".j2").render(**ctx) for name in _TEMPLATES[language]}
