"""The exported whole controller: each language is run and compared with the simulator's ``u``.

The exported step returns the command [V] after saturation with the load feed-forward, so
``K * command - G`` must equal the simulator's ``u`` column (1e-9 relative to its largest value).
The compensation knobs are checked against a reference step written here from the kernel and
the knob law, itself first checked against the simulator with the default knobs.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import math
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import obsdesign as od
from obsdesign.export.controller import (
    REVERSAL_NOISE_FACTOR,
    SCHEDULE_NAMES,
    SCHEDULE_ZERO,
    CompensationSpec,
    controller_constants,
    controller_files,
    sanitize_comment,
)
from obsdesign.sampled.choices import ESTIMATORS, SCHEDULES
from obsdesign.design.discretize import coefficients
from obsdesign.friction.presliding import stiffness, track_reversal

VCM = od.load_preset("vcm")
HAS_GCC = shutil.which("gcc") is not None
HAS_NODE = shutil.which("node") is not None
HAS_OCTAVE = shutil.which("octave") is not None

CASES = {
    "tracking": (VCM, dict(scenario="tracking", controller="pid+observer")),
    "positioning": (VCM, dict(scenario=od.sim.Positioning(step_down=1.2), controller="pid+observer")),
    "pid-only": (VCM, dict(scenario="tracking", controller="pid")),
    "saturated": (VCM.override(u_max=1.8), dict(scenario=od.sim.Positioning(step_down=1.2), controller="pid+observer")),
    # the lag observer runs in its model plant (plant="model", the CLI's default for it): in the physical lag plant
    # table1's compensated loop runs away at the actuator's limit (flagged 'runaway' since issue 33 point 4)
    "noisy-lag": (od.load_preset("table1").override(noise_rms=2e-7),
                  # simulated and exported with the schedule without reversal hysteresis
                  dict(scenario="tracking", controller="pid+observer", stiffness="estimated-raw", plant="model")),
    # the drive's delay ([hardware] delay_samples): the simulated plant applies the command of sample n from
    # n + d; the exported controller has no delay (_applied shifts its commands)
    "delayed": (od.load_preset("table1").override(quantization=1e-7, delay_samples=2),
                dict(scenario=od.sim.Positioning(step_down=1.2), controller="pid+observer", plant="model")),
    "delayed-eso": (VCM.override(noise_rms=1e-6, delay_samples=1),
                    dict(scenario="tracking", controller="pid+observer", estimator="eso")),
}


#: Every schedule of 'paper', then every other estimator (their schedule has no effect).
PARITY = ([("paper", name) for name in SCHEDULES.names() if name != "true"]
          + [(name, "estimated") for name in ESTIMATORS.names() if name != "paper"])


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    cfg, kw = CASES[request.param]
    kw = dict(kw)
    scenario = kw.pop("scenario")
    res = od.simulate(cfg, scenario, duration=2.0, **kw)
    assert not res.metrics["diverged"]
    if request.param == "saturated":
        cmd = (res.u + cfg.plant.G) / cfg.plant.K
        # the limit is active for a while; 1.8 V is above the load G/K = 1.61 V (at 0.5 V the axis could not hold
        # its load and fell 0.3 m, a runaway since issue 33 point 4)
        assert np.sum(np.abs(np.abs(cmd) - 1.8) < 1e-12) > 100
    return request.param, cfg, kw["controller"], res


# ---------------------------------------------------------------------------------------------
# Runners: each takes the files of one language and returns the commands for the inputs; ``extra``
# holds the further inputs of the step (v_ref, w_ff of the feed-forward modes).
def _run_python(files, x_ref, x_meas, tmp_path, extra=()):
    (path,) = [tmp_path / n for n in files]
    path.write_text(files[path.name])
    spec = importlib.util.spec_from_file_location(f"exported_controller_{id(files)}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    ctrl = mod.Controller()
    return np.array([ctrl.step(*map(float, row)) for row in zip(x_ref, x_meas, *extra)])


def _c_driver(n_in):
    names = ["r", "x", "v", "w"][:n_in]
    fmt = ",".join(["%lf"] * n_in)
    return rf"""
