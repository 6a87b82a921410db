"""The controller as an FMI 2.0 and 3.0 co-simulation FMU: FMPy validates it and runs it on the simulator's record.

The FMU's output after the step from t_n is the command of sample n; ``K * command - G`` must equal
the simulator's ``u`` column bit for bit (the FMU is the generated C, compiled on this host). Every test that
builds or runs an FMU runs for both FMI versions (``fmi``): only the FMI wrapper and modelDescription differ.
"""

from __future__ import annotations

import contextlib
import io
import re
import shutil
import sys
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

import obsdesign as od
from obsdesign.export import FMI_VERSIONS, export
from obsdesign.export.fmu import FMU_NAME, MODEL_IDENTIFIER, OBSERVER_FMU_NAME, fmu_archive, fmu_platform

fmpy = pytest.importorskip("fmpy", reason="fmpy (the test extra) is not installed")
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.fmi3 import FMU3Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

HAS_CC = shutil.which("cc") is not None and all(fmu_platform(v) is not None for v in FMI_VERSIONS)
needs_cc = pytest.mark.skipif(not HAS_CC, reason="no C compiler or no FMI platform folder: source FMU only")
#: Every FMI version the export writes: the tests below run for each.
each_fmi = pytest.mark.parametrize("fmi", FMI_VERSIONS, ids=[f"fmi{v}" for v in FMI_VERSIONS])
VCM = od.load_preset("vcm")
TABLE1 = od.load_preset("table1")

#: name -> (config, simulate's keywords); every estimator family, schedule and compensation mode.
CASES = {
    "vcm-tracking": (VCM, dict(scenario="tracking")),
    # the lag variant in its model plant: table1's compensated loop runs away in the physical lag plant
    "noisy-lag-hysteresis": (TABLE1.override(noise_rms=2e-7, quantization=1e-8), dict(scenario="tracking",
                                                                                     plant="model")),
    "saturated": (VCM.override(u_max=1.8), dict(scenario=od.sim.Positioning(step_up=0.1, step_down=0.6))),
    "pid": (VCM, dict(scenario="tracking", controller="pid")),
    "eso": pytest.param((VCM.override(noise_rms=1e-6), dict(scenario="tracking", estimator="eso")),
                        marks=pytest.mark.slow),  # tuning the baseline: ~20 s on a cold cache
    "blend-lag": (TABLE1.override(mode="blend", lookahead=10, noise_rms=2e-7), dict(scenario="tracking", plant="model")),
    # the drive's delay: the FMU's command is not delayed, its estimator is fed the command of d samples earlier
    "delayed": (VCM.override(delay_samples=1), dict(scenario="tracking")),
}


def _simulate(cfg, kw, duration=1.0):
    kw = dict(kw)
    scenario = kw.pop("scenario")
    kw.setdefault("controller", "pid+observer")
    loop = od.loop.prepare(cfg, scenario, duration=duration, **kw)
    res = od.sim.run(loop)
    assert not res.metrics["diverged"]
    extra = loop.reference_feedforward() if cfg.compensation.mode != "observer" else ()
    return res, extra


def _write(tmp_path, data, name=FMU_NAME):
    path = tmp_path / name
    path.write_bytes(data)
    return path


@contextlib.contextmanager
def _running(path, identifier=MODEL_IDENTIFIER):
    """The FMU at ``path`` instantiated and initialised by FMPy's FMI 2.0 or 3.0 API (its ``fmiVersion``):
    ``(set(names, values), step(t, dt), get(names), dt)``."""
    md = fmpy.read_model_description(str(path))
    unzipped = fmpy.extract(str(path))
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    fmi3 = md.fmiVersion.startswith("3")
    fmu = (FMU3Slave if fmi3 else FMU2Slave)(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=identifier,
                                             instanceName="c")
    fmu.instantiate()
    try:
        if fmi3:
            fmu.enterInitializationMode(startTime=0.0)
        else:
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        setter, getter = (fmu.setFloat64, fmu.getFloat64) if fmi3 else (fmu.setReal, fmu.getReal)

        def step(t, dt):
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=dt)

        yield (lambda names, values: setter([vrs[n] for n in names], [float(x) for x in values]), step,
               lambda names: getter([vrs[n] for n in names]), float(md.defaultExperiment.stepSize))
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)


