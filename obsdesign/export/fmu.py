"""The sampled controller (or the observer alone) as an FMI 2.0 co-simulation FMU, built from the generated C.

The archive ``obsdesign_controller.fmu`` holds ``modelDescription.xml``, the sources
``obsdesign_controller.h/.c`` (the files of ``export --format c``, unchanged: one code path) and
``obsdesign_fmu.c`` (the FMI 2.0 interface around them), and, when a C compiler is found at export
time (``$CC``, else ``cc``), the shared library for this platform under ``binaries/``; without
one it is a source FMU that the importer compiles.

The FMU's step runs the controller once per communication step, which must be ``dt``
(``DefaultExperiment stepSize``; ``canHandleVariableCommunicationStepSize = false``). Inputs
``x_ref``, ``x_meas`` (and ``v_ref``, ``w_ff`` for the compensation modes ``feedforward``/``blend``),
outputs ``command``, ``v_hat``, ``f_hat``, ``f_hat_filtered``; the export's numbers are read-only
constants with their units (they are compiled into the C: a new value is a new export).

``fmu_archive(cfg, what="observer")`` wraps the observer's C export the same way
(``obsdesign_observer.fmu``: inputs ``u_prev``, ``x_meas``; outputs ``v_hat``, ``f_hat``).

The bytes depend on the inputs only: no path, no timestamp (the zip entries carry 1980-01-01),
and the ``guid`` is a hash of the archive's text.

Examples
--------
>>> import io, zipfile, obsdesign as od
>>> data = fmu_archive(od.load_preset("vcm"), binary=False)
>>> sorted(zipfile.ZipFile(io.BytesIO(data)).namelist())  # a source FMU
['modelDescription.xml', 'sources/obsdesign_controller.c', 'sources/obsdesign_controller.h', 'sources/obsdesign_fmu.c']
>>> data == fmu_archive(od.load_preset("vcm"), binary=False)
True
"""

from __future__ import annotations

import hashlib
import io
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from .._validate import check_choice
from .._version import __version__
from ..params import Config
from . import WHAT
from .codegen import c_files, export_spec
from .controller import _environment, _literal, controller_constants, controller_files, exported_controller
from .literals import comment_text

__all__ = ["FMU_NAME", "OBSERVER_FMU_NAME", "MODEL_IDENTIFIER", "fmu_archive", "fmu_platform"]

#: The archive's file name.
FMU_NAME = "obsdesign_controller.fmu"
#: The FMI model identifier: the shared library's base name and the prefix-free FMI 2.0 functions.
MODEL_IDENTIFIER = "obsdesign_controller"

#: The observer FMU's archive name.
OBSERVER_FMU_NAME = "obsdesign_observer.fmu"
_WHAT = tuple(w for w in WHAT if w != "friction-table")

#: Constants shown in the FMU: name -> (unit for a linear axis driven in V, description).
_CONSTANTS = {
    "DT": ("s", "sample time (the fixed communication step)"),
    "K": ("N/V", "actuator gain"),
    "G": ("N", "constant load, compensated by the feed-forward G/K"),
    "U_MAX": ("V", "command limit"),
    "KP": ("V/m", "PID proportional gain"),
    "KI": ("V/(m s)", "PID integral gain"),
    "KD": ("V s/m", "PID derivative gain"),
    "ALPHA_D": ("1", "derivative filter pole (discrete)"),
    "SIGMA": ("N s/m", "viscous friction coefficient"),
    "COMP_GAIN": ("1", "compensation gain"),
    "COMP_DEADZONE": ("m/s", "compensation fade-in speed (0: none)"),
    "CF": ("N", "Coulomb friction level"),
    "S": ("1/m", "pre-sliding shape parameter"),
    "KAPPA": ("N/m", "largest pre-sliding stiffness"),
    "REVERSAL_THRESHOLD": ("m", "reversal hysteresis of the stiffness schedule"),
}
_INPUTS = (("x_ref", "m", "set-point"), ("x_meas", "m", "measured position (encoder)"))
_FF_INPUTS = (("v_ref", "m/s", "reference velocity of the trajectory generator"),
              ("w_ff", "1", "feed-forward weight in [-1, 1] (reference_feedforward)"))