#include <stdio.h>
#include "obsdesign_controller.h"
int main(int argc, char **argv) {{
    double {", ".join(names)};
    obsdesign_controller c;
    FILE *in;
    if (argc != 2 || !(in = fopen(argv[1], "r"))) return 2;
    obsdesign_controller_init(&c);
    while (fscanf(in, "{fmt}", {", ".join("&" + n for n in names)}) == {n_in})
        printf("%.17g\n", obsdesign_controller_step(&c, {", ".join(names)}));
    fclose(in);
    return 0;
}}
"""


C_DRIVER = _c_driver(2)


def _compile_c(files, tmp_path, n_in=2):
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "driver.c").write_text(_c_driver(n_in))
    exe = tmp_path / "driver"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", f"-I{tmp_path}", "-o",
                    str(exe), str(tmp_path / "driver.c"), str(tmp_path / "obsdesign_controller.c"), "-lm"],
                   check=True, capture_output=True, text=True)
    return exe


def _run_c(files, x_ref, x_meas, tmp_path, extra=()):
    exe = _compile_c(files, tmp_path, 2 + len(extra))
    data = tmp_path / "in.csv"
    np.savetxt(data, np.column_stack([x_ref, x_meas, *extra]), delimiter=",", fmt="%.17g")
    out = subprocess.run([str(exe), str(data)], capture_output=True, text=True, check=True).stdout
    return np.loadtxt(out.splitlines())


def _run_js(files, x_ref, x_meas, tmp_path, extra=()):
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    rows = [list(map(float, row)) for row in zip(x_ref, x_meas, *extra)]
    (tmp_path / "in.json").write_text(json.dumps(rows))
    module = (tmp_path / "obsdesign_controller.mjs").as_uri()
    script = (f"import {{ Controller }} from {json.dumps(module)}; import fs from 'fs';"
              f"const d = JSON.parse(fs.readFileSync({json.dumps(str(tmp_path / 'in.json'))}, 'utf8'));"
              "const c = new Controller();"
              "console.log(JSON.stringify(d.map((row) => c.step(...row))));")
    out = subprocess.run(["node", "--input-type=module", "-e", script], capture_output=True, text=True, check=True)
    return np.array(json.loads(out.stdout))


def _run_octave(files, x_ref, x_meas, tmp_path, extra=(), *, persistent=False):
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    np.savetxt(tmp_path / "in.csv", np.column_stack([x_ref, x_meas, *extra]), delimiter=",", fmt="%.17g")
    args = ", ".join(f"data(i, {j + 1})" for j in range(2 + len(extra)))
    call = (f"out(i) = obsdesign_controller({args});" if persistent else
            f"[out(i), st] = obsdesign_controller_step(st, {args});")
    script = ("data = dlmread('in.csv', ','); st = obsdesign_controller_init(); out = zeros(rows(data), 1);"
              f"for i = 1:rows(data) {call} end; fprintf('%.17g\\n', out);")
    out = subprocess.run(["octave", "--no-gui", "--quiet", "--no-window-system", "--eval", script],
                         capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert out.returncode == 0, out.stderr
    return np.loadtxt(out.stdout.splitlines())


RUNNERS = {
    "python": (_run_python, True),
    "c": (_run_c, HAS_GCC),
    "js": (_run_js, HAS_NODE),
    "octave": (_run_octave, HAS_OCTAVE),
}


def _applied(command, cfg):
    """The commands the simulated drive applies: those of ``command`` ``[hardware] delay_samples`` later, the
    saturated feed-forward ``G / K`` before the first one arrives (the exported controller has no delay)."""
    d, pl = cfg.hardware.delay_samples, cfg.plant
    command = np.asarray(command)
    if d == 0:
        return command
    return np.concatenate([np.full(d, min(max(pl.G / pl.K, -pl.u_max), pl.u_max)), command[:-d]])


def _max_rel(command, cfg, u_ref):
    u = cfg.plant.K * _applied(command, cfg) - cfg.plant.G
    return float(np.max(np.abs(u - u_ref[: len(u)])) / np.max(np.abs(u_ref)))


@pytest.mark.parametrize("language", list(RUNNERS))
def test_exported_controller_reproduces_the_simulator(language, case, tmp_path):
    run, available = RUNNERS[language]
    if not available:
        pytest.skip(f"{language}: toolchain not installed")
    name, cfg, controller, res = case
    n = len(res.t)
    files = controller_files(cfg, language, controller=controller, schedule=res.stiffness_schedule,
                             estimator=res.estimator)
    command = run(files, res.x_ref[:n], res.x_meas[:n], tmp_path)
    assert command.shape == (n,)
    assert _max_rel(command, cfg, res.u) <= 1e-9
    assert np.all(np.abs(command) <= cfg.plant.u_max)


@pytest.mark.skipif(not HAS_OCTAVE, reason="octave not installed")
def test_octave_persistent_wrapper_equals_the_state_in_out_step(tmp_path):
    res = od.simulate(VCM, "tracking", controller="pid+observer", duration=0.2)
    files = controller_files(VCM, "octave")
    a = _run_octave(files, res.x_ref, res.x_meas, tmp_path, persistent=True)
    assert _max_rel(a, VCM, res.u) <= 1e-9


@pytest.mark.parametrize("estimator, schedule", [("paper", "estimated")] + PARITY[1:],
                         ids=lambda v: v)
def test_octave_files_are_well_formed(estimator, schedule):
    cfg = VCM if (estimator, schedule) == ("paper", "estimated") else od.load_preset("table1")
    files = controller_files(cfg, "octave", estimator=estimator, schedule=schedule)
    for name, text in files.items():
        assert text.startswith(f"function ") and re.match(rf"function .*\b{name[:-2]}\(", text)
        assert "%#codegen" in text
        # every 'function' (and control block) is closed: count block openers against 'end' lines
        opens = len(re.findall(r"^\s*(function|if|for|while)\b", text, flags=re.M))
        assert opens == len(re.findall(r"^\s*end\s*$", text, flags=re.M))
    assert "persistent state" in files["obsdesign_controller.m"]
    consts = controller_constants(cfg, estimator=estimator, schedule=schedule)
    step = files["obsdesign_controller_step.m"]
    for key, value in consts.items():
        assert f"\n{key} = {value!r};\n" in step


# ---------------------------------------------------------------------------------------------
# Compensation knobs against a reference step written from the kernel and the knob law.
def _flat(loop):
    """The numbers of a run's sampled controller under one namespace (the reference below reads them)."""
    import types

    obs, _, ctrl = loop.sampled.kernel_args()
    return types.SimpleNamespace(**{**obs._asdict(), **ctrl._asdict()}, tau_d=loop.sampled.tau_d)


