"""The sampled controller (or the observer alone) as an FMI 2.0 or 3.0 co-simulation FMU, built from the generated C.

The archive ``obsdesign_controller.fmu`` holds ``modelDescription.xml``, the sources
``obsdesign_controller.h/.c`` (the files of ``export --format c``, unchanged: one code path) and
``obsdesign_fmu.c`` (the FMI interface around them), and, when a C compiler is found at export
time (``$CC``, else ``cc``), the shared library for this platform under ``binaries/``; without
one it is a source FMU that the importer compiles. ``fmi_version="3"`` (:data:`obsdesign.export.FMI_VERSIONS`)
writes the FMI 3.0 FMU of the same C files: only ``obsdesign_fmu.c`` and ``modelDescription.xml`` differ (and
FMI 3.0's ``sources/buildDescription.xml`` and platform folder, ``binaries/x86_64-linux``).

The FMU's step runs the controller once per communication step, which must be ``dt``
(``DefaultExperiment stepSize``; ``canHandleVariableCommunicationStepSize = false``). Inputs
``x_ref``, ``x_meas`` (and ``v_ref``, ``w_ff`` for the compensation modes ``feedforward``/``blend``),
outputs ``command``, ``v_hat``, ``f_hat``, ``f_hat_filtered``; the export's numbers are read-only
constants with their units (causality ``local``, variability ``constant``: they are compiled into the C, and the
controller's coefficients are derived from them at export time, so a new value is a new export).

``fmu_archive(cfg, what="observer")`` wraps the observer's C export the same way
(``obsdesign_observer.fmu``: inputs ``u_prev``, ``x_meas``; outputs ``v_hat``, ``f_hat``).

The bytes depend on the inputs only: no path, no timestamp (the zip entries carry 1980-01-01),
and the ``guid`` (FMI 3.0: ``instantiationToken``) is a hash of the archive's text.

Examples
--------
>>> import io, zipfile, obsdesign as od
>>> data = fmu_archive(od.load_preset("vcm"), binary=False)
>>> sorted(zipfile.ZipFile(io.BytesIO(data)).namelist())  # a source FMU
['modelDescription.xml', 'sources/obsdesign_controller.c', 'sources/obsdesign_controller.h', 'sources/obsdesign_fmu.c']
>>> data == fmu_archive(od.load_preset("vcm"), binary=False)
True
>>> fmi3 = zipfile.ZipFile(io.BytesIO(fmu_archive(od.load_preset("vcm"), binary=False, fmi_version="3")))
>>> fmi3.read("sources/obsdesign_controller.c") == zipfile.ZipFile(io.BytesIO(data)).read(
...     "sources/obsdesign_controller.c")
True
>>> sorted(fmi3.namelist())[-1]
'sources/obsdesign_fmu.c'
"""

from __future__ import annotations

import hashlib
import io
import os
import platform
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
from . import FMI_VERSIONS, WHAT
from .codegen import c_files, export_spec
from .controller import _environment, _literal, controller_constants, controller_files, exported_controller
from .literals import comment_text

__all__ = ["FMU_NAME", "OBSERVER_FMU_NAME", "MODEL_IDENTIFIER", "fmu_archive", "fmu_platform"]

#: The archive's file name.
FMU_NAME = "obsdesign_controller.fmu"
#: The FMI model identifier: the shared library's base name (the FMI functions are not prefixed).
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


def fmu_platform(fmi_version: str = FMI_VERSIONS[0]) -> str | None:
    """The platform folder of this machine under ``binaries/``, None where the export builds no binary.

    FMI 2.0: ``linux64``, ``darwin64`` (32-bit: ``linux32``, ``darwin32``); FMI 3.0: the platform tuple
    ``x86_64-linux``, ``aarch64-linux``, ``x86_64-darwin``, ``aarch64-darwin`` (``x86-linux`` on 32 bits).

    Parameters
    ----------
    fmi_version : str
        One of :data:`~obsdesign.export.FMI_VERSIONS` (``"2"`` or ``"3"``).

    Returns
    -------
    str or None
        The folder's name, or None on another operating system.

    Examples
    --------
    >>> fmu_platform() in ("linux64", "linux32", "darwin64", "darwin32", None)
    True
    >>> fmu_platform("3") in ("x86_64-linux", "aarch64-linux", "x86-linux", "x86_64-darwin", "aarch64-darwin", None)
    True
    """
    system = "linux" if sys.platform.startswith("linux") else "darwin" if sys.platform == "darwin" else None
    if system is None:
        return None
    bits = "64" if sys.maxsize > 2**32 else "32"
    if _fmi_version(fmi_version) == "2":
        return system + bits
    machine = platform.machine().lower()
    if machine in ("x86_64", "amd64", "i386", "i686", "x86"):
        return ("x86_64" if bits == "64" else "x86") + "-" + system
    if machine in ("aarch64", "arm64") and bits == "64":
        return "aarch64-" + system
    return None


