"""The controller for a drive's microcontroller: the ``cortex-m4f`` target of the C controller export.

:func:`mcu_controller_files` writes ``obsdesign_controller.h/.c`` for a Cortex-M4F (or any core with a
single-precision FPU) from the one :class:`~obsdesign.sampled.SampledController` the simulator runs:
float32 only, no library call, no division, a fixed cost per sample. What it changes against the host
export (``--target host``, double, bit-exact with :func:`obsdesign.simulate`):

- the position is read in encoder counts (``sensor.quantization`` is the count) and the observer runs in
  increment form, so float32 keeps its precision anywhere on the stroke (:mod:`.mcu_tables`);
- the exact switched discretisation is read from a table of cubics in the stiffness fitted at export
  time, with the error bound written into the header (:func:`~.mcu_tables.stiffness_table`);
- the logarithm of the pre-sliding stiffness is a fitted polynomial (:func:`~.mcu_tables.log_polynomial`);
- every constant quotient (``1 / K``, ``G / K``, ``(1 - alpha_d) / dt``) is computed here in double.

It runs the paper's observer (``paper``, ``paper-k0``) with the compensation mode ``observer`` (gain,
viscous term, deadzone); the baselines and the feed-forward modes stay on the host target.

Examples
--------
>>> import obsdesign as od
>>> files = mcu_controller_files(od.load_preset("vcm"))
>>> sorted(files)
['obsdesign_controller.c', 'obsdesign_controller.h']
>>> "double" in files["obsdesign_controller.c"]
False
>>> mcu_controller_files(od.load_preset("table1"))
Traceback (most recent call last):
...
ValueError: sensor.quantization: the cortex-m4f target reads the position in encoder counts; expected the count [m] > 0, found 0.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sampled.choices import ESTIMATORS, SCHEDULES
from ..sampled.controller import SampledController
from .controller import SCHEDULE_ZERO, check_waits, controller_constants, exported_controller, sanitize_comment, _environment
from . import TARGETS
from .codegen import axis_note
from .mcu_tables import COEFFICIENT_NAMES, _CHECK_POINTS, LogPolynomial, StiffnessTable, log_polynomial, stiffness_table

__all__ = ["mcu_controller_files", "float32_profile", "Float32Profile", "TARGETS", "MCU_ESTIMATORS", "float_literal"]

#: The estimators the ``cortex-m4f`` target runs: the paper's entries of the registry (not the baselines).
MCU_ESTIMATORS = tuple(name for name in ESTIMATORS.names() if not ESTIMATORS[name].baseline)


def float_literal(value: float) -> str:
    """A C float literal (``f`` suffix) that rounds to the float32 nearest ``value``.

    Parameters
    ----------
    value : float
        A finite number within float32's range.

    Examples
    --------
    >>> float_literal(0.1), float_literal(2.0), float_literal(-3e-9)
    ('0.100000001f', '2.0f', '-3.00000003e-09f')
    """
    value = float(value)
    if not math.isfinite(value) or abs(value) > float(np.finfo(np.float32).max):
        raise ValueError(f"constant: expected a finite number within float32's range, found {value!r}")
    text = f"{float(np.float32(value)):.9g}"
    if not any(ch in text for ch in ".e"):
        text += ".0"
    return text + "f"


def _check(ctrl: SampledController) -> float:
    if ctrl.estimator not in MCU_ESTIMATORS:
        raise ValueError(f"estimator: the cortex-m4f target runs the paper observer; expected one of "
                         f"{', '.join(MCU_ESTIMATORS)}, found {ctrl.estimator!r} (the baselines export with --target host)")
    if ctrl.controller == "pid+observer" and ctrl.compensation.mode != "observer":
        raise ValueError(f"compensation.mode: the cortex-m4f target compensates with the observer's estimate; "
                         f"expected 'observer', found {ctrl.compensation.mode!r}")
    res = float(ctrl.config.sensor.quantization)
    if not res > 0.0:
        raise ValueError(f"sensor.quantization: the cortex-m4f target reads the position in encoder counts; "
                         f"expected the count [m] > 0, found {res!r}")
    return res


@dataclass(frozen=True)
class Float32Profile:
    """The numbers of the float32 controller (the ``cortex-m4f`` C and the ST ``REAL`` block): one definition.

    Attributes
    ----------
    resolution : float
        The encoder count [m].
    host : dict
        :func:`~obsdesign.export.controller.controller_constants` of the controller (double).
    table : StiffnessTable
        The cubic segments of the discretisation (:func:`~.mcu_tables.stiffness_table`).
    log : LogPolynomial
        The logarithm on the mantissa (:func:`~.mcu_tables.log_polynomial`).
    floats : dict
        Every constant of the step (quotients computed here in double), to be rounded to float32.
    schedule_code : str
        ``hysteresis``, ``raw``, ``constant`` or ``zero``.
    reversal_counts : int
        The reversal threshold [counts].
    """

    resolution: float
    host: dict
    table: StiffnessTable
    log: LogPolynomial
    floats: dict
    schedule_code: str
    reversal_counts: int


def float32_profile(ctrl: SampledController, *, segments: int = 16) -> Float32Profile:
    """The float32 profile's numbers of ``ctrl`` (checked: paper observer, mode ``observer``, an encoder count).

    Parameters
    ----------
    ctrl : SampledController
        The exported controller (:func:`~obsdesign.export.controller.exported_controller`).
    segments : int
        Cubic segments of the stiffness table.

    Returns
    -------
    Float32Profile

    Examples
    --------
    >>> import obsdesign as od
    >>> p = float32_profile(exported_controller(od.load_preset("vcm")))
    >>> p.schedule_code, p.floats["RES"], p.table.segments
    ('raw', 1e-06, 16)
    """
    res = _check(ctrl)
    delay = ctrl.delay_samples
    host = controller_constants(ctrl)  # the numbers of the simulator's controller, in double
    table = stiffness_table(ctrl, segments=segments)
    log = log_polynomial()
    # the shape of the generated schedule, from the code the host export runs (paper-k0: SCHEDULE_ZERO)
    code = int(host["SCHEDULE"])
    # choice subset: the template's three shapes of the runnable schedules
    shapes = {SCHEDULES.code("estimated"): "hysteresis", SCHEDULES.code("estimated-raw"): "raw",
              SCHEDULES.code("constant"): "constant", SCHEDULE_ZERO: "zero"}
    schedule_code = shapes[code]
    threshold = host["REVERSAL_THRESHOLD"] / res  # [counts]; a reversal needs more than that
    near = round(threshold)
    reversal_counts = int(near) if abs(threshold - near) <= 1e-9 * max(1.0, threshold) else int(math.floor(threshold))
    if reversal_counts >= 2**31 - 1:
        raise ValueError(f"sensor.noise_rms: the reversal threshold must be below 2^31 counts, found {reversal_counts}")
    K, dt = host["K"], host["DT"]
    floats = {
        "RES": res, "DT": dt, "K": K, "G": host["G"], "INV_K": 1.0 / K, "G_OVER_K": host["G"] / K,
        "U_MAX": host["U_MAX"], "SIGMA": host["SIGMA"], "V_HAT0": host["V_HAT0"], "F_HAT0": host["F_HAT0"],
        "KP": host["KP"], "KI": host["KI"], "KD": host["KD"], "ALPHA_D": host["ALPHA_D"],
        "DERIV_GAIN": (1.0 - host["ALPHA_D"]) / dt, "COMP_GAIN": host["COMP_GAIN"],
        "INV_COMP_DEADZONE": 1.0 / host["COMP_DEADZONE"] if host["COMP_DEADZONE"] > 0 else 0.0,
        "KAPPA": host["KAPPA"], "S_RES": host["S"] * res, "MINUS_S_CF": -host["S"] * host["CF"],
        "SEGMENTS_PER_KAPPA": table.segments / table.kappa, "SQRT2": math.sqrt(2.0), "LN2": math.log(2.0),
        "LP_PHI_0M1": host["LP_PHI_0"] - 1.0, "LP_PHI_3M1": host["LP_PHI_3"] - 1.0,
        **{f"LP_{name}": host[f"LP_{name}"] for name in ("PHI_1", "PHI_2", "G0_0", "G0_1", "G1_0", "G1_1")},
        **({"DRIVE_HOLD": host["DRIVE_HOLD"]} if delay else {}),
    }
    return Float32Profile(resolution=res, host=host, table=table, log=log, floats=floats,
                          schedule_code=schedule_code, reversal_counts=reversal_counts)


def mcu_controller_files(cfg, *, controller: str | None = None, schedule: str | None = None,
                         estimator: str | None = None, segments: int = 16, waits: bool = False) -> dict[str, str]:
    """``obsdesign_controller.h`` and ``.c`` of the ``cortex-m4f`` target (float32, counts, tabulated).

    Parameters
    ----------
    cfg : Config or SampledController
        The design (``sensor.quantization`` > 0: the encoder count), or the controller itself
        (:func:`obsdesign.export.controller.exported_controller`; then none of the choices below).
    controller, schedule, estimator : str, optional
        As in :func:`obsdesign.export.controller.controller_files`; the estimator is one of
        :data:`MCU_ESTIMATORS`.
    segments : int
        Cubic segments of the stiffness table (:func:`~obsdesign.export.mcu_tables.stiffness_table`).
    waits : bool
        The controller that waits, for a bench without the drive's delay (as in
        :func:`obsdesign.export.controller.controller_files`). With the drive's delay d > 0 the state
        holds a ring of the last d commands for the estimator (4 d + 4 bytes more).

    Returns
    -------
    dict of str to str
        File name to text.

    Raises
    ------
    TypeError
        ``cfg`` is not a Config or SampledController.
    ValueError
        A choice the target does not run (a baseline, a feed-forward compensation mode), no encoder
        count (``sensor.quantization = 0``), a constant beyond float32's range.
    """
    ctrl = exported_controller(cfg, controller=controller, schedule=schedule, estimator=estimator)
    delay = check_waits(waits, ctrl)
    p = float32_profile(ctrl, segments=segments)
    res, host, table, log, floats = p.resolution, p.host, p.table, p.log, p.floats
    schedule_code, reversal_counts = p.schedule_code, p.reversal_counts
    dt = host["DT"]
    comp, comp_on = ctrl.compensation, ctrl.controller == "pid+observer"
    consts = {key: float_literal(v) for key, v in floats.items()}
    consts["SEGMENTS"] = str(table.segments)
    consts["REVERSAL_COUNTS"] = f"{reversal_counts}L" if reversal_counts > 32767 else str(reversal_counts)
    q = log.coefficients
    horner = float_literal(q[-1])
    for c in reversed(q[:-1]):
        horner = f"{float_literal(c)} + t * ({horner})"
    rows = [", ".join(float_literal(v) for v in table.coefficients[i].ravel()) for i in range(table.segments)]
    bound_lines = [f"{name:<4} {err:.3g} (relative {err / s if s > 0 else 0.0:.2g})"
                   for name, err, s in zip(COEFFICIENT_NAMES, table.max_error, table.scale)]
    count_force = float(np.max(np.abs(table.coefficients[:, 7, 0]))) * res  # g_d2 x one count [N]
    cfg = ctrl.config
    ctx = {
        "name": sanitize_comment(cfg.name), "variant": cfg.observer.variant, "controller": ctrl.controller,
        "estimator": ctrl.estimator, "schedule": ctrl.schedule if ctrl.estimator == "paper" else "zero (paper-k0)",
        "dt": repr(dt), "resolution": repr(res), "kappa": repr(table.kappa), "axis": axis_note(cfg),
        "segments": table.segments, "check_points": _CHECK_POINTS, "bound_lines": bound_lines,
        "log_degree": len(q) - 1, "log_error": f"{log.max_error:.2g}",
        "count_force": f"{count_force:.3g}", "count_force_cf": f"{count_force / host['CF'] * 100:.3g}",
        "resolution_literal": float_literal(res), "dt_literal": float_literal(dt),
        "consts": consts, "table": rows, "log_horner": horner, "schedule_code": schedule_code,
        "comp_on": comp_on, "comp_default": comp.gain == 1.0 and not comp.viscous and comp.deadzone == 0.0,
        "comp_deadzone": comp_on and comp.deadzone > 0.0, "comp_viscous": comp_on and comp.viscous,
        "delay": delay, "waits": waits,
    }
    env = _environment(cfg.units)
    return {name: env.get_template(name.replace(".", "_m4f.") + ".j2").render(**ctx)
            for name in ("obsdesign_controller.h", "obsdesign_controller.c")}