def _reference_commands(loop, x_ref, x_meas, comp: CompensationSpec):
    """Steps 2-5 of the kernel's sample, with ``comp = gain (ff + sigma vh [viscous]) fade``."""
    loop = _flat(loop)
    A0, A1, b0, b1, g0, g1 = loop.A0, loop.A1, loop.b0, loop.b1, loop.g0, loop.g1
    alpha = math.exp(-loop.dt / loop.tau_d)
    y = np.zeros(2)
    zf = np.zeros(2)
    branch = (0.0, 0.0, 0.0)
    k_coef = -1.0
    integ = deriv = e_prev = u_prev = fh_prev = xm_prev = 0.0
    out = []
    for n, (r, xm) in enumerate(zip(x_ref, x_meas)):
        if n == 0:
            y = np.array([loop.v_hat0 - loop.L1 * xm, loop.f_hat0 - loop.L2 * xm])
        else:
            y = P @ y + bu * u_prev + gx0 * xm_prev + gx1 * xm
        vh, fh = y[0] + loop.L1 * xm, y[1] + loop.L2 * xm
        if n > 0:
            zf = loop.lp_phi @ zf + loop.lp_g0 * fh_prev + loop.lp_g1 * fh
        ff = zf[0]
        branch = track_reversal(vh, xm, *branch, loop.s)
        k = stiffness(xm, *branch, loop.Cf, loop.s, loop.kappa)
        if k != k_coef:
            k_coef = k
            c = np.array(coefficients(*(A0 + k * A1).ravel(), loop.dt))
            P, G0, G1 = c[0:4].reshape(2, 2), c[4:8].reshape(2, 2), c[8:12].reshape(2, 2)
            bu = G0 @ (b0 + k * b1)
            gx1 = G1 @ (g0 + k * g1)
            gx0 = G0 @ (g0 + k * g1) - gx1
        e = r - xm
        if n == 0:
            e_prev = e
        deriv = alpha * deriv + (1.0 - alpha) * (e - e_prev) / loop.dt
        integ_new = integ + e * loop.dt
        u_volt = loop.kp * e + loop.ki * integ_new + loop.kd * deriv
        fade = min(1.0, abs(vh) / comp.deadzone) if comp.deadzone > 0 else 1.0
        u_volt += comp.gain * (ff + (loop.sigma * vh if comp.viscous else 0.0)) * fade / loop.K
        total = u_volt + loop.G / loop.K
        if abs(total) <= loop.u_max:
            integ = integ_new
        e_prev = e
        total = min(max(total, -loop.u_max), loop.u_max)
        u_prev = loop.K * total - loop.G
        fh_prev, xm_prev = fh, xm
        out.append(total)
    return np.array(out)