def _fmi_version(value) -> str:
    """``value`` as a name of :data:`~obsdesign.export.FMI_VERSIONS` (the integers 2 and 3 read as "2", "3")."""
    if isinstance(value, int) and not isinstance(value, bool) and str(value) in FMI_VERSIONS:
        return str(value)
    return check_choice("fmi_version", value, FMI_VERSIONS)


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


def _model_description(model: _Model, guid: str, fmi_version: str) -> str:
    """The ``modelDescription.xml`` of ``model``: FMI 2.0 ``ScalarVariable``/``Real`` or FMI 3.0 ``Float64``."""
    cfg, inputs, outputs, constants = model.cfg, model.inputs, model.outputs, model.constants
    identifier = model.identifier
    fmi3 = fmi_version == "3"
    dt = _literal(cfg.observer.dt)
    words = ", ".join(f"{k} {v}" for k, v in model.choices.items())
    desc = f"obsdesign {'sampled controller' if model.module == 'controller' else 'observer'}, {words}, " \
           f"config {comment_text(cfg.name)}"
    time_unit = cfg.units.unit("s")
    units = sorted({v["unit"] for v in inputs + outputs + constants} | ({time_unit} if fmi3 else set()))
    provenance = [f'      <Provenance version={quoteattr(__version__)} config={quoteattr(comment_text(cfg.name))}'
                  f' variant={quoteattr(cfg.observer.variant)} what="{model.module}"',
                  '        ' + " ".join(f"{k}={quoteattr(v)}" for k, v in model.choices.items()) + "/>"]
    if fmi3:
        lines = ['<?xml version="1.0" encoding="UTF-8"?>',
                 f'<fmiModelDescription fmiVersion="3.0" modelName="{identifier}" instantiationToken="{guid}"',
                 f'  description={quoteattr(desc)}',
                 f'  generationTool={quoteattr("obsdesign " + __version__)}', '  variableNamingConvention="flat">',
                 f'  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="false"',
                 f'    fixedInternalStepSize="{dt}" hasEventMode="false" canGetAndSetFMUState="false"',
                 '    canSerializeFMUState="false" providesDirectionalDerivatives="false"/>']
    else:
        lines = ['<?xml version="1.0" encoding="UTF-8"?>',
                 f'<fmiModelDescription fmiVersion="2.0" modelName="{identifier}" guid="{guid}"',
                 f'  description={quoteattr(desc)}',
                 f'  generationTool={quoteattr("obsdesign " + __version__)}',
                 '  variableNamingConvention="flat" numberOfEventIndicators="0">',
                 f'  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="false"',
                 '    canGetAndSetFMUstate="false" canSerializeFMUstate="false" providesDirectionalDerivative="false">',
                 '    <SourceFiles>', '      <File name="obsdesign_fmu.c"/>',
                 f'      <File name="obsdesign_{model.module}.c"/>', '    </SourceFiles>', '  </CoSimulation>']
    lines += ['  <UnitDefinitions>']
    lines += [f'    <Unit name={quoteattr(u)}/>' for u in units]
    lines += ['  </UnitDefinitions>', f'  <DefaultExperiment startTime="0.0" stepSize="{dt}"/>']
    if not fmi3:
        lines += ['  <VendorAnnotations>', '    <Tool name="obsdesign">', *provenance, '    </Tool>',
                  '  </VendorAnnotations>']
    lines += ['  <ModelVariables>']

    def var(v, causality, variability, start):
        if fmi3:
            return [f'    <Float64 name={quoteattr(v["name"])} valueReference="{v["vr"]}" '
                    f'causality="{causality}" variability="{variability}"',
                    f'      description={quoteattr(v["description"])} unit={quoteattr(v["unit"])}{start}/>']
        return [f'    <ScalarVariable name={quoteattr(v["name"])} valueReference="{v["vr"]}" '
                f'causality="{causality}" variability="{variability}"',
                f'      description={quoteattr(v["description"])}>',
                f'      <Real unit={quoteattr(v["unit"])}{start}/>', '    </ScalarVariable>']

    if fmi3:  # the independent variable (value reference 0)
        lines += var({"name": "time", "vr": 0, "description": "simulation time", "unit": time_unit},
                     "independent", "continuous", "")
    for v in inputs:
        lines += var(v, "input", "discrete", ' start="0.0"')
    for v in outputs:
        lines += var(v, "output", "discrete", "")
    for v in constants:  # compiled into the C: FMI's "parameter" would promise a value the importer can set
        lines += var(v, "local", "constant", f' start="{v["value"]}"')
    lines += ['  </ModelVariables>', '  <ModelStructure>']
    if fmi3:
        lines += [f'    <Output valueReference="{v["vr"]}" dependencies=""/>' for v in outputs]
        lines += [f'    <InitialUnknown valueReference="{v["vr"]}" dependencies=""/>' for v in outputs]
        lines += ['  </ModelStructure>', '  <Annotations>', '    <Annotation type="obsdesign">', *provenance,
                  '    </Annotation>', '  </Annotations>']
    else:
        first_output = len(inputs) + 1
        lines += ['    <Outputs>']
        lines += [f'      <Unknown index="{first_output + i}" dependencies=""/>' for i in range(len(outputs))]
        lines += ['    </Outputs>', '    <InitialUnknowns>']
        lines += [f'      <Unknown index="{first_output + i}" dependencies=""/>' for i in range(len(outputs))]
        lines += ['    </InitialUnknowns>', '  </ModelStructure>']
    lines += ['</fmiModelDescription>', '']
    return "\n".join(lines)


