"""Units follow the axis (issue 32, points 6 and 7): every output of identify, observe, experiment and the
report's data section speaks of kg m^2, N m, rad, rad/s, torque constant and current limit on a rotary axis
(and of kg, N, m, m/s, force constant on a linear one); ``--counts-per-rev``; an input in A without its gain;
the rotary identification experiment, simulated and identified."""

from __future__ import annotations

import json
import math
import re
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from obsdesign.axis import AxisSpec
from obsdesign.cli import main

sys.path.insert(0, str(Path(__file__).parent))
from _axis_logs import AXES, axis_trace, noisy_log, simulate_axis  # noqa: E402

#: Linear unit strings and words: none may appear in a rotary axis's output.
LINEAR = (r"\bkg\b(?! m\^2)", r"(?<![/_(])\bN\b(?! m\b)(?!=)", r"\b[mun]?m/s", r"\[[mun]?m\]", r"(?<!N )\bm/A\b",
          r"\bmass\b", r"\bforces?\b", r"voltage", r"\bN/m\b", r"\bN s/m\b")
#: Rotary unit strings and words: none may appear in a linear axis's output.
ROTARY = (r"kg m\^2", r"\bN m\b", r"\binertia\b", r"\btorques?\b", r"\[[mun]?rad\]", r"\brad/A\b", r"N m s/rad")
#: Text that names no unit of an axis: the PID's derivative filter N ('N=10', '(kd/kp)/N').
_NOT_UNITS = re.compile(r"derivative filter N\b|\(kd/kp\)/N|derivative_N")


def leaks(text: str, patterns) -> list[str]:
    """Each match of ``patterns`` in ``text``, with 50 characters around it."""
    text = _NOT_UNITS.sub("", text)
    return [text[max(0, m.start() - 50):m.end() + 30] for p in patterns for m in re.finditer(p, text)]


def test_the_scanner_finds_what_it_looks_for():
    """The patterns catch each unit string a wrong output would print, and let the right ones through."""
    assert leaks("m = 2 [kg] moving mass, Cf 0.3 N, v 2 m/s, x [um], kappa [N/m]", LINEAR) != []
    for bad in ("2 kg", "0.3 N", "2 m/s", "[mm]", "moving mass", "the force", "voltage limit", "[N s/m]"):
        assert leaks(bad, LINEAR), bad
    assert leaks("m 2 kg m^2, Cf 0.3 N m, sigma 1 N m s/rad, v 2 rad/s, x [urad], N=10 (kd/kp)/N", LINEAR) == []
    for bad in ("2 kg m^2", "0.3 N m", "inertia", "torque constant", "[urad]", "[rad/A]"):
        assert leaks(bad, ROTARY), bad
    assert leaks("m 2 kg, Cf 0.3 N, omega_co [rad/s], phase 30 deg, [m/A]", ROTARY) == []


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """A rotary log in encoder counts (2^20 a revolution, current in A) and a linear one (m, A), as CSV."""
    folder = tmp_path_factory.mktemp("axes")
    rot_spec = dict(AXES["rotary-4k-hold-d2"], duration=4.0)
    rot = noisy_log(rot_spec, simulate_axis(rot_spec), 1)
    counts = np.round(rot["x"] / rot_spec["step"]).astype(np.int64)
    with open(folder / "rotary.csv", "w") as f:
        f.write("t,x,i\n" + "".join(f"{float(t)!r},{int(c)},{float(i)!r}\n" for t, c, i in zip(rot["t"], counts, rot["i"])))
    np.savetxt(folder / "rotary_rad.csv", np.column_stack([rot["t"], counts * (2 * math.pi / 2**20), rot["i"]]),
               delimiter=",", header="t,x,i", comments="", fmt="%.17g")
    lin_spec = dict(AXES["linear-1k-hold-d0"], duration=8.0)
    lin = noisy_log(lin_spec, simulate_axis(lin_spec), 1)
    np.savetxt(folder / "linear.csv", np.column_stack([lin["t"], lin["x"], lin["i"]]), delimiter=",",
               header="t,x,i", comments="", fmt="%.17g")
    return folder


