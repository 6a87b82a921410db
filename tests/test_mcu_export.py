"""The cortex-m4f target of the controller export (issue 34): float32 only, no library call, no division,
proven on the ARM target (arm-none-eabi-gcc, unicorn) against the host double controller."""

import math
import re
import shutil
import subprocess

import numpy as np
import pytest
import scipy.linalg

import obsdesign as od
from obsdesign.export import armcheck, export
from obsdesign.export.controller import controller_files
from obsdesign.export.mcu import float_literal, mcu_controller_files
from obsdesign.export.mcu_tables import exact_coefficients, log_polynomial, stiffness_table
from obsdesign.loop.scenarios import Chirp
from obsdesign.sampled import sampled_controller

VCM = od.load_preset("vcm")  # encoder 1 um, no noise: the estimated-raw schedule
# 1.1 um noise on the 1 um encoder: the schedule with the reversal hysteresis (4.4 um: not a whole number of
# counts, where the double controller would decide a tie by the rounding of its differences)
NOISY = VCM.override(noise_rms=1.1e-6)
LAG = od.load_preset("table1").override(quantization=1e-6, noise_rms=1.1e-6)  # the lag variant
VCM_DELAYED = VCM.override(delay_samples=1)  # the drive's delay: the state grows by a ring of one command
MISSING = armcheck.toolchain_missing()
HAS_GCC = shutil.which("gcc") is not None


def _counts(res, q):
    return np.rint(res.x_ref / q).astype(np.int32), np.rint(res.x_meas / q).astype(np.int32)


def test_the_table_is_the_exact_discretisation():
    """The stored cubics against SciPy's matrix exponential (an independent computation) at off-grid stiffnesses."""
    ctrl = sampled_controller(VCM)
    table = stiffness_table(ctrl)
    obs, h = ctrl.observer, ctrl.dt
    L = np.array([obs.design.L1, obs.design.L2])
    for k in (0.0, 123.4, 4321.0, 7999.9, 8000.0):
        A = obs.A0 + k * obs.A1
        Phi = scipy.linalg.expm(A * h)
        # Gamma0 = int_0^h exp(A s) ds from the augmented exponential
        M = np.zeros((4, 4))
        M[:2, :2], M[:2, 2:] = A * h, np.eye(2) * h
        Gamma0 = scipy.linalg.expm(M)[:2, 2:]
        gd = Gamma0 @ L / h  # phi1(A h) L: the increment's gain
        E = Phi - np.eye(2)
        E[:, 0] += h * gd
        expected = np.concatenate([E.ravel(), Gamma0 @ (obs.b0 + k * obs.b1), gd])
        scale = np.array([1, 1, 1, 1, 1, 1, 1, 1]) * table.scale  # each coefficient's range over [0, kappa]
        assert np.all(np.abs(table.evaluate(k) - expected) <= 2e-7 * scale), (k, table.evaluate(k) - expected)
    assert table.relative_error < 1e-7  # at float32's own rounding


def test_the_increment_form_needs_no_absolute_position():
    """g = A L: the coefficients of x[n] and x[n+1] cancel, so only the increment enters (at each stiffness)."""
    ctrl = sampled_controller(LAG)
    for k in (0.0, 5000.0):
        exact_coefficients(ctrl, k)  # raises when the residual is not at rounding level


def test_the_log_polynomial_against_math_log():
    poly = log_polynomial()
    t = np.linspace(math.sqrt(0.5) - 1, math.sqrt(2) - 1, 1001)
    approx = t * np.polynomial.polynomial.polyval(t, poly.coefficients)
    assert np.max(np.abs(approx - np.log1p(t))) <= poly.max_error <= 1e-7


#: Every shape of the generated code: the three schedules, paper-k0, the knobs, pid.
SHAPES = [(VCM, {}), (NOISY, {}), (LAG, {}), (VCM, {"estimator": "paper-k0"}), (VCM, {"schedule": "constant"}),
          (VCM.override(gain=0.8, deadzone=1e-4, viscous=True), {}), (VCM, {"controller": "pid"})]


