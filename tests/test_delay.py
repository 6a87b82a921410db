"""The drive's delay ([hardware] delay_samples) is the hardware's, written once.

The exported controller (Python and C) runs inside the simulated plant of a config with the drive's delay
(:func:`obsdesign.sim.external.run_external`) and must give the response of ``simulate`` sample for sample:
the export adds no delay of its own. Counting the delay twice (a controller that waits, in a plant that
waits too) is the loop of twice the delay.
"""

from __future__ import annotations

import ctypes
import importlib.util
import re
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import obsdesign as od
from obsdesign.export.controller import controller_files
from obsdesign.loop import prepare
from obsdesign.sim.external import run_external

HAS_GCC = shutil.which("gcc") is not None
VCM = od.load_preset("vcm").override(noise_rms=3e-7)
TABLE1 = od.load_preset("table1").override(quantization=1e-7)
SCENARIO = od.sim.Positioning(step_up=0.05, step_down=0.35)


def python_controller(cfg, tmp_path, **kw):
    """The exported Python controller's ``step``."""
    (name, text), = controller_files(cfg, "python", **kw).items()
    path = tmp_path / name
    path.write_text(text)
    spec = importlib.util.spec_from_file_location(f"exported_{id(path)}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.Controller().step


def c_controller(cfg, tmp_path, **kw):
    """The exported C controller's step, compiled into a shared library and called through ctypes."""
    for name, text in controller_files(cfg, "c", **kw).items():
        (tmp_path / name).write_text(text)
    (tmp_path / "size.c").write_text('#include <stddef.h>\n#include "obsdesign_controller.h"\n'
                                     "size_t od_size(void) { return sizeof(obsdesign_controller); }\n")
    lib = tmp_path / "libctrl.so"
    subprocess.run(["gcc", "-std=c99", "-O2", "-shared", "-fPIC", f"-I{tmp_path}", "-o", str(lib),
                    str(tmp_path / "obsdesign_controller.c"), str(tmp_path / "size.c"), "-lm"],
                   check=True, capture_output=True, text=True)
    so = ctypes.CDLL(str(lib))
    so.od_size.restype = ctypes.c_size_t
    state = ctypes.create_string_buffer(so.od_size())
    so.obsdesign_controller_init(state)
    so.obsdesign_controller_step.restype = ctypes.c_double
    so.obsdesign_controller_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double]
    return lambda x_ref, x_meas: so.obsdesign_controller_step(state, x_ref, x_meas)


LANGUAGES = {"python": (python_controller, True), "c": (c_controller, HAS_GCC)}


@pytest.mark.parametrize("language", list(LANGUAGES))
@pytest.mark.parametrize("delay", [0, 1, 2])
@pytest.mark.parametrize("base", [VCM, TABLE1], ids=["vcm", "table1"])
def test_the_exported_controller_in_the_delayed_plant_is_simulate(language, delay, base, tmp_path):
    make, available = LANGUAGES[language]
    if not available:
        pytest.skip(f"{language}: toolchain not installed")
    cfg = base.override(delay_samples=delay)
    # the CLI's default plant: the lag observer in its model plant (in the physical lag plant table1's loop runs
    # away to 0.77 m within 0.6 s, flagged 'runaway' since issue 33 point 4)
    plant = "model" if cfg.observer.variant == "lag" else "physical"
    res = od.simulate(cfg, SCENARIO, controller="pid+observer", duration=0.6, plant=plant)
    assert not res.metrics["diverged"]
    ext = run_external(prepare(cfg, SCENARIO, controller="pid+observer", duration=0.6, plant=plant), make(cfg, tmp_path))
    # sample for sample, to the bit: the plant's position, the measurement and the force the plant felt
    for name in ("x", "x_meas", "u"):
        np.testing.assert_array_equal(getattr(ext, name), getattr(res, name), err_msg=name)
    # the force the plant feels is the controller's command of `delay` samples earlier
    pl = cfg.plant
    np.testing.assert_array_equal(ext.u[delay:], pl.K * ext.command[: len(ext.command) - delay] - pl.G)