@pytest.fixture(scope="module")
def knob_inputs():
    kw = dict(controller="pid+observer", duration=1.0)
    res = od.simulate(VCM, "tracking", **kw)
    loop = od.loop.prepare(VCM, "tracking", **kw)
    ref = _reference_commands(loop, res.x_ref, res.x_meas, CompensationSpec())
    assert _max_rel(ref, VCM, res.u) <= 1e-9  # the reference is the simulator's loop
    return loop, res


KNOBS = [CompensationSpec(gain=0.5), CompensationSpec(viscous=True), CompensationSpec(deadzone=2e-3),
         CompensationSpec(gain=0.7, viscous=True, deadzone=5e-4)]


@pytest.mark.parametrize("language", list(RUNNERS))
@pytest.mark.parametrize("comp", KNOBS, ids=lambda c: f"g{c.gain}-v{int(c.viscous)}-d{c.deadzone}")
def test_compensation_knobs_follow_the_law(language, comp, knob_inputs, tmp_path):
    run, available = RUNNERS[language]
    if not available:
        pytest.skip(f"{language}: toolchain not installed")
    loop, res = knob_inputs
    n = len(res.t)
    ref = _reference_commands(loop, res.x_ref[:n], res.x_meas[:n], comp)
    default = (res.u[:n] + VCM.plant.G) / VCM.plant.K
    assert np.max(np.abs(ref - default)) > 1e-4  # the knob changes the command
    command = run(controller_files(VCM, language, compensation=comp), res.x_ref[:n], res.x_meas[:n], tmp_path)
    assert np.max(np.abs(command - ref)) <= 1e-9 * np.max(np.abs(ref))


# ---------------------------------------------------------------------------------------------
# Parity contract: every schedule and every estimator, under sensor noise and quantization.
# (benchmarks/parity.py runs the same over 60 s tracking and the whole positioning scenario.)
NOISY = {
    # static, noise 1 um: the lag variant runs away in the physical lag plant (issue 33 point 4) and saturates in
    # its model plant (a spring sigma/beta); its parity is the 'noisy-lag' case above
    "tracking": (od.load_preset("table1").override(quantization=1e-7, variant="static"), "tracking", 0.5),
    "positioning": (VCM.override(noise_rms=1e-6), od.sim.Positioning(step_up=0.05, step_down=0.4), 0.7),  # static
}
PARITY_KNOBS = {"default": CompensationSpec(), "knobs": CompensationSpec(gain=0.7, viscous=True, deadzone=1e-4)}


