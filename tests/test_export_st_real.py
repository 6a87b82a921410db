"""The REAL (float32) Structured Text block (obsdesign.export.st_real): run in float32 on the test evaluator
(tests/st_eval.py, numpy.float32 arithmetic) against the Python export (double) within the bound its header
states, and against the cortex-m4f C compiled on the host (float, no contraction): the same arithmetic."""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

import obsdesign as od
from obsdesign.export.controller import controller_files
from obsdesign.export.mcu import mcu_controller_files
from obsdesign.export.st import FB_NAME
from obsdesign.export.st_real import REAL_BOUND_COMMAND, REAL_BOUND_F_CF, real_block_files

blark = pytest.importorskip("blark", reason="blark (the test extra) is not installed")
from st_eval import Program, plcopen_source  # noqa: E402

ST, XML = "obsdesign_controller.st", "obsdesign_controller.xml"
VCM = od.load_preset("vcm")  # encoder 1 um, no noise: the estimated-raw schedule
HAS_GCC = shutil.which("gcc") is not None


def _counts(res, q):
    return np.round(np.asarray(res.x_ref) / q).astype(np.int64), np.round(np.asarray(res.x_meas) / q).astype(np.int64)


def _m4f_on_host(cfg, tmp_path):
    """The cortex-m4f C controller compiled for this machine (float32 SSE, no fused multiply-add): a step
    ``(x_ref, x_meas) [counts] -> (command, f_hat)``."""
    for name, text in mcu_controller_files(cfg).items():
        (tmp_path / name).write_text(text)
    (tmp_path / "glue.c").write_text(
        '#include <stddef.h>\n#include "obsdesign_controller.h"\n'
        "size_t od_size(void) { return sizeof(obsdesign_controller); }\n"
        "float od_f_hat(const obsdesign_controller *c) { return c->f_hat; }\n")
    lib = tmp_path / "libm4f.so"
    subprocess.run(["gcc", "-std=c99", "-O2", "-ffp-contract=off", "-shared", "-fPIC", f"-I{tmp_path}", "-o", str(lib),
                    str(tmp_path / "obsdesign_controller.c"), str(tmp_path / "glue.c")], check=True, capture_output=True)
    so = ctypes.CDLL(str(lib))
    so.od_size.restype = ctypes.c_size_t
    state = ctypes.create_string_buffer(so.od_size())
    so.obsdesign_controller_init(state)
    so.obsdesign_controller_step.restype = ctypes.c_float
    so.obsdesign_controller_step.argtypes = [ctypes.c_void_p, ctypes.c_int32, ctypes.c_int32]
    so.od_f_hat.restype = ctypes.c_float
    so.od_f_hat.argtypes = [ctypes.c_void_p]

    def step(x_ref, x_meas):
        return so.obsdesign_controller_step(state, int(x_ref), int(x_meas)), so.od_f_hat(state)
    return step


def test_the_real_block_has_no_lreal_and_states_its_bound():
    files = real_block_files(VCM)
    text = files[ST]
    assert "LREAL" not in text and "LREAL" not in files[XML]
    assert f"friction estimate within {REAL_BOUND_F_CF:g} x Cf, command within {REAL_BOUND_COMMAND:g} x u_max" in text
    assert "x_meas : DINT;" in text and "ring" not in text.replace("squaring", "")
    delayed = real_block_files(VCM.override(delay_samples=2))[ST]
    assert "ring : ARRAY[0..1] OF REAL" in delayed


@pytest.mark.parametrize("kwargs, match", [
    (dict(cfg=od.load_preset("table1")), "sensor.quantization: the cortex-m4f target reads the position"),
    (dict(cfg=VCM, estimator="eso"), "estimator: the cortex-m4f target runs the paper observer"),
    (dict(cfg=VCM.override(mode="feedforward")), "compensation.mode: the cortex-m4f target compensates"),
])
def test_the_real_block_refuses_what_the_float32_profile_cannot_run(kwargs, match):
    kwargs = dict(kwargs)
    cfg = kwargs.pop("cfg")
    with pytest.raises(ValueError, match=match):
        real_block_files(cfg, **kwargs)