def _run(capsys, *argv):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


FLAGS = {"rotary": ("rotary.csv", ["--counts-per-rev", 2**20, "--input-unit", "A", "--input-gain", 0.1]),
         "linear": ("linear.csv", ["--position-unit", "m", "--input-unit", "A", "--input-gain", 6.5])}
#: What each axis's config must say (units and words).
WANTED = {"rotary": ("[kg m^2] inertia", "[N m/A] actuator torque constant", "[A] actuator current limit",
                     "[N m s/rad]", "[rad/s]", "[N m] Coulomb"),
          "linear": ("[kg] moving mass", "[N/A] actuator force constant", "[A] actuator current limit",
                     "[N s/m]", "[m/s]", "[N] Coulomb")}


@pytest.mark.parametrize("kind", ["rotary", "linear"])
def test_identify_and_observe_speak_the_axis(kind, logs, tmp_path, capsys):
    """identify (text, warnings, JSON, -o config) and observe (text, CSV) in the axis's units only."""
    name, flags = FLAGS[kind]
    wrong = LINEAR if kind == "rotary" else ROTARY
    data = ["identify", logs / name, "--time", "t", "--position", "x", "--input", "i", *flags, "--bootstrap", 0,
            "--stribeck", "on", "--fix", "offset=0"]
    status, out, err = _run(capsys, *data, "-o", tmp_path / "c.toml")
    assert status == 0, err
    config = (tmp_path / "c.toml").read_text()
    status, out_json, _ = _run(capsys, *data, "--json")
    assert status == 0
    payload = json.loads(out_json)
    for where, text in (("text", out), ("warnings", err), ("config", config), ("json", out_json)):
        assert leaks(text, wrong) == [], (where, leaks(text, wrong))
    for wanted in WANTED[kind]:
        assert wanted in config, wanted
    rotary = kind == "rotary"
    assert payload["units"]["mass_unit"] == ("kg m^2" if rotary else "kg")
    assert payload["config"]["friction.sigma"]["unit"] == ("N m s/rad" if rotary else "N s/m")
    assert (" kg m^2  " if rotary else " kg  ") in out and ("N m s/rad" if rotary else "N s/m") in out
    assert tomllib.loads(config)["axis"] == {"kind": kind, "input": "A"}
    # observe with that config, its text and CSV
    cfg_path = tmp_path / "c.toml"
    status, obs_out, obs_err = _run(capsys, "observe", logs / name, "--config", cfg_path, "--time", "t",
                                    "--position", "x", "--input", "i", *flags, "--out", tmp_path / "o.csv")
    assert status == 0, obs_err
    for where, text in (("observe", obs_out + obs_err), ("csv", (tmp_path / "o.csv").read_text()[:200])):
        assert leaks(text, wrong) == [], (where, leaks(text, wrong))
    assert ("[N m]" if rotary else "[N]") in obs_out and ("[rad/s]" if rotary else "[m/s]") in obs_out


def test_counts_per_rev_is_a_resolution_of_2pi_over_n(logs, capsys):
    """The same log in counts with --counts-per-rev and in rad: the same identification (to rounding of the
    written rad values, 1e-16 relative)."""
    common = ["--time", "t", "--position", "x", "--input", "i", "--input-unit", "A", "--input-gain", 0.1,
              "--bootstrap", 0, "--json", "--input-timing", "hold", "--delay-samples", 2]
    status, counts, err = _run(capsys, "identify", logs / "rotary.csv", "--counts-per-rev", 2**20, *common)
    assert status == 0, err
    status, rad, err = _run(capsys, "identify", logs / "rotary_rad.csv", "--position-unit", "rad", *common)
    assert status == 0, err
    a, b = json.loads(counts), json.loads(rad)
    assert a["units"]["position"] == "counts" and b["units"]["position"] == "rad"
    for key in ("m", "sigma", "Cf", "offset"):
        assert a[key] == pytest.approx(b[key], rel=1e-9), key
    assert a["config"]["sensor.quantization"]["value"] == pytest.approx(2 * math.pi / 2**20, rel=1e-9)