def _drive(path, inputs):
    """The FMU stepped over ``inputs`` (rows of x_ref, x_meas[, v_ref, w_ff]) by FMPy's FMI API; the commands."""
    names = ["x_ref", "x_meas", "v_ref", "w_ff"][:inputs.shape[1]]
    out = np.empty(len(inputs))
    with _running(path) as (set_inputs, step, get, dt):
        for n, row in enumerate(inputs):
            set_inputs(names, row)
            step(n * dt, dt)
            out[n] = get(["command"])[0]
    return out


@needs_cc
@each_fmi
@pytest.mark.parametrize("case", CASES.values(), ids=list(CASES))
def test_fmu_reproduces_the_simulator_bit_for_bit(case, fmi, tmp_path):
    cfg, kw = case
    res, extra = _simulate(cfg, kw)
    path = _write(tmp_path, fmu_archive(cfg, binary=True, controller=kw.get("controller"),
                                        schedule=res.stiffness_schedule, estimator=res.estimator, fmi_version=fmi))
    assert validate_fmu(str(path)) == []
    command = _drive(path, np.column_stack([res.x_ref, res.x_meas, *extra]))
    d = cfg.hardware.delay_samples  # the simulated drive applies the command of sample n from n + d
    u = cfg.plant.K * command[:len(command) - d] - cfg.plant.G
    assert np.array_equal(u, res.u[d:]), f"max |du| = {np.max(np.abs(u - res.u[d:])):g}"


@needs_cc
@each_fmi
def test_simulate_fmu_with_the_recorded_inputs_gives_the_simulated_command(fmi, tmp_path):
    res, _ = _simulate(VCM, dict(scenario="tracking"), duration=0.15)
    path = _write(tmp_path, fmu_archive(VCM, schedule=res.stiffness_schedule, fmi_version=fmi))
    assert validate_fmu(str(path)) == []
    n, dt = len(res.t), VCM.observer.dt
    signals = np.zeros(n, dtype=[("time", float), ("x_ref", float), ("x_meas", float)])
    signals["time"], signals["x_ref"], signals["x_meas"] = np.arange(n) * dt, res.x_ref, res.x_meas
    out = fmpy.simulate_fmu(str(path), start_time=0.0, stop_time=n * dt, step_size=dt, output_interval=dt,
                            input=signals, output=["command"], validate=True)
    command = out["command"][1:n + 1]  # the output at t_(n+1): the command of sample n
    assert np.array_equal(VCM.plant.K * command - VCM.plant.G, res.u)


def _variables(root):
    """name -> (element with causality and variability, unit, start) of a modelDescription, FMI 2.0 or 3.0."""
    if root.get("fmiVersion") == "2.0":
        return {v.get("name"): (v, v.find("Real").get("unit"), v.find("Real").get("start"))
                for v in root.iter("ScalarVariable")}
    return {v.get("name"): (v, v.get("unit"), v.get("start")) for v in root.find("ModelVariables")}


@each_fmi
def test_source_fmu_validates_and_describes_the_controller(fmi, tmp_path):
    cfg = dataclasses_replace_axis(VCM)
    path = _write(tmp_path, fmu_archive(cfg, binary=False, fmi_version=fmi))
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as archive:
        names = set(archive.namelist())
        xml = archive.read("modelDescription.xml").decode()
        sources = {n: archive.read(n).decode() for n in names if n.startswith("sources/")}
    assert not any(n.startswith("binaries/") for n in names)
    # one code path: the sources are the C export's files, unchanged
    from obsdesign.export.controller import controller_files

    for fname, text in controller_files(cfg, "c").items():
        assert sources[f"sources/{fname}"] == text
    root = ET.fromstring(xml)
    assert root.get("fmiVersion") == f"{fmi}.0" and root.get("generationTool") == f"obsdesign {od.__version__}"
    assert float(root.find("DefaultExperiment").get("stepSize")) == cfg.observer.dt
    found = _variables(root)
    variables = {name: v for name, (v, _, _) in found.items()}
    units = {name: unit for name, (_, unit, _) in found.items()}
    assert units["x_ref"] == units["x_meas"] == "rad" and units["command"] == "A"  # a rotary axis driven in A
    assert units["KAPPA"] == "N m/rad" and units["DT"] == "s"
    assert {variables[n].get("causality") for n in ("x_ref", "x_meas")} == {"input"}
    assert variables["command"].get("causality") == "output"
    assert float(found["KP"][2]) == od.export.controller.controller_constants(cfg)["KP"]
    assert {v.get("variability") for n, v in variables.items() if v.get("causality") == "local"} == {"constant"}
    defined = {u.get("name") for u in root.iter("Unit")}
    assert set(units.values()) <= defined
    if fmi == "3":  # the FMI 3.0 specifics: Float64, instantiationToken, the independent time, buildDescription
        assert root.get("instantiationToken") and root.get("guid") is None
        assert {v.tag for v in variables.values()} == {"Float64"}
        assert variables["time"].get("causality") == "independent" and variables["time"].get("valueReference") == "0"
        assert root.find("CoSimulation").get("hasEventMode") == "false"
        assert "sources/buildDescription.xml" in names


