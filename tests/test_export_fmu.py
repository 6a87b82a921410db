"""The controller as an FMI 2.0 co-simulation FMU: FMPy validates it and runs it on the simulator's record.

The FMU's output after the step from t_n is the command of sample n; ``K * command - G`` must equal
the simulator's ``u`` column bit for bit (the FMU is the generated C, compiled on this host).
"""

from __future__ import annotations

import io
import re
import shutil
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

import obsdesign as od
from obsdesign.export import export
from obsdesign.export.fmu import FMU_NAME, MODEL_IDENTIFIER, OBSERVER_FMU_NAME, fmu_archive, fmu_platform

fmpy = pytest.importorskip("fmpy", reason="fmpy (the test extra) is not installed")
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

HAS_CC = shutil.which("cc") is not None and fmu_platform() is not None
needs_cc = pytest.mark.skipif(not HAS_CC, reason="no C compiler or no FMI platform folder: source FMU only")
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


def _drive(path, inputs):
    """The FMU stepped over ``inputs`` (rows of x_ref, x_meas[, v_ref, w_ff]) by FMPy's FMI 2.0 API; the commands."""
    md = fmpy.read_model_description(str(path))
    unzipped = fmpy.extract(str(path))
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    dt = float(md.defaultExperiment.stepSize)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=MODEL_IDENTIFIER, instanceName="c")
    fmu.instantiate()
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        names = ["x_ref", "x_meas", "v_ref", "w_ff"][:inputs.shape[1]]
        refs = [vrs[n] for n in names]
        out = np.empty(len(inputs))
        for n, row in enumerate(inputs):
            fmu.setReal(refs, [float(x) for x in row])
            fmu.doStep(currentCommunicationPoint=n * dt, communicationStepSize=dt)
            out[n] = fmu.getReal([vrs["command"]])[0]
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    return out


@needs_cc
@pytest.mark.parametrize("case", CASES.values(), ids=list(CASES))
def test_fmu_reproduces_the_simulator_bit_for_bit(case, tmp_path):
    cfg, kw = case
    res, extra = _simulate(cfg, kw)
    path = _write(tmp_path, fmu_archive(cfg, binary=True, controller=kw.get("controller"),
                                        schedule=res.stiffness_schedule, estimator=res.estimator))
    command = _drive(path, np.column_stack([res.x_ref, res.x_meas, *extra]))
    d = cfg.hardware.delay_samples  # the simulated drive applies the command of sample n from n + d
    u = cfg.plant.K * command[:len(command) - d] - cfg.plant.G
    assert np.array_equal(u, res.u[d:]), f"max |du| = {np.max(np.abs(u - res.u[d:])):g}"


@needs_cc
def test_simulate_fmu_with_the_recorded_inputs_gives_the_simulated_command(tmp_path):
    res, _ = _simulate(VCM, dict(scenario="tracking"), duration=0.15)
    path = _write(tmp_path, fmu_archive(VCM, schedule=res.stiffness_schedule))
    assert validate_fmu(str(path)) == []
    n, dt = len(res.t), VCM.observer.dt
    signals = np.zeros(n, dtype=[("time", float), ("x_ref", float), ("x_meas", float)])
    signals["time"], signals["x_ref"], signals["x_meas"] = np.arange(n) * dt, res.x_ref, res.x_meas
    out = fmpy.simulate_fmu(str(path), start_time=0.0, stop_time=n * dt, step_size=dt, output_interval=dt,
                            input=signals, output=["command"], validate=True)
    command = out["command"][1:n + 1]  # the output at t_(n+1): the command of sample n
    assert np.array_equal(VCM.plant.K * command - VCM.plant.G, res.u)


def test_source_fmu_validates_and_describes_the_controller(tmp_path):
    cfg = dataclasses_replace_axis(VCM)
    path = _write(tmp_path, fmu_archive(cfg, binary=False))
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
    assert root.get("fmiVersion") == "2.0" and root.get("generationTool") == f"obsdesign {od.__version__}"
    assert float(root.find("DefaultExperiment").get("stepSize")) == cfg.observer.dt
    variables = {v.get("name"): v for v in root.iter("ScalarVariable")}
    units = {name: v.find("Real").get("unit") for name, v in variables.items()}
    assert units["x_ref"] == units["x_meas"] == "rad" and units["command"] == "A"  # a rotary axis driven in A
    assert units["KAPPA"] == "N m/rad" and units["DT"] == "s"
    assert {variables[n].get("causality") for n in ("x_ref", "x_meas")} == {"input"}
    assert variables["command"].get("causality") == "output"
    assert float(variables["KP"].find("Real").get("start")) == od.export.controller.controller_constants(cfg)["KP"]
    assert {v.get("variability") for n, v in variables.items() if v.get("causality") == "local"} == {"constant"}
    defined = {u.get("name") for u in root.iter("Unit")}
    assert set(units.values()) <= defined


def dataclasses_replace_axis(cfg):
    import dataclasses

    return dataclasses.replace(cfg, axis=od.AxisSpec(kind="rotary", input="A"))