def _build_description(model: _Model) -> str:
    """FMI 3.0's ``sources/buildDescription.xml``: the two C files of the FMU (FMI 2.0 lists them in ``SourceFiles``)."""
    return "\n".join(['<?xml version="1.0" encoding="UTF-8"?>', '<fmiBuildDescription fmiVersion="3.0">',
                      f'  <BuildConfiguration modelIdentifier="{model.identifier}">',
                      '    <SourceFileSet language="C99">', '      <SourceFile name="obsdesign_fmu.c"/>',
                      f'      <SourceFile name="obsdesign_{model.module}.c"/>', '    </SourceFileSet>',
                      '  </BuildConfiguration>', '</fmiBuildDescription>', ''])


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
                schedule: str | None = None, estimator: str | None = None, waits: bool = False,
                fmi_version: str = FMI_VERSIONS[0]) -> bytes:
    """The FMU (FMI 2.0 or 3.0 co-simulation) of the exported controller or observer, as the bytes of its zip archive.

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
    fmi_version : {'2', '3'}
        The FMI version (:data:`obsdesign.export.FMI_VERSIONS`; the integers 2 and 3 are read as these):
        ``'2'`` (default) FMI 2.0, ``'3'`` FMI 3.0 (``Float64`` variables, ``instantiationToken``,
        ``fmi3InstantiateCoSimulation``, no event mode). The controller's C files are the same for both.

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
    version = _fmi_version(fmi_version)
    if check_choice("what", what, _WHAT) == "observer":
        if waits:
            raise ValueError("waits: applies to what='controller' only, found True with what='observer'")
        model = _observer_model(cfg, choices)
    else:
        model = _controller_model(cfg, choices, waits)
    if binary not in (None, True, False):
        raise TypeError(f"binary: expected True, False or None, found {binary!r}")
    cc, folder = _compiler(), fmu_platform(version)
    if binary and (cc is None or folder is None):
        raise ValueError(f"binary: no C compiler ($CC or cc) or no FMI {version}.0 platform folder for "
                         f"{sys.platform!r}; expected binary=False (a source FMU) or None")
    build = binary if binary is not None else (cc is not None and folder is not None)
    sources = dict(model.sources)

    def render(guid):
        wrapper = _environment(model.cfg.units).get_template("obsdesign_fmu.c.j2").render(
            name=comment_text(model.cfg.name), module=model.module,
            choices=", ".join(f"{k} {v}" for k, v in model.choices.items()), dt=_literal(model.cfg.observer.dt),
            guid=guid, inputs=model.inputs, outputs=model.outputs, constants=model.constants, fmi=int(version))
        return wrapper, _model_description(model, guid, version)

    digest = hashlib.sha256("\0".join((*render("{}"), *sources.values())).encode()).hexdigest()
    guid = "{" + str(uuid.UUID(digest[:32])) + "}"
    wrapper, xml = render(guid)
    sources["obsdesign_fmu.c"] = wrapper
    entries = {"modelDescription.xml": xml.encode()}
    entries.update({f"sources/{name}": text.encode() for name, text in sources.items()})
    if version == "3":
        entries["sources/buildDescription.xml"] = _build_description(model).encode()
    if build and cc is not None and folder is not None:
        lib = _build(sources, cc, model.identifier, model.module)
        entries[f"binaries/{folder}/{model.identifier}{'.dylib' if sys.platform == 'darwin' else '.so'}"] = lib
    return _zip(entries)