def _noisy_run(scenario_name, estimator, schedule, knobs):
    cfg, scenario, duration = NOISY[scenario_name]
    comp = PARITY_KNOBS[knobs]
    cfg = cfg.override(gain=comp.gain, viscous=comp.viscous, deadzone=comp.deadzone)
    res = od.simulate(cfg, scenario, controller="pid+observer", stiffness=schedule, estimator=estimator,
                      duration=duration)
    # parity needs finite traces, not a good loop: ('paper', 'constant') runs away on table1's tracking
    # (|e| 0.14 m, flagged 'runaway' since issue 33 point 4), and the export must reproduce that run too
    assert res.metrics["divergence"] in (None, "runaway")
    return cfg, res


# The compensation knobs' half of the cases is slow (make test runs it; the knobs' law is in the fast run
# through test_compensation_knobs_follow_the_law).
@pytest.fixture(scope="module", params=[pytest.param((s, e, sc, k), marks=[pytest.mark.slow] if k == "knobs" else [])
                                        for s in NOISY for e, sc in PARITY for k in PARITY_KNOBS],
                ids=lambda p: "-".join(p))
def noisy_case(request):
    scenario_name, estimator, schedule, knobs = request.param
    cfg, res = _noisy_run(scenario_name, estimator, schedule, knobs)
    return cfg, estimator, schedule, res


@pytest.mark.parametrize("language", list(RUNNERS))
def test_every_schedule_and_estimator_reproduces_the_simulator_under_noise(language, noisy_case, tmp_path):
    run, available = RUNNERS[language]
    if not available:
        pytest.skip(f"{language}: toolchain not installed")
    cfg, estimator, schedule, res = noisy_case
    files = controller_files(cfg, language, schedule=schedule, estimator=estimator)
    command = run(files, res.x_ref, res.x_meas, tmp_path)
    assert command.shape == res.u.shape
    assert _max_rel(command, cfg, res.u) <= 1e-9


@pytest.mark.parametrize("scenario_name", list(NOISY))
def test_the_parity_cases_exercise_the_hysteresis_and_the_knobs(scenario_name):
    """The noisy runs are not vacuous: the hysteresis changes the simulated command, and so do the knobs."""
    _, hyst = _noisy_run(scenario_name, "paper", "estimated", "default")
    _, raw = _noisy_run(scenario_name, "paper", "estimated-raw", "default")
    _, knobs = _noisy_run(scenario_name, "paper", "estimated", "knobs")
    assert np.max(np.abs(hyst.u - raw.u)) > 1e-3 * np.max(np.abs(hyst.u))
    assert np.max(np.abs(hyst.u - knobs.u)) > 1e-3 * np.max(np.abs(hyst.u))
    assert np.any(hyst.stiffness != raw.stiffness)


def test_the_python_export_reproduces_the_simulated_estimates_and_schedule(tmp_path):
    """Beyond ``u``: v_hat, f_hat, the compensated estimate and the stiffness of every sample."""
    for estimator, schedule in (("paper", "estimated"), ("dob", "estimated")):
        cfg, res = _noisy_run("positioning", estimator, schedule, "default")
        text = controller_files(cfg, "python", schedule=schedule, estimator=estimator)["obsdesign_controller.py"]
        namespace: dict = {}
        exec(compile(text, "obsdesign_controller.py", "exec"), namespace)
        ctrl = namespace["Controller"]()
        got = []
        for r, x in zip(res.x_ref, res.x_meas):
            ctrl.step(float(r), float(x))
            got.append((ctrl.v_hat, ctrl.f_hat, ctrl.f_hat_filtered, ctrl.stiffness))
        got = np.array(got)
        for col, name in enumerate(("v_hat", "f_hat", "f_hat_filtered", "stiffness")):
            np.testing.assert_array_equal(got[:, col], getattr(res, name), err_msg=f"{estimator}: {name}")


