"""Export the whole sampled controller (observer, low-pass, PID, compensation) as code.

One call of the generated ``step(x_ref, x_meas)`` per sample does what
:func:`obsdesign.sim.kernel.run_loop` does in steps 2 to 5 of its sample, in its order:

1. observer: at the first sample its state is set from the first measurement; after
   that the exact recursion advances it with the net force ``u`` of the previous sample
   (held) and the previous and new measurements; ``v_hat``, ``f_hat`` by eq:3:1:3;
2. low-pass eq:3:4:5 of ``f_hat`` (the simulator's FOH state-space recursion; it starts
   at zero and is first advanced at the second sample);
3. ``estimated`` stiffness schedule for the coming interval (branch from the measurement
   and the sign of ``v_hat``); the recursion is recomputed only when the stiffness changed;
4. parallel PID on ``e = x_ref - x_meas``: first-order filtered derivative (``e_prev = e``
   at the first sample), integral by conditional integration (kept only when the
   unsaturated command is within the limit), compensation ``comp / K`` (``pid+observer``),
   load feed-forward ``G / K``, saturation at ``u_max``; the net force ``K command - G``
   is kept for the next observer step.

The returned command [V] is after saturation and includes the feed-forward, so the
simulator's ``u`` column is ``K * command - G``.

Compensation law (the config's ``[compensation]`` section, :class:`~obsdesign.params.CompensationSpec`;
the defaults give the paper's law ``f_hat_filtered / K`` with exactly its operations)::

    fade = min(1, |v_hat| / deadzone)  if deadzone > 0 else 1
    comp = gain * (f_hat_filtered + (sigma * v_hat if viscous else 0)) * fade
    u_volt += comp / K

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
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..design.pid import pid_gains
from ..params import CompensationSpec, Config
from ..design import discretize
from ..design.discretize import lowpass_arrays
from ..friction import presliding as friction
from .codegen import _plain_source, export_spec
from .literals import NAME_MAX as _NAME_MAX
from .literals import comment_text

__all__ = ["CompensationSpec", "controller_files", "controller_constants", "sanitize_comment", "LANGUAGES",
           "CONTROLLERS"]

LANGUAGES = ("c", "python", "octave", "js")
CONTROLLERS = ("pid", "pid+observer")
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


def _choice(name: str, value, options) -> str:
    if not isinstance(value, str) or value not in options:
        raise ValueError(f"{name}: expected one of {', '.join(options)}, found {value!r}")
    return value


def controller_constants(cfg: Config, *, controller: str = "pid+observer",
                         compensation: CompensationSpec | None = None) -> dict[str, float]:
    """Every number of the generated controller, computed as :func:`obsdesign.simulate` computes it.

    Parameters
    ----------
    cfg : Config
        The design.
    controller : {'pid+observer', 'pid'}
        The controller.
    compensation : CompensationSpec, optional
        The compensation knobs (default: the config's ``[compensation]`` section).

    Keys are the constant names of the generated code (``DT``, ``KP``, ``A0_0``, ...);
    flags (``COMP_ON``, ``COMP_VISCOUS``) are 0.0 or 1.0.

    >>> import obsdesign as od
    >>> c = controller_constants(od.load_preset("vcm"), controller="pid")
    >>> c["COMP_ON"], round(c["KP"], 2), round(c["G"] / c["K"], 4)
    (0.0, 428.97, 1.6067)
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    controller = _choice("controller", controller, CONTROLLERS)
    if compensation is None:
        compensation = cfg.compensation if controller == "pid+observer" else CompensationSpec()
    if not isinstance(compensation, CompensationSpec):
        raise TypeError(f"compensation: expected a CompensationSpec, found {type(compensation).__name__}")
    if controller == "pid" and compensation != CompensationSpec():
        raise ValueError("compensation: only the controller 'pid+observer' compensates friction; "
                         "leave the default CompensationSpec() for 'pid'")
    spec = export_spec(cfg)
    arr = spec.arrays
    dt = spec.dt
    lp_phi, lp_g0, lp_g1 = lowpass_arrays(cfg.observer.omega_co, dt)
    _, _, kp, ki, kd = pid_gains(phi=cfg.phi, tau=cfg.pid.tau, max_S=cfg.pid.max_S,
                                 phase_margin_deg=cfg.pid.phase_margin_deg)
    tau_d = kd / kp / cfg.pid.derivative_N
    pl, fr = cfg.plant, cfg.friction
    consts = {
        "DT": dt, "K": pl.K, "G": pl.G, "U_MAX": pl.u_max, "CF": fr.Cf, "S": fr.s, "KAPPA": fr.kappa,
        "SIGMA": fr.sigma, "L1": spec.L1, "L2": spec.L2, "V_HAT0": 0.0, "F_HAT0": 0.0,
        "KP": kp, "KI": ki, "KD": kd, "ALPHA_D": math.exp(-dt / tau_d) if tau_d > 0.0 else 0.0,
        "COMP_ON": 1.0 if controller == "pid+observer" else 0.0, "COMP_GAIN": compensation.gain,
        "COMP_VISCOUS": 1.0 if compensation.viscous else 0.0, "COMP_DEADZONE": compensation.deadzone,
    }
    for name, values in (("A0", arr.A0.ravel()), ("A1", arr.A1.ravel()), ("B0", arr.b0), ("B1", arr.b1),
                         ("G0", arr.g0), ("G1", arr.g1), ("LP_PHI", lp_phi.ravel()), ("LP_G0", lp_g0),
                         ("LP_G1", lp_g1)):
        consts.update({f"{name}_{i}": float(v) for i, v in enumerate(values)})
    return {key: float(value) for key, value in consts.items()}


def _literal(value: float) -> str:
    """A floating-point literal valid in C, Python, Octave and JavaScript that round-trips exactly."""
    if not math.isfinite(value):
        raise ValueError(f"constant: expected a finite number, found {value!r}")
    return repr(float(value))


def _environment():
    from jinja2 import Environment, PackageLoader, StrictUndefined

    return Environment(loader=PackageLoader("obsdesign.export", "templates"), undefined=StrictUndefined,
                       keep_trailing_newline=True, autoescape=False, trim_blocks=True, lstrip_blocks=True)


def _c_core() -> str:
    from importlib import resources

    return resources.files("obsdesign.export").joinpath("c/obsdesign_core.inc").read_text(encoding="utf-8")


def _python_helpers() -> str:
    fns = (friction.presliding_shape, friction.coulomb_normalized, friction.stiffness, friction.track_reversal,
           discretize._mul, discretize.coefficients)
    return "\n\n".join(_plain_source(fn) for fn in fns)


_TEMPLATES = {
    "c": ("obsdesign_controller.h", "obsdesign_controller.c"),
    "python": ("obsdesign_controller.py",),
    "octave": ("obsdesign_controller_init.m", "obsdesign_controller_step.m", "obsdesign_controller.m"),
    "js": ("obsdesign_controller.mjs",),
}


def controller_files(cfg: Config, language: str, *, controller: str = "pid+observer",
                     compensation: CompensationSpec | None = None) -> dict[str, str]:
    """The sampled controller of the simulator's closed loop as source files of one language.

    Parameters
    ----------
    cfg : Config
        The design; its ``name`` appears in comments only in sanitized form (:func:`sanitize_comment`).
    language : {'c', 'python', 'octave', 'js'}
    controller : {'pid+observer', 'pid'}
        As in :func:`obsdesign.simulate`; ``pid`` still runs the observer (for monitoring) but
        does not compensate.
    compensation : CompensationSpec, optional
        Knobs of the compensation law (``pid+observer`` only; default: the config's
        ``[compensation]`` section, as the simulator reads it).

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
        ``cfg`` is not a Config or ``compensation`` not a CompensationSpec.
    ValueError
        Unknown language or controller; knobs other than the default with ``pid``.

    Examples
    --------
    >>> import obsdesign as od
    >>> text = controller_files(od.load_preset("vcm"), "python")["obsdesign_controller.py"]
    >>> namespace = {}
    >>> exec(compile(text, "obsdesign_controller.py", "exec"), namespace)
    >>> ctrl = namespace["Controller"]()
    >>> round(ctrl.step(1e-3, 0.0), 6)  # 1 mm error: kp e + ki e dt + G/K [V]
    2.036116
    """
    language = _choice("language", language, LANGUAGES)
    consts = controller_constants(cfg, controller=controller, compensation=compensation)
    compensation = CompensationSpec(gain=consts["COMP_GAIN"], viscous=consts["COMP_VISCOUS"] != 0.0,
                                    deadzone=consts["COMP_DEADZONE"])
    ctx = {
        "name": sanitize_comment(cfg.name), "variant": cfg.observer.variant, "controller": controller,
        "compensation": compensation, "consts": {k: _literal(v) for k, v in consts.items()},
        "core": _c_core() if language == "c" else "",
        "helpers": _python_helpers() if language == "python" else "",
        "terms": discretize._TERMS,
    }
    env = _environment()
    return {name: env.get_template(name + ".j2").render(**ctx) for name in _TEMPLATES[language]}