def test_generated_code_has_no_double_no_division_no_library():
    for cfg, kw in SHAPES:
        text = mcu_controller_files(cfg, **kw)["obsdesign_controller.c"]
        code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
        assert "double" not in code and "#include <math.h>" not in code
        literals = re.findall(r"(?<![\w.])(\d+\.\d*(?:e[-+]?\d+)?|\d+e[-+]?\d+)(f?)", code)
        assert literals and all(suffix == "f" for _, suffix in literals)
        assert " / " not in code and "/=" not in code


@pytest.mark.skipif(not HAS_GCC, reason="gcc not installed")
def test_host_build_is_strict_and_float_only(tmp_path):
    for cfg, kw in SHAPES:
        for name, text in mcu_controller_files(cfg, **kw).items():
            (tmp_path / name).write_text(text)
        subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wdouble-promotion",
                        "-Wfloat-conversion", "-O2", "-c", "obsdesign_controller.c"], cwd=tmp_path, check=True)
        undefined = subprocess.run(["nm", "-u", "obsdesign_controller.o"], cwd=tmp_path, capture_output=True,
                                   text=True, check=True).stdout.split()
        assert [s for s in undefined if s != "U"] == []  # no libm, no memset/memcpy


@pytest.mark.skipif(MISSING is not None, reason=f"the ARM toolchain: {MISSING}")
def test_arm_object_needs_nothing_and_fits(tmp_path):
    arm = armcheck.build(mcu_controller_files(NOISY), tmp_path)
    assert not any(s.startswith("__aeabi_d") for s in arm.symbols)
    assert set(arm.symbols) <= {"obsdesign_controller_init", "obsdesign_controller_step", "od_table", "od_ln",
                                "od_coulomb_n", "od_stiffness", "od_track", "od_coefficients", "od_diff", "od_acc",
                                "od_abs"}
    assert arm.ram == 0 and arm.flash < 8192 and arm.state < 160 and arm.stack < 128
    dis = subprocess.run(["arm-none-eabi-objdump", "-d", str(tmp_path / "obsdesign_controller.o")],
                         capture_output=True, text=True, check=True).stdout
    assert "vdiv" not in dis and "sdiv" not in dis and "udiv" not in dis  # no division, float or integer


def _compare(cfg, scenario, duration, controller, tmp_path, *, count=True):
    q = cfg.sensor.quantization
    res = od.simulate(cfg, scenario, duration=duration, controller=controller)
    x_ref, x_meas = _counts(res, q)
    arm = armcheck.build(mcu_controller_files(cfg, controller=controller), tmp_path / "arm")
    run = armcheck.emulate(arm, x_ref, x_meas, count=count)
    host = armcheck.host_run(controller_files(cfg, "c", controller=controller), x_ref * q, x_meas * q, tmp_path / "host")
    return res, run, host


@pytest.mark.skipif(MISSING is not None or not HAS_GCC, reason=f"the ARM toolchain or gcc: {MISSING}")
@pytest.mark.parametrize("cfg, scenario, controller", [
    (VCM, od.sim.Positioning(step_up=0.1, step_down=0.6), "pid+observer"),
    (NOISY, "tracking", "pid+observer"),
    # the lag variant (table1) compensating runs away in the simulator itself on this scenario: monitored
    (LAG, "tracking", "pid"),
    # the drive's delay: both controllers feed their estimator the command of d samples earlier (a ring)
    (VCM_DELAYED, od.sim.Positioning(step_up=0.1, step_down=0.6), "pid+observer"),
], ids=["vcm", "vcm-noisy", "table1-lag", "vcm-delay-1"])
def test_emulated_step_matches_the_host_double_controller(cfg, scenario, controller, tmp_path):
    res, run, host = _compare(cfg, scenario, 1.0, controller, tmp_path)
    # the host controller on unrounded set-points is the simulator (bit-exact): the reference is not vacuous
    if cfg is VCM or cfg is VCM_DELAYED:  # (the set-points of the steps are whole counts)
        np.testing.assert_array_equal(host.f_hat, res.f_hat)
    Cf = cfg.friction.Cf
    assert np.max(np.abs(run.f_hat - host.f_hat)) <= 1e-3 * Cf
    assert np.max(np.abs(run.f_hat_filtered - host.f_hat_filtered)) <= 1e-3 * Cf
    assert np.max(np.abs(run.command - host.command)) <= 1e-4 * cfg.plant.u_max
    assert run.instructions.max() <= 1500
    assert run.instructions.min() >= 100  # a real count: the step does more than return