def test_the_export_and_the_simulator_share_the_choices_and_the_threshold():
    from obsdesign.sim.simulate import REVERSAL_NOISE_FACTOR as SIM_FACTOR

    assert REVERSAL_NOISE_FACTOR == SIM_FACTOR
    assert SCHEDULE_NAMES == tuple(name for name in SCHEDULES.names() if name != "true")
    from obsdesign.export import CONTROLLER_FORMATS, TOOL_FORMATS
    from obsdesign.export.controller import LANGUAGES

    # every controller format has its templates, or is built around them (fmu: the c files; st: its own)
    assert set(LANGUAGES) | set(TOOL_FORMATS) == set(CONTROLLER_FORMATS)
    assert not set(LANGUAGES) & set(TOOL_FORMATS)
    assert SCHEDULE_ZERO not in {SCHEDULES.code(name) for name in SCHEDULES.names()}
    table1 = od.load_preset("table1")
    c = controller_constants(table1)
    assert c["SCHEDULE"] == SCHEDULES.code("estimated") and c["REVERSAL_THRESHOLD"] == 4.0 * 1e-6
    assert controller_constants(VCM)["SCHEDULE"] == SCHEDULES.code("estimated-raw")  # no noise: no hysteresis
    assert controller_constants(table1, estimator="paper-k0", schedule="constant")["SCHEDULE"] == SCHEDULE_ZERO
    eso = controller_constants(table1, estimator="eso")
    assert eso["E_NZ"] == 3.0 and "L1" not in eso and "E_PHI_2_2" in eso