_OUTPUTS = (("command", "V", "actuator command: saturated, with the load feed-forward G/K", "command"),
            ("v_hat", "m/s", "velocity estimate", "v_hat"),
            ("f_hat", "N", "friction estimate", "f_hat"),
            ("f_hat_filtered", "N", "friction estimate that compensates", "f_hat_filtered"))
_OBSERVER_INPUTS = (("u_prev", "N", "net force K u - G held over the interval that ended at this sample"),
                    ("x_meas", "m", "measured position (encoder)"))
_OBSERVER_OUTPUTS = (("v_hat", "m/s", "velocity estimate", "obsdesign_observer_velocity(&m->c)"),
                     ("f_hat", "N", "friction estimate", "obsdesign_observer_friction(&m->c)"))


def fmu_platform() -> str | None:
    """The FMI 2.0 platform folder of this machine (``linux64``, ``darwin64``), None where not built.

    Examples
    --------
    >>> fmu_platform() in ("linux64", "linux32", "darwin64", "darwin32", None)
    True
    """
    bits = "64" if sys.maxsize > 2**32 else "32"
    if sys.platform.startswith("linux"):
        return "linux" + bits
    if sys.platform == "darwin":
        return "darwin" + bits
    return None


def _compiler() -> list[str] | None:
    cc = os.environ.get("CC") or "cc"
    argv = shlex.split(cc)
    return argv if argv and shutil.which(argv[0]) else None


@dataclass(frozen=True)
class _Model:
    """What one FMU wraps: the C files, the variables, the words of its descriptions."""

    identifier: str            # modelIdentifier: obsdesign_controller or obsdesign_observer
    module: str                # controller or observer
    cfg: Config
    sources: dict[str, str]
    inputs: list[dict]
    outputs: list[dict]        # each with "field": the C expression of its value
    constants: list[dict]
    choices: dict[str, str]    # provenance: the export's choices


def _variables(units, inputs, outputs, consts) -> tuple[list[dict], list[dict], list[dict]]:
    ins = [{"name": n, "unit": units.unit(u), "description": d, "vr": i + 1} for i, (n, u, d) in enumerate(inputs)]
    outs = [{"name": n, "unit": units.unit(u), "description": d, "field": f, "vr": 11 + i}
            for i, (n, u, d, f) in enumerate(outputs)]
    constants = [{"name": n, "unit": units.unit(u), "description": d, "vr": 101 + i, "value": _literal(consts[n])}
                 for i, (n, (u, d)) in enumerate(_CONSTANTS.items()) if n in consts]
    return ins, outs, constants


def _controller_model(cfg, choices, waits: bool = False) -> _Model:
    ctrl = exported_controller(cfg, **choices)
    ffmode = ctrl.controller == "pid+observer" and ctrl.compensation.mode != "observer"
    outputs = [(n, u, d, "m->c." + f) for n, u, d, f in _OUTPUTS]
    variables = _variables(ctrl.config.units, _INPUTS + (_FF_INPUTS if ffmode else ()), outputs,
                           controller_constants(ctrl))
    return _Model("obsdesign_controller", "controller", ctrl.config, dict(controller_files(ctrl, "c", waits=waits)),
                  *variables, {"controller": ctrl.controller, "estimator": ctrl.estimator, "schedule": ctrl.schedule,
                               "compensation": ctrl.compensation.mode, **({"waits": "yes"} if waits else {})})


def _observer_model(cfg, choices) -> _Model:
    given = {k: v for k, v in choices.items() if v is not None}
    if given:
        name = next(iter(given))
        raise ValueError(f"{name}: applies to what='controller' only, found {given[name]!r} with what='observer'")
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    spec = export_spec(cfg)
    fr = cfg.friction
    consts = {"DT": spec.dt, "CF": fr.Cf, "S": fr.s, "KAPPA": fr.kappa}
    variables = _variables(cfg.units, _OBSERVER_INPUTS, _OBSERVER_OUTPUTS, consts)
    return _Model("obsdesign_observer", "observer", cfg, dict(c_files(spec)), *variables,
                  {"schedule": "estimated"})