@pytest.mark.parametrize("binary", [pytest.param(True, marks=needs_cc), False])
def test_same_inputs_give_the_same_bytes_and_no_path(binary, tmp_path, monkeypatch):
    a = fmu_archive(VCM, binary=binary)
    monkeypatch.chdir(tmp_path)
    b = fmu_archive(VCM, binary=binary)
    assert a == b
    with zipfile.ZipFile(io.BytesIO(a)) as archive:
        assert {i.date_time for i in archive.infolist()} == {(1980, 1, 1, 0, 0, 0)}
        blobs = [archive.read(n) for n in archive.namelist()]
    for blob in blobs:
        assert not re.search(rb"/(tmp|home|root|work|usr/src)/", blob)
        assert b"obsdesign-fmu-" not in blob  # the build folder's name


HOSTILE = ['"><x a="&amp;', "]]> */ (* *) \\", "name\u2028with\nlines", "é" * 200]


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_names_stay_in_comments_and_attributes(name, tmp_path):
    import dataclasses

    cfg = dataclasses.replace(VCM, name=name)
    data = fmu_archive(cfg, binary=HAS_CC)
    path = _write(tmp_path, data)
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    assert od.export.controller.sanitize_comment(name) in root.get("description")
    # the controller is the same whatever its name
    clean = zipfile.ZipFile(io.BytesIO(fmu_archive(VCM, binary=False)))
    assert clean.read("sources/obsdesign_controller.c").split(b"\n", 1)[1] == \
        zipfile.ZipFile(io.BytesIO(fmu_archive(cfg, binary=False))).read("sources/obsdesign_controller.c").split(
            b"\n", 1)[1]


@needs_cc
def test_a_step_other_than_dt_is_refused(tmp_path, capfd):
    path = _write(tmp_path, fmu_archive(VCM))
    with pytest.raises(Exception, match="fmi2DoStep failed"):
        fmpy.simulate_fmu(str(path), stop_time=10 * VCM.observer.dt, step_size=2 * VCM.observer.dt,
                          output_interval=2 * VCM.observer.dt)
    assert "the communication step must be dt" in capfd.readouterr().out


@pytest.mark.parametrize("args, kwargs, exc, match", [
    ((VCM,), {"binary": "yes"}, TypeError, "binary: expected True, False or None"),
    ((VCM,), {"schedule": "true"}, ValueError, "schedule: 'true'"),
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
@pytest.mark.parametrize("cfg", [VCM, TABLE1.override(rho=3.0)], ids=["vcm", "table1-rho3"])
def test_the_observer_fmu_reproduces_the_simulated_estimates_bit_for_bit(cfg, tmp_path):
    res = od.simulate(cfg, "tracking", duration=0.5)  # the default schedule, as the observer export
    path = _write(tmp_path, fmu_archive(cfg, what="observer", binary=True), OBSERVER_FMU_NAME)
    assert validate_fmu(str(path)) == []
    md = fmpy.read_model_description(str(path))
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = fmpy.extract(str(path))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier="obsdesign_observer", instanceName="o")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    u_prev = np.concatenate([[0.0], res.u[:-1]])  # the net force held over the interval that ends at sample n
    out = []
    for n, (u, x) in enumerate(zip(u_prev, res.x_meas)):
        fmu.setReal([vrs["u_prev"], vrs["x_meas"]], [float(u), float(x)])
        fmu.doStep(currentCommunicationPoint=n * cfg.observer.dt, communicationStepSize=cfg.observer.dt)
        out.append(fmu.getReal([vrs["v_hat"], vrs["f_hat"]]))
    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)
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
    monkeypatch.setenv("CC", "no-such-compiler-obsdesign")
    code, _, err = _cli(capsys, "export", "--format", "fmu", "--what", "controller", "-o", str(tmp_path / "s"))
    assert code == 0 and len(err) == 1 and "a source FMU" in err[0]


@needs_cc
@pytest.mark.slow  # CMake configures a project: about 9 s
def test_the_source_fmu_builds_in_an_importer_and_runs_the_same(tmp_path, capfd):
    """FMPy's own build of a source FMU (CMake, its flags): what an importer without our compiler does."""
    build = pytest.importorskip("fmpy.build", reason="fmpy without its build module")
    if shutil.which("cmake") is None:
        pytest.skip("cmake (a dependency of fmpy) is not on PATH")
    res, _ = _simulate(VCM, dict(scenario="tracking"), duration=0.3)
    path = _write(tmp_path, fmu_archive(VCM, binary=False, schedule=res.stiffness_schedule))
    unzipped = fmpy.extract(str(path), unzipdir=str(tmp_path / "unzipped"))
    (tmp_path / "build").mkdir()
    build.build_platform_binary(unzipped, build_dir=str(tmp_path / "build"))
    capfd.readouterr()  # CMake's progress
    n, dt = len(res.t), VCM.observer.dt
    signals = np.rec.fromarrays([np.arange(n) * dt, res.x_ref, res.x_meas], names="time,x_ref,x_meas")
    out = fmpy.simulate_fmu(str(unzipped), stop_time=n * dt, step_size=dt, output_interval=dt, input=signals,
                            output=["command"])
    assert np.array_equal(VCM.plant.K * out["command"][1:] - VCM.plant.G, res.u)