@pytest.mark.slow  # a fresh interpreter that exports twice (4-6 s)
def test_a_paper_export_does_not_load_the_estimators():
    """The baselines' modules (python-control tuning) are imported only when a baseline is exported; the
    estimators' light catalogue (obsdesign.estimators.registry, the names) is read either way."""
    code = ("import sys, obsdesign as od; from obsdesign.export.controller import controller_files; "
            "controller_files(od.load_preset('table1'), 'c', estimator='paper-k0'); "
            "assert 'obsdesign.estimators.base' not in sys.modules; "
            "controller_files(od.load_preset('table1'), 'c', estimator='kalman'); "
            "assert 'obsdesign.estimators.base' in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)


# ---------------------------------------------------------------------------------------------
# Hostile config names, C hygiene, errors
HOSTILE = ['"""; import os; os.system("x") #', "*/ int evil; /*", "a\\\nb", "nul\x00name", "two\nlines\r\nx",
           "sep\u2028para\u2029", "</script><!--", "${x} `y` % %s ]]", "x" * 500]


@pytest.mark.parametrize("name", HOSTILE, ids=range(len(HOSTILE)))
def test_hostile_names_are_sanitized_everywhere(name, tmp_path):
    cfg = dataclasses.replace(VCM, name=name)
    safe = sanitize_comment(name)
    assert re.fullmatch(r"[A-Za-z0-9 _.,+\-]*", safe) and len(safe) <= 64
    for language in RUNNERS:
        files = controller_files(cfg, language)
        for text in files.values():
            assert safe in text
            assert not set(text) & {"\x00", "\u2028", "\u2029", "\r"}
            if len(name) > 64:
                assert name not in text
    # the exported code still works: Python imports and runs, C compiles strictly, JS parses
    x_ref, x_meas = np.full(50, 1e-4), np.linspace(0.0, 2e-5, 50)
    (tmp_path / "plain").mkdir()
    ref = _run_python(controller_files(VCM, "python"), x_ref, x_meas, tmp_path / "plain")
    got = _run_python(controller_files(cfg, "python"), x_ref, x_meas, tmp_path)
    np.testing.assert_array_equal(got, ref)
    if HAS_GCC:
        _compile_c(controller_files(cfg, "c"), tmp_path)
    if HAS_NODE:
        (tmp_path / "m.mjs").write_text(controller_files(cfg, "js")["obsdesign_controller.mjs"])
        subprocess.run(["node", "--check", str(tmp_path / "m.mjs")], check=True, capture_output=True)


@pytest.mark.skipif(not HAS_GCC or shutil.which("nm") is None, reason="gcc/nm not installed")
@pytest.mark.parametrize("estimator", ["paper", "kalman"])
def test_c_object_has_no_data_symbols_and_no_allocation(estimator, tmp_path):
    files = controller_files(VCM, "c", estimator=estimator)
    assert "malloc" not in files["obsdesign_controller.c"]
    assert ("static double od_" in files["obsdesign_controller.c"]) == (estimator == "paper")  # baselines: no core
    assert "typedef struct obsdesign_controller {" in files["obsdesign_controller.h"]
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    obj = tmp_path / "controller.o"
    subprocess.run(["gcc", "-std=c99", "-c", "-O2", "-o", str(obj), str(tmp_path / "obsdesign_controller.c")], check=True)
    symbols = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout.splitlines()
    assert not [s for s in symbols if re.match(r"^\S*\s+[BbDdCc]\s", s)]  # read-only literals (r) are fine
    defined = {s.split()[-1] for s in symbols if " T " in s}
    assert defined == {"obsdesign_controller_init", "obsdesign_controller_step"}


def test_python_module_uses_the_standard_library_only():
    text = controller_files(VCM, "python")["obsdesign_controller.py"]
    imports = set(re.findall(r"^(?:import|from) (\w+)", text, flags=re.M))
    assert imports == {"math"}
    assert "numba" not in text and "numpy" not in text


def test_pid_export_does_not_compensate():
    assert controller_constants(VCM, controller="pid")["COMP_ON"] == 0.0
    assert controller_constants(VCM)["COMP_ON"] == 1.0


@pytest.mark.parametrize("args, kwargs, exc, match", [
    ((VCM, "fortran"), {}, ValueError, "language: expected one of c, python, octave, js"),
    ((VCM, "c"), {"controller": "open-loop"}, ValueError, "controller: expected one of pid, pid"),
    ((VCM, "c"), {"compensation": {"gain": 1.0}}, TypeError, "compensation: expected a CompensationSpec"),
    ((VCM, "c"), {"controller": "pid", "compensation": CompensationSpec(gain=0.5)}, ValueError,
     "compensation: only the controller 'pid\\+observer'"),
    (("vcm", "c"), {}, TypeError, "cfg: expected a Config"),
    ((VCM, "c"), {"schedule": "true"}, ValueError,
     "schedule: 'true' \\(the simulated plant's stiffness\\) cannot run on an axis; expected one of estimated, "
     "constant, estimated-raw, found 'true'"),
    ((VCM, "c"), {"schedule": "raw"}, ValueError, "schedule: expected one of estimated, constant, estimated-raw, "
     "found 'raw'"),
    ((VCM, "c"), {"estimator": "luenberger"}, ValueError,
     "estimator: expected one of paper, paper-k0, eso, kalman, dob, found 'luenberger'"),
    ((VCM, "c"), {"estimator": 3}, ValueError, "estimator: expected one of .*found 3"),
])
def test_controller_files_errors(args, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        controller_files(*args, **kwargs)


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"gain": 0.0}, ValueError, r"compensation.gain: expected a finite number > 0 and <= 1, found 0.0"),
    ({"gain": 1.01}, ValueError, "compensation.gain"),
    ({"gain": math.nan}, ValueError, "compensation.gain"),
    ({"gain": "1"}, TypeError, "compensation.gain: expected a finite number > 0 and <= 1, found str '1'"),
    ({"viscous": 1}, TypeError, "compensation.viscous: expected true or false, found int 1"),
    ({"deadzone": -1e-3}, ValueError, "compensation.deadzone: expected a finite number >= 0"),
    ({"deadzone": math.inf}, ValueError, "compensation.deadzone"),
    ({"deadzone": True}, TypeError, "compensation.deadzone: expected a finite number >= 0 and <= 1000, found bool True"),
])
def test_compensation_spec_errors(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        CompensationSpec(**kwargs)


def test_compensation_spec_is_frozen_and_normalized():
    spec = CompensationSpec(gain=1, deadzone=0)
    assert spec == CompensationSpec() and isinstance(spec.gain, float)
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.gain = 0.5  # type: ignore[misc]
