"""The sampled controller (or the observer alone) as IEC 61131-3 Structured Text, for a PLC or soft-motion runtime.

``FB_ObsdesignController`` runs what ``obsdesign_controller_step`` of the C export runs, statement
for statement (the C's helpers inlined, the schedule's branch chosen at export), in ``LREAL``
(IEEE 754 double, the host profile): its state lives in the block's ``VAR`` section, nothing is
allocated, the numbers are ``VAR CONSTANT``. Three helper functions (``OD_Shape``, ``OD_CoulombN``,
``OD_Stiffness``) carry the pre-sliding branch model. The same POUs are written as a plain
``obsdesign_controller.st`` (TwinCAT, Siemens SCL-type import, any text editor) and as PLCopen XML
(TC6 2.01, ``obsdesign_controller.xml``) for CODESYS-type runtimes. ``st_files(cfg, what="observer")``
writes ``FB_ObsdesignObserver``, the observer export's step, as ``obsdesign_observer.st``/``.xml``.

Every identifier the generator writes is checked against :data:`ST_KEYWORDS` and for a
case-insensitive clash (ST does not tell ``K`` from ``k``); user text (the config's name) reaches
only comments, through :func:`obsdesign.export.literals.comment_text`.

Examples
--------
>>> import obsdesign as od
>>> files = st_files(od.load_preset("vcm"))
>>> sorted(files)
['obsdesign_controller.st', 'obsdesign_controller.xml']
>>> "FUNCTION_BLOCK FB_ObsdesignController" in files["obsdesign_controller.st"]
True
>>> st_literal(1e-06), st_literal(-2.0)
('1.0E-06', '-2.0')
>>> check_st_identifier("elsif")
Traceback (most recent call last):
...
ValueError: identifier: 'elsif' is an IEC 61131-3 keyword or standard function name; expected another name
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

from .._validate import check_choice
from .._version import __version__
from ..params import Config
from ..sampled.choices import SCHEDULES
from .codegen import axis_note, export_spec
from . import WHAT
from .controller import SCHEDULE_ZERO, _environment, _literal, check_waits, controller_constants, exported_controller
from .literals import KEYWORDS, ST_LANGUAGE, comment_text

__all__ = ["ST_KEYWORDS", "FB_NAME", "OBSERVER_FB_NAME", "st_files", "st_literal", "check_st_identifier"]

_WHAT = tuple(w for w in WHAT if w != "friction-table")
#: The function blocks' names: the whole controller, the observer alone.
FB_NAME = "FB_ObsdesignController"
OBSERVER_FB_NAME = "FB_ObsdesignObserver"

#: IEC 61131-3 (3rd edition) keywords, elementary type names and standard function names, with the common
#: extensions of CODESYS/TwinCAT: no generated identifier may be one, in any case (the one list:
#: :data:`obsdesign.export.literals.KEYWORDS`).
ST_KEYWORDS = KEYWORDS[ST_LANGUAGE]
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def check_st_identifier(name: str) -> str:
    """``name`` if it is a valid ST identifier that is not in :data:`ST_KEYWORDS`; else a ValueError.

    Parameters
    ----------
    name : str
        An identifier the generator writes.

    Returns
    -------
    str
        ``name``.

    Raises
    ------
    ValueError
        Not letters, digits and single inner underscores, or a keyword or standard function name
        in any case.

    Examples
    --------
    >>> check_st_identifier("x_meas")
    'x_meas'
    >>> check_st_identifier("Exp")
    Traceback (most recent call last):
    ...
    ValueError: identifier: 'Exp' is an IEC 61131-3 keyword or standard function name; expected another name
    """
    if not isinstance(name, str) or not _IDENTIFIER.match(name) or "__" in name or name.endswith("_"):
        raise ValueError(f"identifier: expected letters, digits and single inner underscores (IEC 61131-3), "
                         f"found {name!r}")
    if name.upper() in ST_KEYWORDS:
        raise ValueError(f"identifier: {name!r} is an IEC 61131-3 keyword or standard function name; "
                         "expected another name")
    return name


def st_literal(value: float) -> str:
    """An ST ``LREAL`` literal of ``value`` that reads back exactly (a mantissa with a point, ``E`` exponent).

    Parameters
    ----------
    value : float
        A finite number.

    Returns
    -------
    str
        The shortest decimal that reads back as ``value``.

    Examples
    --------
    >>> st_literal(1e16), st_literal(0.0001)
    ('1.0E+16', '0.0001')
    """
    text = _literal(value)  # repr: shortest round-trip, finite only
    mantissa, _, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return mantissa + (f"E{exponent}" if exponent else "")


@dataclass(frozen=True)
class _Var:
    name: str
    type: str                  # LREAL, BOOL, DINT or ARRAY[0..n] OF LREAL
    init: str | None = None    # a literal
    comment: str = ""


@dataclass(frozen=True)
class _Pou:
    name: str
    kind: str                  # FUNCTION_BLOCK or FUNCTION
    sections: tuple[tuple[str, tuple[_Var, ...]], ...]   # (VAR_INPUT | VAR_OUTPUT | VAR | VAR_TEMP | VAR CONSTANT, vars)
    body: str
    returns: str | None = None


def _lreal(*names: str, comment: str = "") -> tuple[_Var, ...]:
    return tuple(_Var(n, "LREAL", None, comment) for n in names)


def _array(n: int, *names: str) -> tuple[_Var, ...]:
    return tuple(_Var(name, f"ARRAY[0..{n - 1}] OF LREAL") for name in names)


_FUNCTIONS = (
    _Pou("OD_Shape", "FUNCTION", (("VAR_INPUT", _lreal("z")),), """\