def _model_description(model: _Model, guid: str) -> str:
    cfg, inputs, outputs, constants = model.cfg, model.inputs, model.outputs, model.constants
    identifier = model.identifier
    dt = _literal(cfg.observer.dt)
    words = ", ".join(f"{k} {v}" for k, v in model.choices.items())
    desc = f"obsdesign {'sampled controller' if model.module == 'controller' else 'observer'}, {words}, " \
           f"config {comment_text(cfg.name)}"
    units = sorted({v["unit"] for v in inputs + outputs + constants})
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<fmiModelDescription fmiVersion="2.0" modelName="{identifier}" guid="{guid}"',
             f'  description={quoteattr(desc)}',
             f'  generationTool={quoteattr("obsdesign " + __version__)}',
             '  variableNamingConvention="flat" numberOfEventIndicators="0">',
             f'  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="false"',
             '    canGetAndSetFMUstate="false" canSerializeFMUstate="false" providesDirectionalDerivative="false">',
             '    <SourceFiles>', '      <File name="obsdesign_fmu.c"/>', f'      <File name="obsdesign_{model.module}.c"/>',
             '    </SourceFiles>', '  </CoSimulation>', '  <UnitDefinitions>']
    lines += [f'    <Unit name={quoteattr(u)}/>' for u in units]
    lines += ['  </UnitDefinitions>', f'  <DefaultExperiment startTime="0.0" stepSize="{dt}"/>', '  <VendorAnnotations>', '    <Tool name="obsdesign">',
              f'      <Provenance version={quoteattr(__version__)} config={quoteattr(comment_text(cfg.name))}'
              f' variant={quoteattr(cfg.observer.variant)} what="{model.module}"',
              '        ' + " ".join(f"{k}={quoteattr(v)}" for k, v in model.choices.items()) + "/>",
              '    </Tool>', '  </VendorAnnotations>', '  <ModelVariables>']

    def var(v, causality, variability, real):
        return [f'    <ScalarVariable name={quoteattr(v["name"])} valueReference="{v["vr"]}" '
                f'causality="{causality}" variability="{variability}"',
                f'      description={quoteattr(v["description"])}>',
                f'      <Real unit={quoteattr(v["unit"])}{real}/>', '    </ScalarVariable>']

    for v in inputs:
        lines += var(v, "input", "discrete", ' start="0.0"')
    for v in outputs:
        lines += var(v, "output", "discrete", "")
    for v in constants:
        lines += var(v, "local", "constant", f' start="{v["value"]}"')
    first_output = len(inputs) + 1
    lines += ['  </ModelVariables>', '  <ModelStructure>', '    <Outputs>']
    lines += [f'      <Unknown index="{first_output + i}" dependencies=""/>' for i in range(len(outputs))]
    lines += ['    </Outputs>', '    <InitialUnknowns>']
    lines += [f'      <Unknown index="{first_output + i}" dependencies=""/>' for i in range(len(outputs))]
    lines += ['    </InitialUnknowns>', '  </ModelStructure>', '</fmiModelDescription>', '']
    return "\n".join(lines)