@pytest.mark.parametrize("extra, match", [
    (["--counts-per-rev", "0"], "argument --counts-per-rev: expected an integer >= 1 and <= 1099511627776, found '0'"),
    (["--counts-per-rev", "-4096"], "argument --counts-per-rev: expected an integer >= 1"),
    (["--counts-per-rev", "1.5"], "found '1.5'"),
    (["--counts-per-rev", str(2**41)], f"found '{2**41}'"),
    (["--counts-per-rev", "4096", "--resolution", "1e-3"], "not allowed with argument"),
    (["--counts-per-rev", "4096", "--position-unit", "mm"], "argument --counts-per-rev: expected a position in counts"),
])
@pytest.mark.parametrize("command", ["identify", "observe"])
def test_counts_per_rev_bad_input(command, extra, match, logs, capsys):
    argv = [command, logs / "rotary.csv", "--time", "t", "--position", "x", "--input", "i", *extra]
    if command == "observe":
        argv += ["--preset", "vcm"]
    status, _, err = _run(capsys, *argv)
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1 and match in lines[0], lines


def test_experiment_counts_per_rev_bad_input(capsys):
    base = ["experiment", "--stroke", 60, "--speed", 20, "--force", 1, "--mass", 2.5e-3, "--dt", 2.5e-4]
    for extra, match in ((["--counts-per-rev", 0], "found '0'"),
                         (["--counts-per-rev", 100], "expected more than 2 pi / travel = 6283.19 counts"),
                         (["--counts-per-rev", 4096, "--resolution", 1e-6], "not allowed with argument"),
                         (["--stribeck-speed", 2, 1], "argument --stribeck-speed: expected (lo, hi) with 0 < lo <= hi")):
        status, _, err = _run(capsys, *base, *extra)
        lines = err.strip().splitlines()
        assert status == 2 and len(lines) == 1 and match in lines[0] and "--" in lines[0], lines


def test_input_in_ampere_without_its_gain_says_so(logs, tmp_path, capsys):
    """Without --input-gain the numbers are per N m/A of the unknown torque constant: exactly the physical values
    divided by it (the fit is linear in the force), a warning says so, and the config's K and m say it too."""
    common = [logs / "rotary_rad.csv", "--time", "t", "--position", "x", "--input", "i", "--position-unit", "rad",
              "--input-unit", "A", "--bootstrap", 0, "--json", "--input-timing", "hold", "--delay-samples", 2]
    status, out, err = _run(capsys, "identify", *common, "-o", tmp_path / "per_amp.toml")
    assert status == 0
    per_amp = json.loads(out)
    note = [line for line in err.splitlines() if "input gain 1 N m/A" in line]
    assert len(note) == 1 and "m/K, sigma/K, Cf/K and offset/K" in note[0] and "--input-gain K" in note[0]
    status, out, err = _run(capsys, "identify", *common, "--input-gain", 0.1)
    physical = json.loads(out)
    assert "input gain 1" not in err
    for key in ("m", "sigma", "Cf", "offset"):
        assert per_amp[key] == pytest.approx(physical[key] / 0.1, rel=1e-9), key
    sources = tomllib.loads((tmp_path / "per_amp.toml").read_text())["sources"]
    assert sources["plant.K"].startswith("NOT measured") and "not physical" in sources["plant.m"]