IF z = 0.0 THEN
    OD_Shape := 0.0;
ELSE
    OD_Shape := z * (1.0 - LN(ABS(z)));
END_IF;
""", "LREAL"),
    _Pou("OD_CoulombN", "FUNCTION", (("VAR_INPUT", _lreal("x", "dir", "xr", "fr", "s")), ("VAR", _lreal("z", "fp"))),
         """\
(* normalized Coulomb friction Fc/Cf on the branch (dir, xr, fr), eq:2:3:3-4 *)
IF dir = 0.0 THEN
    OD_CoulombN := fr;
ELSE
    z := s * (x - xr);
    IF dir * z >= 1.0 THEN
        OD_CoulombN := dir;
    ELSE
        fp := ABS(dir - fr) * OD_Shape(z) + fr;
        IF fp > 1.0 THEN
            OD_CoulombN := 1.0;
        ELSIF fp < -1.0 THEN
            OD_CoulombN := -1.0;
        ELSE
            OD_CoulombN := fp;
        END_IF;
    END_IF;
END_IF;
""", "LREAL"),
    _Pou("OD_Stiffness", "FUNCTION",
         (("VAR_INPUT", _lreal("x", "dir", "xr", "fr", "cf", "s", "kappa")), ("VAR", _lreal("z", "ks"))), """\
(* pre-sliding stiffness dFc/dx bounded by kappa (0 in gross sliding), eq:2:3:5 *)
IF dir = 0.0 THEN
    OD_Stiffness := kappa;
ELSE
    z := s * (x - xr);
    IF dir * z >= 1.0 THEN
        OD_Stiffness := 0.0;
    ELSIF z = 0.0 THEN
        OD_Stiffness := kappa;
    ELSE
        ks := -s * cf * ABS(dir - fr) * LN(ABS(z));
        IF ks > kappa THEN
            OD_Stiffness := kappa;
        ELSIF ks < 0.0 THEN
            OD_Stiffness := 0.0;
        ELSE
            OD_Stiffness := ks;
        END_IF;
    END_IF;
