"""The ``REAL`` (float32) variant of the Structured Text controller: the ``cortex-m4f`` C's step for a PLC.

``real_block_files(cfg)`` (``export --format st --target real``) writes ``FB_ObsdesignController`` with no ``LREAL`` at all, for runtimes or
tasks where double precision is slow or absent: the arithmetic of the ``cortex-m4f`` C controller
(:mod:`obsdesign.export.mcu`, the one :class:`~obsdesign.export.mcu.Float32Profile` of numbers), statement
for statement, where ST allows it:

- the position in encoder counts (``DINT``; ``sensor.quantization`` is the count) and the observer in
  increment form, so float32 keeps its precision anywhere on the stroke; a counter that wraps is handled
  where the runtime wraps ``DINT`` arithmetic (two's complement, as TwinCAT and CODESYS do);
- compensated sums (the rounding carried in ``lo``) for ``v_hat``, ``f_hat``, the low-pass and the integral;
- the switched discretisation read from the same table of cubics in the stiffness (``OD_TABLE``, fitted in
  double at export time; its error bound in the header);
- the logarithm of the pre-sliding model: the same polynomial on the mantissa, the exponent found by
  halving or doubling (exact in float32) instead of reading the bits (ST has no portable bit cast), so the
  result is the C's to the bit for every normal float.

The header states the bound against the double controller that the tests hold it to (tests/test_export_st.py:
the block run in float32 on recorded inputs against the Python export, and against the ``cortex-m4f`` C
compiled on the host). Refused in one line where the ``cortex-m4f`` target refuses: a baseline estimator, a
compensation mode other than ``observer``, no encoder count.

Examples
--------
>>> import obsdesign as od
>>> text = real_block_files(od.load_preset("vcm"))["obsdesign_controller.st"]
>>> "LREAL" in text, "x_meas : DINT;" in text
(False, True)
"""

from __future__ import annotations

import numpy as np

from .controller import check_waits, exported_controller
from .mcu import float32_profile
from .mcu_tables import COEFFICIENT_NAMES
from .st import FB_NAME, _check_names, _header, _plcopen, _Pou, _st_text, _Var, st_literal
from .controller import _environment

__all__ = ["real_block_files", "REAL_BOUND_F_CF", "REAL_BOUND_COMMAND"]

#: The bound the tests hold the REAL block to against the double controller: the friction estimate within
#: this fraction of ``Cf`` ...
REAL_BOUND_F_CF = 1e-3
#: ... and the command within this fraction of ``u_max`` (the cortex-m4f C's bounds, tests/test_mcu_export.py).
REAL_BOUND_COMMAND = 1e-4


def _real(value: float) -> str:
    """An ST literal of the float32 nearest ``value`` (exact: the double of that float32, shortest form)."""
    return st_literal(float(np.float32(value)))


def _reals(*names: str, comment: str = "") -> tuple[_Var, ...]:
    return tuple(_Var(n, "REAL", None, comment) for n in names)