@pytest.mark.slow
@pytest.mark.skipif(MISSING is not None or not HAS_GCC, reason=f"the ARM toolchain or gcc: {MISSING}")
def test_a_one_metre_stroke_over_a_million_steps_does_not_drift(tmp_path):
    """Issue 34's numbers: 1 m stroke at 1 um over 10^6 steps, friction within 0.1 % of Cf (estimator for
    monitoring: controller pid, so the replay has no compensation loop around the estimator)."""
    chirp = Chirp(f0=0.01, f1=0.1, peak_velocity=2 * np.pi * 0.1 * 0.5)  # +-0.5 m
    res, run, host = _compare(VCM, chirp, 100.0, "pid", tmp_path, count=False)
    assert np.ptp(res.x_meas) > 0.99
    err = np.abs(run.f_hat - host.f_hat)
    assert np.max(err) <= 1e-3 * VCM.friction.Cf


def test_float_literal_and_bad_input():
    assert float_literal(1.0) == "1.0f" and np.float32(float_literal(0.1)[:-1]) == np.float32(0.1)
    with pytest.raises(ValueError, match="constant: expected a finite number within float32's range"):
        float_literal(1e40)
    with pytest.raises(ValueError, match="compensation.mode: the cortex-m4f target"):
        mcu_controller_files(VCM.override(mode="feedforward"))
    with pytest.raises(ValueError, match="segments: expected an integer >= 1, found 0"):
        stiffness_table(sampled_controller(VCM), segments=0)


@pytest.mark.parametrize("kwargs, match", [
    ({"what": "observer"}, "target: 'cortex-m4f' applies to what='controller' in format 'c' only"),
    ({"what": "controller", "fmt": "python"}, "target: 'cortex-m4f' applies to what='controller' in format 'c'"),
])
def test_export_target_errors(kwargs, match, tmp_path):
    kw = {"fmt": "c", **kwargs}
    with pytest.raises(ValueError, match=match):
        export(VCM, kw.pop("fmt"), tmp_path, target="cortex-m4f", **kw)
    with pytest.raises(ValueError, match="target: expected one of host, cortex-m4f, real, found 'avr'"):
        export(VCM, "c", tmp_path, what="controller", target="avr")
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("args, match", [
    (["--target", "cortex-m4f"], "argument --target: cortex-m4f applies to --what controller --format c only"),
    (["--what", "controller", "--target", "cortex-m4f", "--preset", "table1"],
     "sensor.quantization: the cortex-m4f target reads the position in encoder counts"),
    (["--what", "controller", "--target", "cortex-m4f", "--estimator", "kalman"],
     "estimator: the cortex-m4f target runs the paper observer"),
    (["--what", "controller", "--target", "arm"], "argument --target: invalid choice: 'arm'"),
])
def test_cli_target_errors(args, match, tmp_path, monkeypatch, capsys):
    from obsdesign.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["export", "--format", "c", *args, "-o", "out"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0]
    assert list(tmp_path.iterdir()) == []


def test_cli_writes_the_target_files(tmp_path, capsys):
    from obsdesign.cli import main

    assert main(["export", "--format", "c", "--what", "controller", "--target", "cortex-m4f", "-o", str(tmp_path)]) == 0
    assert "float obsdesign_controller_step(obsdesign_controller *c, int32_t x_ref, int32_t x_meas);" in (
        tmp_path / "obsdesign_controller.h").read_text()


@pytest.mark.skipif(MISSING is not None, reason=f"the ARM toolchain: {MISSING}")
def test_the_ring_of_the_drive_delay_is_in_the_state_and_nowhere_else(tmp_path):
    """d = 2: the state grows by the ring (2 floats and its index, 12 bytes), no static RAM appears."""
    base = armcheck.build(mcu_controller_files(VCM), tmp_path / "d0")
    ring = armcheck.build(mcu_controller_files(VCM.override(delay_samples=2)), tmp_path / "d2")
    assert ring.state - base.state == 4 * 2 + 4 and ring.ram == base.ram == 0
    assert "12 bytes of the state" in mcu_controller_files(VCM.override(delay_samples=2))["obsdesign_controller.h"]