END_IF;
""", "LREAL"),
)


#: The temporaries of the observer's step and of the exact discretization for a new stiffness.
_SCHEDULE_TEMPS = (_lreal("t1", "t2", "ks", "fnew", "dx", "a11", "a12", "a21", "a22", "cb", "n1", "n2", "nrm", "pw",
                          "hs", "fact", "hc", "ih", "b1", "b2", "g1", "g2", "m0", "m1", "m2", "m3",
                          "q4", "q5", "q6", "q7", "q8", "q9", "q10", "q11")
                   + _array(4, "mb", "mp", "mq", "me", "mg", "mj", "mi", "mn")
                   + (_Var("sq", "DINT"), _Var("i", "DINT"), _Var("j", "DINT")))


def _block(ctrl, units, waits: bool = False) -> _Pou:
    consts = controller_constants(ctrl)
    baseline = ctrl.baseline is not None
    ffmode = ctrl.controller == "pid+observer" and ctrl.compensation.mode != "observer"
    blend = ffmode and ctrl.compensation.mode == "blend"
    u = units.unit
    inputs: tuple[_Var, ...] = (_Var("x_ref", "LREAL", None, f"set-point [{u('m')}]"),
              _Var("x_meas", "LREAL", None, f"measured position [{u('m')}]"))
    if ffmode:
        inputs += (_Var("v_ref", "LREAL", None, f"reference velocity [{u('m/s')}]"),
                   _Var("w_ff", "LREAL", None, "feed-forward weight, -1..1"))
    outputs = (_Var("command", "LREAL", None, f"actuator command [{u('V')}], saturated, with G/K"),
               _Var("v_hat", "LREAL", None, f"velocity estimate [{u('m/s')}]"),
               _Var("f_hat", "LREAL", None, f"friction estimate [{u('N')}]"),
               _Var("f_hat_filtered", "LREAL", None, f"friction estimate that compensates [{u('N')}]"))
    state: tuple[_Var, ...] = (_Var("started", "BOOL", "FALSE", "FALSE until the first call"),)
    temps: tuple[_Var, ...]
    if baseline:
        nz = int(consts["E_NZ"])
        state += _array(nz, "z") + _lreal("x_prev")
        temps = _array(nz, "t")
    else:
        state += _lreal("y1", "y2", "x_prev", "dir", "x_r", "f_r", "x_ext")
        state += (_Var("k", "LREAL", "-1.0", f"stiffness of the coming interval [{u('N/m')}]"),)
        state += _array(4, "phi") + _array(2, "bu", "gx0", "gx1") + _lreal("zf1", "zf2", "f_hat_prev")
        temps = _SCHEDULE_TEMPS
    state += _lreal("integ", "deriv", "e_prev", "u")
    delay = ctrl.delay_samples
    if delay:  # the last d commands: the drive's delay, the estimator's input only
        state += (_Var("ring", f"ARRAY[0..{delay - 1}] OF LREAL", None, f"the last {delay} commands [{u('V')}]"),
                  _Var("ring_i", "DINT", "0", "the oldest command of the ring"))
        temps += _lreal("applied") + (_Var("ri", "DINT"),)
    if blend:
        state += _lreal("zb1", "zb2", "fb_prev")
        temps += _lreal("fo")
    temps += _lreal("e", "integ_new", "u_volt", "total", "comp", "fade", "viscous")
    if ffmode:
        temps += _lreal("qv")
    constants = tuple(_Var("OD_" + k, "LREAL", st_literal(v)) for k, v in consts.items())
    code = consts.get("SCHEDULE")  # the branch the C selects by its constant OD_SCHEDULE
    # choice subset: the schedules with a branch of their own in the template ('constant' is the rest)
    kinds = {float(SCHEDULE_ZERO): "zero", **{float(SCHEDULES.code(n)): n for n in ("estimated", "estimated-raw")}}
    kind = kinds.get(code, "constant") if code is not None else ""
    env = _environment(units)
    body = env.get_template("obsdesign_controller_body.st.j2").render(
        observer_only=False, baseline=baseline, nz=int(consts.get("E_NZ", 0)), controller=ctrl.controller, ffmode=ffmode, blend=blend,
        blend_viscous=ctrl.config.observer.variant == "lag", compensation=ctrl.compensation, schedule_kind=kind,
        schedule_label=ctrl.schedule if ctrl.estimator == "paper" else "none: k = 0", delay=delay, waits=waits)
    sections = (("VAR_INPUT", inputs), ("VAR_OUTPUT", outputs), ("VAR", state), ("VAR_TEMP", temps),
                ("VAR CONSTANT", constants))
    return _Pou(FB_NAME, "FUNCTION_BLOCK", sections, body)


def _observer_block(cfg) -> _Pou:
    """``FB_ObsdesignObserver``: the observer export's step (obsdesign_observer.c), the simulator's default
    schedule ``estimated`` (its reversal hysteresis; at sign changes of ``v_hat`` where that is 0)."""
    spec = export_spec(cfg)
    u = cfg.units.unit
    fr = cfg.friction
    threshold = spec.reversal_threshold
    kind = "estimated" if threshold > 0.0 else "estimated-raw"
    consts = {"L1": spec.L1, "L2": spec.L2, "DT": spec.dt, "CF": fr.Cf, "S": fr.s, "KAPPA": fr.kappa,
              "REVERSAL_THRESHOLD": threshold}
    arrays = spec.arrays
    for name, values in (("A0", arrays.A0), ("A1", arrays.A1), ("B0", arrays.b0), ("B1", arrays.b1),
                         ("G0", arrays.g0), ("G1", arrays.g1)):
        consts.update({f"{name}_{i}": float(v) for i, v in enumerate(values.ravel())})
    inputs = (_Var("u_prev", "LREAL", None, f"net force held over the interval just ended [{u('N')}]"),
              _Var("x_meas", "LREAL", None, f"measured position [{u('m')}]"))
    outputs = (_Var("v_hat", "LREAL", None, f"velocity estimate [{u('m/s')}]"),
               _Var("f_hat", "LREAL", None, f"friction estimate [{u('N')}]"))
    state = ((_Var("started", "BOOL", "FALSE", "FALSE until the first call"),)
             + _lreal("y1", "y2", "x_prev", "dir", "x_r", "f_r", "x_ext")
             + (_Var("k", "LREAL", "-1.0", f"stiffness of the coming interval [{u('N/m')}]"),)
             + _array(4, "phi") + _array(2, "bu", "gx0", "gx1"))
    constants = tuple(_Var("OD_" + k, "LREAL", st_literal(float(v))) for k, v in consts.items())
    body = _environment(cfg.units).get_template("obsdesign_controller_body.st.j2").render(
        observer_only=True, baseline=False, schedule_kind=kind, schedule_label=f"estimated, reversal threshold {threshold:g}")
    sections = (("VAR_INPUT", inputs), ("VAR_OUTPUT", outputs), ("VAR", state), ("VAR_TEMP", _SCHEDULE_TEMPS),
                ("VAR CONSTANT", constants))
    return _Pou(OBSERVER_FB_NAME, "FUNCTION_BLOCK", sections, body)


def _check_names(pous: tuple[_Pou, ...]) -> None:
    for pou in pous:
        seen: dict[str, str] = {pou.name.upper(): pou.name}
        for other in pous:
            seen.setdefault(other.name.upper(), other.name)
        for _, variables in pou.sections:
            for var in variables:
                key = check_st_identifier(var.name).upper()
                if key in seen and seen[key] != pou.name:
                    raise ValueError(f"identifier: {var.name!r} clashes with {seen[key]!r} in {pou.name} "
                                     "(ST is case-insensitive); expected distinct names")
                seen[key] = var.name
        check_st_identifier(pou.name)


_LREAL_PRECISION = ("LREAL (IEEE 754 double): the operations of the C and Python exports in their order; obsdesign's "
                    "tests run this text on recorded inputs and match the Python export within 1e-12 relative.")


def _header(cfg, module: str, choices: str, fb: str, wiring: str, *, precision: str = _LREAL_PRECISION) -> str:
    axis = axis_note(cfg)
    what = "the sampled controller of obsdesign's closed loop" if module == "controller" else "the friction observer"
    lines = [f"obsdesign_{module}.st: {what}, generated by obsdesign {__version__}.",
             f"Config {comment_text(cfg.name)}, variant {cfg.observer.variant}, {choices}.",
             *([axis + "."] if axis else []),
             f"Cycle time: call {fb} exactly once per dt = {_literal(cfg.observer.dt)} s (the task's cycle; "
             "the constants are for that period).",
             wiring,
             precision,
             "No dynamic memory: the state is the block's VAR section; a new instance starts at its first call."]
    if any("(*" in line or "*)" in line for line in lines):
        raise ValueError("comment: the header would open or close a comment; expected plain text")
    return "\n".join("(* " + line + " *)" for line in lines) + "\n"


def _declarations(pou: _Pou) -> str:
    out = []
    for section, variables in pou.sections:
        if not variables:
            continue
        out.append(section)
        for v in variables:
            init = f" := {v.init}" if v.init is not None else ""
            comment = f"  (* {v.comment} *)" if v.comment else ""
            out.append(f"    {v.name} : {v.type}{init};{comment}")
        out.append("END_VAR")
    return "\n".join(out) + "\n"


def _st_text(pous: tuple[_Pou, ...], header: str) -> str:
    parts = [header]
    for pou in pous:
        head = f"{pou.kind} {pou.name}" + (f" : {pou.returns}" if pou.returns else "")
        parts.append(f"\n{head}\n{_declarations(pou)}{pou.body}END_{pou.kind}\n")
    return "".join(parts)


_XML_SECTIONS = {"VAR_INPUT": "inputVars", "VAR_OUTPUT": "outputVars", "VAR": "localVars", "VAR_TEMP": "tempVars",
                 "VAR CONSTANT": "localVars"}
_XHTML = 'xmlns:xhtml="http://www.w3.org/1999/xhtml"'


def _xml_type(type_: str) -> str:
    m = re.fullmatch(r"ARRAY\[0\.\.(\d+)\] OF (\w+)", type_)
    if m:
        return (f'<array><dimension lower="0" upper="{m.group(1)}"/><baseType><{m.group(2)}/></baseType>'
                '</array>')
    return f"<{type_}/>"


def _xml_value(init: str) -> str:
    if init.startswith("["):  # an array's initial values
        return "<arrayValue>" + "".join(f'<value><simpleValue value="{v.strip()}"/></value>'
                                        for v in init[1:-1].split(",")) + "</arrayValue>"
    return f'<simpleValue value="{init}"/>'


def _plcopen(pous: tuple[_Pou, ...], header: str) -> str:
    lines = ['<?xml version="1.0" encoding="utf-8"?>',
             '<project xmlns="http://www.plcopen.org/xml/tc6_0201">',
             # the schema requires a date: a fixed one, so that the same inputs give the same bytes
             f'  <fileHeader companyName="obsdesign" productName="obsdesign" productVersion={quoteattr(__version__)}'
             ' creationDateTime="1970-01-01T00:00:00"/>',
             '  <contentHeader name="obsdesign_controller">',
             '    <coordinateInfo><fbd><scaling x="1" y="1"/></fbd><ld><scaling x="1" y="1"/></ld>'
             '<sfc><scaling x="1" y="1"/></sfc></coordinateInfo>',
             '  </contentHeader>', '  <types>', '    <dataTypes/>', '    <pous>']
    for pou in pous:
        kind = "functionBlock" if pou.kind == "FUNCTION_BLOCK" else "function"
        lines.append(f'      <pou name="{pou.name}" pouType="{kind}">')
        lines.append('        <interface>')
        if pou.returns:
            lines.append(f'          <returnType><{pou.returns}/></returnType>')
        for section, variables in pou.sections:
            if not variables:
                continue
            tag = _XML_SECTIONS[section]
            lines.append(f'          <{tag}{" constant=" + chr(34) + "true" + chr(34) if section == "VAR CONSTANT" else ""}>')
            for v in variables:
                lines.append(f'            <variable name="{v.name}"><type>{_xml_type(v.type)}</type>'
                             + (f'<initialValue>{_xml_value(v.init)}</initialValue>' if v.init else "")
                             + (f'<documentation><xhtml:p {_XHTML}>{escape(v.comment)}</xhtml:p></documentation>'
                                if v.comment else "") + '</variable>')
            lines.append(f'          </{tag}>')
        lines.append('        </interface>')
        body = pou.body if pou.kind == "FUNCTION" else header + pou.body
        lines.append(f'        <body><ST><xhtml:p {_XHTML}><![CDATA[{body}]]></xhtml:p></ST></body>')
        lines.append('      </pou>')
    lines += ['    </pous>', '  </types>', '  <instances><configurations/></instances>', '</project>', '']
    return "\n".join(lines)


def st_files(cfg, *, what: str = "controller", controller: str | None = None, schedule: str | None = None,
             estimator: str | None = None, waits: bool = False) -> dict[str, str]:
    """``obsdesign_controller.st`` and its PLCopen XML ``obsdesign_controller.xml`` (or ``obsdesign_observer.*``).

    Parameters
    ----------
    cfg : Config or SampledController
        The design, or the controller itself. With the drive's delay (``[hardware] delay_samples`` d > 0)
        the block keeps its last d commands for its estimator (the command it returns is not delayed).
    what : {'controller', 'observer'}
        ``controller`` (default): ``FB_ObsdesignController``, the whole sampled controller;
        ``observer``: ``FB_ObsdesignObserver``, the observer export's step (inputs ``u_prev``,
        ``x_meas``; outputs ``v_hat``, ``f_hat``; the simulator's default ``estimated`` schedule).
    controller, schedule, estimator, waits : optional
        As in :func:`obsdesign.export.controller.controller_files` (``waits``: the block that waits, for a
        bench without the drive's delay; controller only).

    Returns
    -------
    dict of str to str
        File name to text; the same inputs give the same text.

    Raises
    ------
    ValueError
        A generated identifier that is an ST keyword or clashes, and the
        errors of :func:`~obsdesign.export.controller.controller_files`.
    """
    if check_choice("what", what, _WHAT) == "observer":
        given = {k: v for k, v in (("controller", controller), ("schedule", schedule), ("estimator", estimator),
                                   ("waits", waits or None)) if v is not None}
        if given:
            name = next(iter(given))
            raise ValueError(f"{name}: applies to what='controller' only, found {given[name]!r} with what='observer'")
        if not isinstance(cfg, Config):
            raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
        pous = (*_FUNCTIONS, _observer_block(cfg))
        u = cfg.units.unit
        header = _header(cfg, "observer", "schedule estimated", OBSERVER_FB_NAME,
                         f"Inputs u_prev [{u('N')}] (the net force K command - G held over the interval just ended), "
                         f"x_meas [{u('m')}]; outputs v_hat [{u('m/s')}], f_hat [{u('N')}].")
    else:
        ctrl = exported_controller(cfg, controller=controller, schedule=schedule, estimator=estimator)
        d = check_waits(waits, ctrl)
        pous = (*_FUNCTIONS, _block(ctrl, ctrl.config.units, waits))
        cfg, u = ctrl.config, ctrl.config.units.unit
        plural = "s" if d > 1 else ""
        delay_note = (f" The drive's delay of {d} cycle{plural} ([hardware] delay_samples) is the hardware's: the "
                      f"command is not delayed here, the estimator is fed the command the drive applies (that of "
                      f"{d} cycle{plural} earlier)." if d and not waits else "")
        if waits:
            delay_note = (f" THE BLOCK WAITS: it returns the command of {d} cycle{plural} earlier (export "
                          "--controller-waits), for a bench WITHOUT the drive's delay; hardware that has the delay "
                          "must not run it (the loop would have twice the delay).")
        header = _header(cfg, "controller", f"controller {ctrl.controller}, estimator {ctrl.estimator}, schedule "
                         f"{ctrl.schedule}, compensation {ctrl.compensation.mode}", FB_NAME,
                         f"Inputs x_ref, x_meas [{u('m')}]; output command [{u('V')}] (saturated, with the load "
                         "feed-forward G/K), applied until the next call." + delay_note)
    _check_names(pous)
    module = pous[-1].name.removeprefix("FB_Obsdesign").lower()
    return {f"obsdesign_{module}.st": _st_text(pous, header), f"obsdesign_{module}.xml": _plcopen(pous, header)}