@needs_cc
def test_fmi2_and_fmi3_wrap_the_same_c_and_differ_in_the_wrapper_only():
    zips = {v: zipfile.ZipFile(io.BytesIO(fmu_archive(TABLE1.override(mode="blend"), fmi_version=v)))
            for v in FMI_VERSIONS}
    two, three = zips["2"], zips["3"]
    for name in ("sources/obsdesign_controller.c", "sources/obsdesign_controller.h"):
        assert two.read(name) == three.read(name)
    assert set(three.namelist()) - set(two.namelist()) == {
        "sources/buildDescription.xml",
        f"binaries/{fmu_platform('3')}/{MODEL_IDENTIFIER}{'.dylib' if sys.platform == 'darwin' else '.so'}"}
    assert b"fmi3DoStep" in three.read("sources/obsdesign_fmu.c") and b"fmi2" not in three.read("sources/obsdesign_fmu.c")
    assert fmu_archive(VCM, binary=False, fmi_version=3) == fmu_archive(VCM, binary=False, fmi_version="3")


def dataclasses_replace_axis(cfg):
    import dataclasses

    return dataclasses.replace(cfg, axis=od.AxisSpec(kind="rotary", input="A"))


@each_fmi
@pytest.mark.parametrize("binary", [pytest.param(True, marks=needs_cc), False])
def test_same_inputs_give_the_same_bytes_and_no_path(binary, fmi, tmp_path, monkeypatch):
    a = fmu_archive(VCM, binary=binary, fmi_version=fmi)
    monkeypatch.chdir(tmp_path)
    b = fmu_archive(VCM, binary=binary, fmi_version=fmi)
    assert a == b
    with zipfile.ZipFile(io.BytesIO(a)) as archive:
        assert {i.date_time for i in archive.infolist()} == {(1980, 1, 1, 0, 0, 0)}
        blobs = [archive.read(n) for n in archive.namelist()]
    for blob in blobs:
        assert not re.search(rb"/(tmp|home|root|work|usr/src)/", blob)
        assert b"obsdesign-fmu-" not in blob  # the build folder's name


HOSTILE = ['"><x a="&amp;', "]]> */ (* *) \\", "name\u2028with\nlines", "é" * 200]


@each_fmi
@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_names_stay_in_comments_and_attributes(name, fmi, tmp_path):
    import dataclasses

    cfg = dataclasses.replace(VCM, name=name)
    data = fmu_archive(cfg, binary=HAS_CC, fmi_version=fmi)
    path = _write(tmp_path, data)
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    assert od.export.controller.sanitize_comment(name) in root.get("description")
    # the controller is the same whatever its name
    clean = zipfile.ZipFile(io.BytesIO(fmu_archive(VCM, binary=False, fmi_version=fmi)))
    assert clean.read("sources/obsdesign_controller.c").split(b"\n", 1)[1] == \
        zipfile.ZipFile(io.BytesIO(fmu_archive(cfg, binary=False, fmi_version=fmi))).read(
            "sources/obsdesign_controller.c").split(b"\n", 1)[1]


@needs_cc
@each_fmi
def test_a_step_other_than_dt_is_refused(fmi, tmp_path, capfd):
    path = _write(tmp_path, fmu_archive(VCM, fmi_version=fmi))
    with pytest.raises(Exception, match=f"fmi{fmi}DoStep failed"):
        fmpy.simulate_fmu(str(path), stop_time=10 * VCM.observer.dt, step_size=2 * VCM.observer.dt,
                          output_interval=2 * VCM.observer.dt)
    assert "the communication step must be dt" in capfd.readouterr().out