def test_export_writes_the_real_block_for_the_controller_only(tmp_path):
    from obsdesign.export import export

    paths = export(VCM, "st", tmp_path, what="controller", target="real")
    assert [p.name for p in paths] == [ST, "obsdesign_controller.xml"] and "OD_Ln32" in paths[0].read_text()
    with pytest.raises(ValueError, match="target: 'real' applies to what='controller' in format 'st' only"):
        export(VCM, "st", tmp_path, target="real")


@pytest.mark.slow  # blark parses the block with its 512-entry table in about 40 s (the XML case: twice)
@pytest.mark.parametrize("cfg, xml", [(VCM, True), (VCM.override(delay_samples=1), False),
                                      (VCM.override(noise_rms=1.1e-6), False)],
                         ids=["vcm+xml", "vcm-delay-1", "vcm-noisy-hysteresis"])
def test_the_real_block_in_float32_matches_the_double_controller_and_the_m4f_c(cfg, xml, tmp_path):
    q = cfg.sensor.quantization
    res = od.simulate(cfg, od.sim.Positioning(step_up=0.1, step_down=0.4), duration=0.6, controller="pid+observer")
    x_ref, x_meas = _counts(res, q)
    files = real_block_files(cfg)
    block = Program(files[ST], real32=True).block(FB_NAME)
    out = [block(int(r), int(m)) for r, m in zip(x_ref, x_meas)]
    command = np.array([o["COMMAND"] for o in out])
    f_hat = np.array([o["F_HAT"] for o in out])
    assert command.dtype == np.float32 and f_hat.dtype == np.float32  # the evaluator ran in float32
    if xml:  # the PLCopen XML a runtime imports, rebuilt from the XML alone: the same float32 numbers
        imported = Program(plcopen_source(files[XML]), real32=True).block(FB_NAME)
        again = [imported(int(r), int(m)) for r, m in zip(x_ref, x_meas)]
        assert np.array_equal([o["COMMAND"] for o in again], command)
        assert np.array_equal([o["F_HAT"] for o in again], f_hat)
        assert {type(o["F_HAT"]) for o in again} == {np.float32}
    # the double controller (the Python export, = simulate on these whole-count inputs)
    ns: dict = {}
    exec(controller_files(cfg, "python")["obsdesign_controller.py"], ns)
    ctrl = ns["Controller"]()
    ref, f_ref = [], []
    for r, m in zip(x_ref, x_meas):
        ref.append(ctrl.step(float(r) * q, float(m) * q))
        f_ref.append(ctrl.f_hat)
    np.testing.assert_array_equal(np.array(f_ref), res.f_hat)  # the reference is the simulator's estimate
    assert np.max(np.abs(f_hat - np.array(f_ref))) <= REAL_BOUND_F_CF * cfg.friction.Cf
    assert np.max(np.abs(command - np.array(ref))) <= REAL_BOUND_COMMAND * cfg.plant.u_max
    assert np.max(np.abs(f_hat - np.array(f_ref))) > 0.0  # float32: not the double's numbers
    if HAS_GCC:  # the cortex-m4f C on the host: the same float32 operations in the same order
        step = _m4f_on_host(cfg, tmp_path)
        m4f = np.array([step(r, m) for r, m in zip(x_ref, x_meas)], dtype=np.float32)
        np.testing.assert_array_equal(command, m4f[:, 0])
        np.testing.assert_array_equal(f_hat, m4f[:, 1])


def test_cli_writes_the_real_block_and_refuses_it_elsewhere(tmp_path, capsys):
    from obsdesign.cli import main

    out = tmp_path / "plc"
    assert main(["export", "--what", "controller", "--format", "st", "--target", "real", "-o", str(out)]) == 0
    assert "REAL (float32) profile" in (out / ST).read_text() and capsys.readouterr().err == ""
    assert main(["export", "--what", "controller", "--format", "c", "--target", "real", "-o", str(tmp_path / "no")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "argument --target: real applies to --what controller --format st only" in err[0]
    assert not (tmp_path / "no").exists()