def test_config_words_follow_the_input_unit():
    """The config's sentences for each axis kind and command unit (AxisSpec.words, one table)."""
    import obsdesign as od

    cfg = od.load_preset("vcm")
    for axis, wanted, unwanted in (
            (AxisSpec(kind="rotary", input="A"), ("[kg m^2] inertia", "[N m/A] actuator torque constant",
                                                   "[A] actuator current limit", "[N m] known load torque"),
             ("mass", "force", "voltage")),
            (AxisSpec(kind="rotary", input="V"), ("[N m/V] actuator torque constant", "[V] actuator voltage limit"),
             ("mass", "force", "current")),
            (AxisSpec(kind="linear", input="A"), ("[kg] moving mass", "[N/A] actuator force constant",
                                                   "[A] actuator current limit"), ("inertia", "torque", "voltage")),
            (AxisSpec(kind="linear", input="N"), ("[N] actuator force limit",), ("voltage", "torque"))):
        text = _with_axis(cfg, axis).to_toml()
        body = text.split("[sources]")[0]
        for w in wanted:
            assert w in body, (axis, w)
        for w in unwanted:
            assert re.search(rf"\b{w}\b", body) is None, (axis, w, re.search(rf".{{40}}\b{w}\b.{{20}}", body))


def _strings(value) -> list[str]:
    """Every string value of a JSON-like object (not its keys)."""
    if isinstance(value, dict):
        return [s for v in value.values() for s in _strings(v)]
    if isinstance(value, (list, tuple)):
        return [s for v in value for s in _strings(v)]
    return [value] if isinstance(value, str) else []


def _with_axis(cfg, axis):
    import dataclasses

    return dataclasses.replace(cfg, axis=axis, sources={})


def test_rotary_experiment_covers_the_stribeck_range():
    """The staircase runs from a third of lo to three times hi with levels at most 1.6 apart, in rad/s."""
    from obsdesign.data import design_experiment

    exp = design_experiment(stroke=60.0, speed=20.0, force=1.0, mass=2.5e-3, dt=2.5e-4, travel=1e-3, rotary=True,
                            stribeck_speed=(0.2, 1.0), resolution=2 * math.pi / 2**20)
    levels = np.array(exp.levels)
    assert levels.min() <= 0.2 / 3 * (1 + 1e-12) and levels.max() >= 3.0
    inside = levels[(levels >= 0.2 / 3 * (1 - 1e-12)) & (levels <= 3.0 * (1 + 1e-12))]
    assert np.all(inside[1:] / inside[:-1] <= 1.6 + 1e-12) and inside.size >= 8
    assert np.all(np.diff(levels) > 0)
    for v in levels:  # each level run in both directions
        assert np.any(np.abs(exp.v_ref - v) < 1e-12) and np.any(np.abs(exp.v_ref + v) < 1e-12)
    assert exp.expected["Fs"]["identifiable"] and exp.expected["vs"]["identifiable"]
    assert not exp.expected["timing"]["identifiable"]
    text, payload = str(exp), json.dumps(_strings(exp.to_dict()))  # the JSON's values (its keys are API names)
    assert leaks(text, LINEAR) == [] and leaks(payload, LINEAR) == [], leaks(text, LINEAR)
    assert "[rad/s]" in text and "rad/s^2" in text and exp.to_dict()["units"] == {
        "length": "rad", "speed": "rad/s", "acceleration": "rad/s^2", "force": "N m", "mass": "kg m^2"}
    # without a Stribeck range no claim on Fs, vs; a range the encoder cannot reach is refused as a claim
    assert "vs" not in design_experiment(stroke=60.0, speed=20.0, force=1.0, mass=2.5e-3, dt=2.5e-4,
                                         rotary=True).expected
    slow = design_experiment(stroke=60.0, speed=20.0, force=1.0, mass=2.5e-3, dt=2.5e-4, rotary=True, travel=0.05,
                             stribeck_speed=(0.01, 0.02))
    assert min(slow.levels) == pytest.approx(0.03) and not slow.expected["vs"]["identifiable"]
    linear = design_experiment(stroke=0.04, speed=0.05, force=32.8, mass=0.538, dt=1e-4, travel=1e-3)
    assert leaks(str(linear), ROTARY) == [] and "[m/s]" in str(linear)