@needs_cc
@each_fmi
def test_the_constants_are_read_only_and_no_parameter_is_declared(fmi, tmp_path, capfd):
    """The export's numbers are compiled into the C (the coefficients are derived from them at export time): the
    FMU declares them local constants, not parameters an importer could set, and refuses a value for one."""
    path = _write(tmp_path, fmu_archive(VCM, fmi_version=fmi))
    md = fmpy.read_model_description(str(path))
    assert not {v.causality for v in md.modelVariables} & {"parameter", "calculatedParameter", "structuralParameter"}
    consts = od.export.controller.controller_constants(VCM)
    with _running(path) as (set_inputs, step, get, dt):
        assert get(["KP", "DT"]) == [consts["KP"], VCM.observer.dt]
        with pytest.raises(Exception, match=f"fmi{fmi}Set{'Real' if fmi == '2' else 'Float64'} failed"):
            set_inputs(["KP"], [1.0])
        assert get(["KP"]) == [consts["KP"]]
    assert "only the inputs can be set (the constants are compiled in)" in capfd.readouterr().out


@pytest.mark.parametrize("args, kwargs, exc, match", [
    ((VCM,), {"binary": "yes"}, TypeError, "binary: expected True, False or None"),
    ((VCM,), {"schedule": "true"}, ValueError, "schedule: 'true'"),
    ((VCM,), {"fmi_version": "3.0"}, ValueError, "fmi_version: expected one of 2, 3, found '3.0'"),
    ((VCM,), {"fmi_version": 1}, ValueError, "fmi_version: expected one of 2, 3, found 1"),
    ((VCM,), {"fmi_version": True}, ValueError, "fmi_version: expected one of 2, 3, found True"),
])
def test_fmu_errors(args, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        fmu_archive(*args, **kwargs)


def test_binary_without_a_compiler_is_refused(monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-obsdesign")
    with pytest.raises(ValueError, match=r"binary: no C compiler"):
        fmu_archive(VCM, binary=True)
    assert b"binaries/" not in fmu_archive(VCM)  # the default falls back to a source FMU


def test_export_writes_the_controller_and_the_observer_fmu(tmp_path):
    (path,) = export(VCM, "fmu", tmp_path, what="controller")
    assert path.name == FMU_NAME and zipfile.is_zipfile(path)
    (path,) = export(VCM, "fmu", tmp_path)
    assert path.name == OBSERVER_FMU_NAME and validate_fmu(str(path)) == []
    for what in ("controller", "observer"):
        (path,) = export(VCM, "fmu", tmp_path / "3", what=what, fmi_version="3")
        assert fmpy.read_model_description(str(path)).fmiVersion == "3.0" and validate_fmu(str(path)) == []
    with pytest.raises(ValueError, match="fmi_version: applies to format 'fmu' only, found '3' with format 'c'"):
        export(VCM, "c", tmp_path / "no", fmi_version="3")
    assert not (tmp_path / "no").exists()
    with pytest.raises(ValueError, match="estimator: applies to what='controller' only"):
        fmu_archive(VCM, what="observer", estimator="eso")
    with pytest.raises(ValueError, match="what: expected one of observer, controller, found 'table'"):
        fmu_archive(VCM, what="table")


def _observer_reference(cfg, u_prev, x_meas, tmp_path):
    """(v_hat, f_hat) of the Python observer export (``Observer``) on the same inputs."""
    import importlib.util

    from obsdesign.export.codegen import export_spec, python_module

    path = tmp_path / "obsdesign_observer.py"
    path.write_text(python_module(export_spec(cfg)))
    spec = importlib.util.spec_from_file_location(f"observer_reference_{id(cfg)}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    obs = mod.Observer(float(x_meas[0]))
    out = [(obs.velocity, obs.friction)]
    for u, x in zip(u_prev[1:], x_meas[1:]):
        obs.step(float(u), float(x))
        out.append((obs.velocity, obs.friction))
    return np.array(out)


@needs_cc
@each_fmi
@pytest.mark.parametrize("cfg", [VCM, TABLE1.override(rho=3.0)], ids=["vcm", "table1-rho3"])
def test_the_observer_fmu_reproduces_the_simulated_estimates_bit_for_bit(cfg, fmi, tmp_path):
    res = od.simulate(cfg, "tracking", duration=0.5)  # the default schedule, as the observer export
    path = _write(tmp_path, fmu_archive(cfg, what="observer", binary=True, fmi_version=fmi), OBSERVER_FMU_NAME)
    assert validate_fmu(str(path)) == []
    u_prev = np.concatenate([[0.0], res.u[:-1]])  # the net force held over the interval that ends at sample n
    out = []
    with _running(path, "obsdesign_observer") as (set_inputs, step, get, dt):
        assert dt == cfg.observer.dt
        for n, (u, x) in enumerate(zip(u_prev, res.x_meas)):
            set_inputs(["u_prev", "x_meas"], [u, x])
            step(n * dt, dt)
            out.append(get(["v_hat", "f_hat"]))
    out = np.array(out)
    assert np.array_equal(out[:, 0], res.v_hat) and np.array_equal(out[:, 1], res.f_hat)
    assert np.array_equal(out, _observer_reference(cfg, u_prev, res.x_meas, tmp_path))


def _cli(capsys, *argv):
    from obsdesign.cli import main

    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err.strip().splitlines()


def test_cli_writes_the_fmu_and_the_st_and_refuses_in_one_line(tmp_path, capsys, monkeypatch):
    out = tmp_path / "gen"
    for fmt, names in (("fmu", [FMU_NAME]), ("st", ["obsdesign_controller.st", "obsdesign_controller.xml"])):
        status, stdout, err = _cli(capsys, "export", "--format", fmt, "--what", "controller", "-o", str(out))
        assert status == 0 and stdout.split() == [str(out / n) for n in names]
        status, stdout, err = _cli(capsys, "export", "--format", fmt, "-o", str(out))
        assert status == 0 and [p.rsplit("/", 1)[1] for p in stdout.split()] == [
            n.replace("controller", "observer") for n in names]
        code, _, err = _cli(capsys, "export", "--format", fmt, "--estimator", "eso", "-o", str(tmp_path / "no"))
        assert code == 2 and len(err) == 1 and "applies to --what controller only" in err[0]
    assert not (tmp_path / "no").exists()
    config = tmp_path / "delayed.toml"
    config.write_text(od.load_preset("vcm").override(delay_samples=1).to_toml())
    code, _, err = _cli(capsys, "export", "--format", "st", "--what", "controller", "--config", str(config),
                        "-o", str(tmp_path / "d"))  # the drive's delay is not the block's (issue 33): exported as is
    assert code == 0 and err == []
    assert (tmp_path / "d" / "obsdesign_controller.st").is_file()
    status, stdout, err = _cli(capsys, "export", "--format", "fmu", "--fmi-version", "3", "-o", str(tmp_path / "f3"))
    assert status == 0 and stdout.split() == [str(tmp_path / "f3" / OBSERVER_FMU_NAME)]
    assert fmpy.read_model_description(stdout.split()[0]).fmiVersion == "3.0"
    code, _, err = _cli(capsys, "export", "--format", "c", "--fmi-version", "3", "-o", str(tmp_path / "no"))
    assert code == 2 and err == ["obsdesign export: argument --fmi-version: applies to --format fmu only, found "
                                 "--fmi-version 3 with --format c"]
    code, _, err = _cli(capsys, "export", "--format", "fmu", "--fmi-version", "4", "-o", str(tmp_path / "no"))
    assert code == 2 and len(err) == 1 and "--fmi-version: invalid choice: '4'" in err[0]
    assert not (tmp_path / "no").exists()
    monkeypatch.setenv("CC", "no-such-compiler-obsdesign")
    code, _, err = _cli(capsys, "export", "--format", "fmu", "--what", "controller", "-o", str(tmp_path / "s"))
    assert code == 0 and len(err) == 1 and "a source FMU" in err[0]


@needs_cc
@each_fmi
@pytest.mark.slow  # CMake configures a project: about 9 s
def test_the_source_fmu_builds_in_an_importer_and_runs_the_same(fmi, tmp_path, capfd):
    """FMPy's own build of a source FMU (CMake, its flags): what an importer without our compiler does."""
    build = pytest.importorskip("fmpy.build", reason="fmpy without its build module")
    if shutil.which("cmake") is None:
        pytest.skip("cmake (a dependency of fmpy) is not on PATH")
    res, _ = _simulate(VCM, dict(scenario="tracking"), duration=0.3)
    path = _write(tmp_path, fmu_archive(VCM, binary=False, schedule=res.stiffness_schedule, fmi_version=fmi))
    unzipped = fmpy.extract(str(path), unzipdir=str(tmp_path / "unzipped"))
    (tmp_path / "build").mkdir()
    build.build_platform_binary(unzipped, build_dir=str(tmp_path / "build"))
    capfd.readouterr()  # CMake's progress
    n, dt = len(res.t), VCM.observer.dt
    signals = np.rec.fromarrays([np.arange(n) * dt, res.x_ref, res.x_meas], names="time,x_ref,x_meas")
    out = fmpy.simulate_fmu(str(unzipped), stop_time=n * dt, step_size=dt, output_interval=dt, input=signals,
                            output=["command"])
    assert np.array_equal(VCM.plant.K * out["command"][1:] - VCM.plant.G, res.u)