def test_a_controller_that_waits_in_a_plant_that_waits_is_the_loop_of_twice_the_delay(tmp_path):
    """The failure the single definition prevents: an export that added the drive's delay again (as
    before [hardware]) in a plant with that delay runs the loop of 2 d (controller 'pid': its command
    does not depend on the estimator's input), with the margin of 2 d."""
    from obsdesign.design.sampled_loop import sampled_loop

    cfg = VCM.override(delay_samples=1)
    step = python_controller(cfg, tmp_path, controller="pid")
    held = [cfg.plant.G / cfg.plant.K]

    def waits(x_ref, x_meas):
        held.append(step(x_ref, x_meas))
        return held.pop(0)

    loop = prepare(cfg, SCENARIO, controller="pid", duration=0.6)
    twice = od.simulate(cfg.override(delay_samples=2), SCENARIO, controller="pid", duration=0.6)
    once = od.simulate(cfg, SCENARIO, controller="pid", duration=0.6)
    ext = run_external(loop, waits)
    np.testing.assert_array_equal(ext.x, twice.x)
    assert np.max(np.abs(ext.x - once.x)) > 1e-7
    assert sampled_loop(cfg).phase_margin_deg - sampled_loop(cfg.override(delay_samples=2)).phase_margin_deg > 0


def test_no_export_delays_its_command_and_d0_has_no_ring():
    """The command is not delayed (test above); d = 0 generates no ring in C, Python and Octave (the
    JavaScript reads ``DRIVE_DELAY`` from its constants, which the report's explorer sets from its field);
    d > 0 adds the ring's constants."""
    for language in ("python", "c", "octave", "js"):
        for name, text in controller_files(VCM, language).items():
            assert "DRIVE_" not in text or language == "js", (language, name)
            assert "DRIVE_DELAY:" not in text, (language, name)
        with3 = controller_files(VCM.override(delay_samples=3), language)
        assert any("DRIVE_HOLD" in text for text in with3.values()), language
        assert all("ubuf" not in text for text in with3.values()), language


@pytest.mark.parametrize("delay", [1, 3])
def test_the_estimator_is_fed_the_command_the_drive_applies(delay):
    """With the drive's delay the controller keeps its last d commands for its estimator: the estimate in
    ``simulate`` equals the observer run over the recorded measurement and the force the plant felt
    (:func:`obsdesign.sampled.kernel.observe_loop`, the estimator fed from outside), and the exported controller's
    estimator input ``u`` is K times the command of d samples earlier, less G (the drive's hold before)."""
    from obsdesign.sampled import sampled_controller
    from obsdesign.sampled.kernel import observe_loop

    cfg = VCM.override(delay_samples=delay)
    res = od.simulate(cfg, SCENARIO, controller="pid+observer", duration=0.6)
    obs, est, _ = sampled_controller(cfg).kernel_args()
    n = len(res.x_meas)
    seen = {name: np.empty(n) for name in ("v_hat", "f_hat", "f_hat_filtered", "stiffness")}
    observe_loop(obs, est, np.asarray(res.x_meas), np.asarray(res.u), np.zeros(n), *seen.values())
    for name in ("v_hat", "f_hat", "f_hat_filtered"):
        np.testing.assert_array_equal(seen[name], getattr(res, name), err_msg=name)
    # the exported controller's estimator input over the run
    (name, text), = controller_files(cfg, "python").items()
    namespace: dict = {}
    exec(compile(text, name, "exec"), namespace)
    ctrl = namespace["Controller"]()
    pl = cfg.plant
    commands, inputs = [], []
    for x_ref, xm in zip(res.x_ref, res.x_meas):
        commands.append(ctrl.step(float(x_ref), float(xm)))
        inputs.append(ctrl.u)
    commands = np.array(commands)
    np.testing.assert_array_equal(np.array(inputs[delay:]), pl.K * commands[:-delay] - pl.G)
    np.testing.assert_array_equal(np.array(inputs[:delay]), pl.K * (pl.G / pl.K) - pl.G)


@pytest.mark.parametrize("language", list(LANGUAGES))
def test_the_controller_that_waits_in_an_undelayed_plant_is_simulate_with_the_delay(language, tmp_path):
    """The opt-in for a bench without the drive's delay: the exported controller returns its command of d
    samples earlier; in the plant without a delay it runs the loop that ``simulate`` runs with d."""
    make, available = LANGUAGES[language]
    if not available:
        pytest.skip(f"{language}: toolchain not installed")
    cfg = VCM.override(delay_samples=2)
    res = od.simulate(cfg, SCENARIO, controller="pid+observer", duration=0.6)
    bench = prepare(cfg.override(delay_samples=0), SCENARIO, controller="pid+observer", duration=0.6)
    ext = run_external(bench, make(cfg, tmp_path, waits=True))
    for name in ("x", "x_meas", "u"):
        np.testing.assert_array_equal(getattr(ext, name), getattr(res, name), err_msg=name)