def _functions(p) -> tuple[_Pou, ...]:
    """``OD_Ln32``, ``OD_CoulombN32``, ``OD_Stiffness32``: the cortex-m4f C's helpers with their constants inline."""
    q = p.log.coefficients
    horner = _real(q[-1])
    for c in reversed(q[:-1]):
        horner = f"{_real(c)} + t * ({horner})"
    f = p.floats
    s_res, kappa, minus_s_cf = _real(f["S_RES"]), _real(f["KAPPA"]), _real(f["MINUS_S_CF"])
    ln = _Pou("OD_Ln32", "FUNCTION", (("VAR_INPUT", _reals("a")), ("VAR", _reals("m", "t") + (_Var("ex", "DINT"),))), f"""\
(* natural logarithm of a > 0 (a normal float): the exponent by exact halving/doubling, a polynomial on the mantissa *)
m := a;
ex := 0;
WHILE m >= 2.0 DO
    m := m * 0.5;
    ex := ex + 1;
END_WHILE;
WHILE m < 1.0 DO
    m := m * 2.0;
    ex := ex - 1;
END_WHILE;
IF m > {_real(f["SQRT2"])} THEN
    m := m * 0.5;
    ex := ex + 1;
END_IF;
t := m - 1.0;
OD_Ln32 := DINT_TO_REAL(ex) * {_real(f["LN2"])} + t * ({horner});
""", "REAL")
    args = (_Var("x", "DINT"), _Var("dir", "DINT"), _Var("x_r", "DINT"), _Var("f_r", "REAL"))
    coulomb = _Pou("OD_CoulombN32", "FUNCTION", (("VAR_INPUT", args), ("VAR", _reals("z", "fp", "dirf"))), f"""\
(* normalized Coulomb friction Fc/Cf on the branch (dir, x_r, f_r) at x [counts], eq:2:3:3-4 *)
IF dir = 0 THEN
    OD_CoulombN32 := f_r;
    RETURN;
END_IF;
dirf := DINT_TO_REAL(dir);
z := {s_res} * DINT_TO_REAL(x - x_r);
IF dirf * z >= 1.0 THEN
    OD_CoulombN32 := dirf;
    RETURN;
END_IF;
IF z = 0.0 THEN
    fp := f_r;
ELSE
    fp := ABS(dirf - f_r) * (z * (1.0 - OD_Ln32(ABS(z)))) + f_r;
END_IF;
IF fp > 1.0 THEN
    OD_CoulombN32 := 1.0;
ELSIF fp < -1.0 THEN
    OD_CoulombN32 := -1.0;
ELSE
    OD_CoulombN32 := fp;
END_IF;
""", "REAL")
    stiff = _Pou("OD_Stiffness32", "FUNCTION", (("VAR_INPUT", args), ("VAR", _reals("z", "ks", "dirf"))), f"""\
(* pre-sliding stiffness dFc/dx bounded by kappa (0 in gross sliding) at x [counts], eq:2:3:5 *)
IF dir = 0 THEN
    OD_Stiffness32 := {kappa};
    RETURN;
END_IF;
dirf := DINT_TO_REAL(dir);
z := {s_res} * DINT_TO_REAL(x - x_r);
IF dirf * z >= 1.0 THEN
    OD_Stiffness32 := 0.0;
ELSIF z = 0.0 THEN
    OD_Stiffness32 := {kappa};
ELSE
    ks := {minus_s_cf} * ABS(dirf - f_r) * OD_Ln32(ABS(z));
    IF ks > {kappa} THEN
        OD_Stiffness32 := {kappa};
    ELSIF ks < 0.0 THEN
        OD_Stiffness32 := 0.0;
    ELSE
        OD_Stiffness32 := ks;
    END_IF;
END_IF;
""", "REAL")
    return ln, coulomb, stiff