def _zip(entries: dict[str, bytes]) -> bytes:
    """A zip of ``entries`` whose bytes depend on the entries only (sorted, fixed dates and modes)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as archive:
        for name in sorted(entries):
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.create_system = 3
            info.external_attr = 0o100644 << 16
            archive.writestr(info, entries[name], compresslevel=9)
    return buf.getvalue()


def _build(sources: dict[str, str], cc: list[str], identifier: str, module: str) -> bytes:
    """The shared library of ``sources`` (compiled in a temporary folder: no path reaches the binary)."""
    suffix = ".dylib" if sys.platform == "darwin" else ".so"
    with tempfile.TemporaryDirectory(prefix="obsdesign-fmu-") as tmp:
        for name, text in sources.items():
            (Path(tmp) / name).write_text(text, encoding="utf-8")
        out = identifier + suffix
        argv = [*cc, "-std=c99", "-O2", "-ffp-contract=off", "-fPIC", "-shared", "-o", out,
                "obsdesign_fmu.c", f"obsdesign_{module}.c", "-lm"]
        try:
            subprocess.run(argv, cwd=tmp, check=True, capture_output=True, text=True)
        except subprocess.CalledProcessError as exc:
            first = (exc.stderr or "").strip().splitlines()[:1]
            raise OSError(f"compiler: {shlex.join(argv)} failed: {first[0] if first else exc}") from exc
        return (Path(tmp) / out).read_bytes()


def fmu_archive(cfg, *, what: str = "controller", binary: bool | None = None, controller: str | None = None,
                schedule: str | None = None, estimator: str | None = None, waits: bool = False) -> bytes:
    """The FMU (FMI 2.0 co-simulation) of the exported controller or observer, as the bytes of its zip archive.

    Parameters
    ----------
    cfg : Config or SampledController
        The design, or the controller itself. With the drive's delay (``[hardware] delay_samples`` d > 0)
        the controller keeps its last d commands for its estimator (its output is not delayed).
    what : {'controller', 'observer'}
        ``controller`` (default): ``obsdesign_controller.fmu`` around the files of ``--format c --what
        controller``; ``observer``: ``obsdesign_observer.fmu`` around those of ``--format c`` (the
        observer alone, the simulator's default ``estimated`` schedule: inputs ``u_prev`` [N], the net force held over
        the interval just ended, and ``x_meas``; outputs ``v_hat``, ``f_hat``).
    binary : bool, optional
        True: compile the shared library for this platform (``$CC`` or ``cc``; an error if there is
        none); False: a source FMU; None (default): compile when a compiler is found.
    controller, schedule, estimator, waits : optional
        As in :func:`obsdesign.export.controller.controller_files` (``waits``: the controller that waits, for
        a bench without the drive's delay; controller only).

    Returns
    -------
    bytes
        The ``.fmu`` archive. The same inputs give the same bytes.

    Raises
    ------
    ValueError
        ``binary=True`` without a compiler or on a platform with no FMI folder;
        and the errors of :func:`~obsdesign.export.controller.controller_files`.
    OSError
        The compiler failed.
    """
    choices = {"controller": controller, "schedule": schedule, "estimator": estimator}
    if check_choice("what", what, _WHAT) == "observer":
        if waits:
            raise ValueError("waits: applies to what='controller' only, found True with what='observer'")
        model = _observer_model(cfg, choices)
    else:
        model = _controller_model(cfg, choices, waits)
    if binary not in (None, True, False):
        raise TypeError(f"binary: expected True, False or None, found {binary!r}")
    cc, platform = _compiler(), fmu_platform()
    if binary and (cc is None or platform is None):
        raise ValueError(f"binary: no C compiler ($CC or cc) or no FMI platform folder for {sys.platform!r}; "
                         "expected binary=False (a source FMU) or None")
    build = binary if binary is not None else (cc is not None and platform is not None)
    sources = dict(model.sources)

    def render(guid):
        wrapper = _environment(model.cfg.units).get_template("obsdesign_fmu.c.j2").render(
            name=comment_text(model.cfg.name), module=model.module,
            choices=", ".join(f"{k} {v}" for k, v in model.choices.items()), dt=_literal(model.cfg.observer.dt),
            guid=guid, inputs=model.inputs, outputs=model.outputs, constants=model.constants)
        return wrapper, _model_description(model, guid)

    digest = hashlib.sha256("\0".join((*render("{}"), *sources.values())).encode()).hexdigest()
    guid = "{" + str(uuid.UUID(digest[:32])) + "}"
    wrapper, xml = render(guid)
    sources["obsdesign_fmu.c"] = wrapper
    entries = {"modelDescription.xml": xml.encode()}
    entries.update({f"sources/{name}": text.encode() for name, text in sources.items()})
    if build and cc is not None and platform is not None:
        lib = _build(sources, cc, model.identifier, model.module)
        entries[f"binaries/{platform}/{model.identifier}{'.dylib' if sys.platform == 'darwin' else '.so'}"] = lib
    return _zip(entries)