@pytest.mark.slow
def test_rotary_experiment_identifies_what_it_claims():
    """The plan run on a simulated rotary LuGre axis with a Stribeck drop (4 kHz, held current, position one
    sample late, 2^20 counts a revolution), identified as the plan says (the staircase window, --stribeck on,
    its min speed, the drive's timing): every parameter it calls identifiable within its interval; Fs and vs
    (for which identify gives no interval) within 1 %."""
    from obsdesign.data import design_experiment, identify

    spec = AXES["rotary-4k-hold-d1-stribeck"]  # vs = 0.5 rad/s, Fs 0.08, Cf 0.05 N m
    exp = design_experiment(stroke=60.0, speed=20.0, force=0.5 * spec["i_max"] * spec["gain"], mass=spec["m"],
                            dt=1.0 / spec["rate"], travel=1e-3, resolution=spec["step"], rotary=True,
                            stribeck_speed=(0.25, 1.0), blocks=1)
    clean = simulate_axis(spec, (exp.x_ref, exp.v_ref, np.gradient(exp.v_ref, exp.dt)))
    claimed = [k for k, v in exp.expected.items() if v["identifiable"]]
    assert {"m", "sigma", "Cf", "offset", "Fs", "vs"} <= set(claimed)
    for seed in (3, 4):
        trace = axis_trace(spec, noisy_log(spec, clean, seed))
        ident = identify(trace, window=(0.0, exp.staircase_end * exp.dt), stribeck="on",
                         min_speed=0.5 * min(exp.levels), input_timing="hold", delay_samples=1)
        for name in ("m", "sigma", "Cf", "offset"):
            low, high = ident.intervals[name]
            assert low <= spec[name] <= high, (seed, name, getattr(ident, name), (low, high))
        assert ident.Fs == pytest.approx(spec["Fs"], rel=0.01) and ident.vs == pytest.approx(spec["vs"], rel=0.01)


@pytest.mark.slow
def test_report_data_section_speaks_the_axis(logs, tmp_path, capsys):
    """The report's 'Validation on measured data' on a rotary log with its identified config: rotary units only
    (its text, table and figures' labels and legends)."""
    import html

    flags = ["--time", "t", "--position", "x", "--input", "i", "--counts-per-rev", 2**20, "--input-unit", "A",
             "--input-gain", 0.1]
    status, _, err = _run(capsys, "identify", logs / "rotary.csv", *flags, "--bootstrap", 0, "-o", tmp_path / "c.toml")
    assert status == 0, err
    status, _, err = _run(capsys, "report", "--config", tmp_path / "c.toml", "--data", logs / "rotary.csv", *flags,
                          "-o", tmp_path / "r.html", "--quiet")
    assert status == 0, err
    page = (tmp_path / "r.html").read_text()
    start = page.index("Validation on measured data")
    section = page[start:page.index("</figure>", page.index("<figure>", page.index("observer of", start)))]
    text = html.unescape(re.sub(r"<[^>]+>", " ", section))
    assert leaks(text, LINEAR) == [], leaks(text, LINEAR)
    for wanted in ("kg m^2", "N m s/rad", "torque [N m]", "friction [N m]", "velocity [mrad/s]"):
        assert wanted in text, wanted


@pytest.mark.slow
def test_refine_speaks_the_axis():
    """The output-error refinement of a rotary log: its parameters, RMS error and note in kg m^2, N m, rad."""
    from obsdesign.data import identify
    from obsdesign.data.output_error import refine

    spec = dict(AXES["rotary-4k-hold-d2"], duration=4.0)
    trace = axis_trace(spec, noisy_log(spec, simulate_axis(spec), 1))
    ident = identify(trace, n_boot=0)
    result = refine(trace, ident, parameters=("s", "m", "offset"))
    text, payload = str(result), json.dumps(_strings(result.to_dict()))
    assert leaks(text, LINEAR) == [] and leaks(payload, LINEAR) == [], (leaks(text, LINEAR), leaks(payload, LINEAR))
    assert [result[k].unit for k in ("s", "m", "offset")] == ["1/rad", "kg m^2", "N m"]
    assert "rad; condition number" in text