def test_waits_needs_a_delay():
    with pytest.raises(ValueError, match="waits: .* expected delay_samples >= 1, found 0"):
        controller_files(VCM, "python", waits=True)
    with pytest.raises(TypeError, match="waits: expected a bool, found int"):
        controller_files(VCM.override(delay_samples=1), "python", waits=1)


def without_hardware(text):
    """A config's TOML without its ``[hardware]`` table (as written before the table existed)."""
    return re.sub(r"\n\[hardware\]\ndelay_samples = 0 [^\n]*\n", "\n", text)


def test_legacy_pid_delay_samples_is_read_as_hardware_with_a_warning():
    text = without_hardware(od.load_preset("vcm").to_toml())
    text = text.replace("[pid]\n", "[pid]\ndelay_samples = 2\n")
    with pytest.warns(FutureWarning, match=r"\[pid\] delay_samples is the drive's delay, not a controller setting"):
        cfg = od.Config.from_toml(text)
    assert cfg.hardware.delay_samples == 2 and cfg == od.load_preset("vcm").override(delay_samples=2)
    assert "[hardware]\ndelay_samples = 2" in cfg.to_toml() and "[pid]\ndelay_samples" not in cfg.to_toml()
    both = text + "\n[hardware]\ndelay_samples = 1\n"
    with pytest.raises(ValueError, match=r"delay_samples is set in \[pid\] and in \[hardware\]; expected it once"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            od.Config.from_toml(both)


def test_a_config_without_hardware_has_no_delay():
    text = without_hardware(od.load_preset("vcm").to_toml())
    assert "[hardware]" not in text
    assert od.Config.from_toml(text).hardware.delay_samples == 0


@pytest.mark.parametrize("loop, step, match", [
    ("vcm", lambda r, x: 0.0, "loop: expected LoopInputs"),
    (None, 1.0, "step: expected a callable"),
])
def test_run_external_errors(loop, step, match):
    loop = prepare(VCM, SCENARIO, duration=0.6) if loop is None else loop
    with pytest.raises(TypeError, match=match):
        run_external(loop, step)


def _cli(capsys, *argv):
    from obsdesign.cli import main

    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err.strip().splitlines()


@pytest.mark.parametrize("fmt, target, name", [("python", "host", "obsdesign_controller.py"),
                                               ("c", "cortex-m4f", "obsdesign_controller.c"),
                                               ("st", "host", "obsdesign_controller.st")])
def test_cli_controller_waits_warns_and_needs_a_delay(fmt, target, name, tmp_path, capsys):
    config = tmp_path / "delayed.toml"
    config.write_text(VCM.override(delay_samples=2).to_toml())
    out = tmp_path / "gen"
    code, stdout, err = _cli(capsys, "export", "--what", "controller", "--format", fmt, "--target", target,
                             "--config", str(config), "--controller-waits", "-o", str(out))
    assert code == 0 and len(err) == 1
    assert "--controller-waits" in err[0] and "hardware that has the delay must not run it" in err[0]
    assert "WAITS" in (out / name).read_text()
    # without the flag: no warning, a controller that does not wait
    code, _, err = _cli(capsys, "export", "--what", "controller", "--format", fmt, "--target", target,
                        "--config", str(config), "-o", str(tmp_path / "plain"))
    assert code == 0 and err == [] and "WAITS" not in (tmp_path / "plain" / name).read_text()
    # no delay in the config: nothing to wait for; the observer export has no controller
    code, _, err = _cli(capsys, "export", "--what", "controller", "--format", fmt, "--controller-waits",
                        "-o", str(tmp_path / "no"))
    assert code == 2 and len(err) == 1 and "expected delay_samples >= 1 in the config, found 0" in err[0]
    code, _, err = _cli(capsys, "export", "--format", "python", "--config", str(config), "--controller-waits",
                        "-o", str(tmp_path / "no"))
    assert code == 2 and len(err) == 1 and "applies to --what controller only" in err[0]
    assert not (tmp_path / "no").exists()