def real_block_files(cfg, *, controller: str | None = None, schedule: str | None = None,
                     estimator: str | None = None, waits: bool = False) -> dict[str, str]:
    """``obsdesign_controller.st`` and ``.xml`` of the REAL (float32) function block.

    Parameters
    ----------
    cfg : Config or SampledController
        The design (``sensor.quantization`` > 0: the encoder count), or the controller itself.
    controller, schedule, estimator, waits : optional
        As in :func:`obsdesign.export.controller.controller_files`; the estimator is one of
        :data:`obsdesign.export.mcu.MCU_ESTIMATORS`, the compensation mode ``observer``.

    Returns
    -------
    dict of str to str
        File name to text; the same inputs give the same text.

    Raises
    ------
    ValueError
        What the ``cortex-m4f`` target refuses (:func:`obsdesign.export.mcu.mcu_controller_files`), and
        the errors of :func:`obsdesign.export.st.st_files`.
    """
    ctrl = exported_controller(cfg, controller=controller, schedule=schedule, estimator=estimator)
    delay = check_waits(waits, ctrl)
    p = float32_profile(ctrl)
    comp, comp_on = ctrl.compensation, ctrl.controller == "pid+observer"
    cfg, u = ctrl.config, ctrl.config.units.unit
    inputs = (_Var("x_ref", "DINT", None, "set-point [counts]"), _Var("x_meas", "DINT", None, "encoder reading [counts]"))
    outputs = (_Var("command", "REAL", None, f"actuator command [{u('V')}], saturated, with G/K"),
               _Var("v_hat", "REAL", None, f"velocity estimate [{u('m/s')}]"),
               _Var("f_hat", "REAL", None, f"friction estimate [{u('N')}]"),
               _Var("f_hat_filtered", "REAL", None, f"friction estimate that compensates [{u('N')}]"))
    state = (_Var("started", "BOOL", "FALSE", "FALSE until the first call"), _Var("x_prev", "DINT", "0"),
             _Var("coef", "ARRAY[0..7] OF REAL", None, "the recursion: E (4), b_u (2), g_d (2)"),
             _Var("dir", "DINT", "0"), _Var("x_r", "DINT", "0"), _Var("x_ext", "DINT", "0"), *_reals("f_r"),
             *_reals("zf1", "zf2", "f_hat_prev", "integ", "deriv"), _Var("e_prev", "DINT", "0"),
             _Var("u", "REAL", None, f"net force the drive applies until the next call [{u('N')}]"),
             _Var("lo", "ARRAY[0..4] OF REAL", None, "rounding carried by v_hat, f_hat, zf1, zf2, integ"))
    temps = (*_reals("v", "f", "nu", "y", "sum", "t1", "t2", "fnew", "k", "xs", "ts", "e", "de", "integ_new",
                     "integ_lo", "u_volt", "total", "comp", "fade"),
             _Var("seg", "DINT"), _Var("j", "DINT"), _Var("p", "DINT"), _Var("dc", "DINT"), _Var("e_counts", "DINT"))
    if delay:
        state += (_Var("ring", f"ARRAY[0..{delay - 1}] OF REAL", None, f"the last {delay} commands [{u('V')}]"),
                  _Var("ring_i", "DINT", "0", "the oldest command of the ring"))
        temps += (*_reals("applied"), _Var("ri", "DINT"))
    constants = tuple(_Var("OD_" + key, "REAL", _real(value)) for key, value in p.floats.items())
    table = p.table.coefficients.reshape(p.table.segments, -1)
    constants += (_Var("OD_SEGMENTS", "DINT", str(p.table.segments)),
                  _Var("OD_REVERSAL_COUNTS", "DINT", str(p.reversal_counts)))
    # the table is filled at the first call (an initializer list of this length is slow to parse for blark)
    state += (_Var("OD_TABLE", f"ARRAY[0..{table.size - 1}] OF REAL", None,
                   "the cubic segments: 32 per segment, 4 powers of each of the 8 coefficients"),)
    fill = "".join(f"    OD_TABLE[{i}] := {_real(v)};\n" for i, v in enumerate(table.ravel()))
    body = _environment(cfg.units).get_template("obsdesign_controller_real.st.j2").render(fill=fill,
        schedule_code=p.schedule_code, comp_on=comp_on,
        comp_default=comp.gain == 1.0 and not comp.viscous and comp.deadzone == 0.0,
        comp_deadzone=comp_on and comp.deadzone > 0.0, comp_viscous=comp_on and comp.viscous, delay=delay, waits=waits)
    sections = (("VAR_INPUT", inputs), ("VAR_OUTPUT", outputs), ("VAR", state), ("VAR_TEMP", temps),
                ("VAR CONSTANT", constants))
    pous = (*_functions(p), _Pou(FB_NAME, "FUNCTION_BLOCK", sections, body))
    _check_names(pous)
    bounds = "; ".join(f"{name} {err:.3g}" for name, err in zip(COEFFICIENT_NAMES, p.table.max_error))
    plural = "s" if delay > 1 else ""
    wiring = (f"Inputs x_ref, x_meas [counts of {p.resolution!r} m, DINT]; output command [{u('V')}] (saturated, with "
              "the load feed-forward G/K), applied until the next call."
              + (f" The drive's delay of {delay} cycle{plural} is the hardware's: the estimator is fed the command of "
                 f"{delay} cycle{plural} earlier, the command is not delayed." if delay and not waits else "")
              + (f" THE BLOCK WAITS: it returns the command of {delay} cycle{plural} earlier, for a bench WITHOUT the "
                 "drive's delay; hardware that has the delay must not run it." if waits else ""))
    precision = (f"REAL (float32) profile: the cortex-m4f C's arithmetic in its order (counts, increment form, compensated "
                 f"sums, the discretisation from a table of {p.table.segments} cubic segments in the stiffness, largest "
                 f"error {bounds}; the logarithm a degree-{len(p.log.coefficients) - 1} polynomial, error "
                 f"{p.log.max_error:.2g}). Error bound against the double-precision controller, held by obsdesign's tests "
                 f"on recorded runs: friction estimate within {REAL_BOUND_F_CF:g} x Cf, command within "
                 f"{REAL_BOUND_COMMAND:g} x u_max.")
    header = _header(cfg, "controller", f"controller {ctrl.controller}, estimator {ctrl.estimator}, schedule "
                     f"{ctrl.schedule}, compensation {comp.mode}", FB_NAME, wiring, precision=precision)
    return {"obsdesign_controller.st": _st_text(pous, header), "obsdesign_controller.xml": _plcopen(pous, header)}
