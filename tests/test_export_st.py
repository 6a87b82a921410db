"""The controller as IEC 61131-3 Structured Text: blark parses it; a small ST evaluator runs it.

``tests/st_eval.py`` evaluates the subset the generator emits on blark's parse tree; driven with the
simulator's recorded x_ref and x_meas, the function block's command must match the Python export
within 1e-12 relative (and ``K * command - G`` the simulator's ``u``). blark's Earley parser takes
some 20 s for a whole block, so the runs of the block are slow tests; the helper functions are
parsed and checked against the package's friction routines in the fast run.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import obsdesign as od
from obsdesign.export import export
from obsdesign.export.controller import controller_files
from obsdesign.export.st import FB_NAME, OBSERVER_FB_NAME, ST_KEYWORDS, check_st_identifier, st_files, st_literal
from obsdesign.friction.presliding import coulomb_normalized, stiffness

blark = pytest.importorskip("blark", reason="blark (the test extra) is not installed")
from st_eval import Program, plcopen_source  # noqa: E402

VCM = od.load_preset("vcm")
TABLE1 = od.load_preset("table1")
ST, XML = "obsdesign_controller.st", "obsdesign_controller.xml"


def _python_commands(files, rows, tmp_path):
    path = tmp_path / "obsdesign_controller.py"
    path.write_text(files["obsdesign_controller.py"])
    spec = importlib.util.spec_from_file_location(f"st_reference_{id(files)}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    ctrl = mod.Controller()
    return np.array([ctrl.step(*map(float, row)) for row in rows])


CASES = {
    "vcm-tracking": (VCM, dict(scenario="tracking")),
    # the lag variant in its model plant: table1's compensated loop runs away in the physical lag plant
    "noisy-lag-hysteresis-knobs": (TABLE1.override(noise_rms=2e-7, gain=0.7, viscous=True, deadzone=1e-4),
                                   dict(scenario="tracking", plant="model")),
    "saturated-constant": (VCM.override(u_max=1.8), dict(scenario=od.sim.Positioning(step_up=0.1, step_down=0.4),
                                                         stiffness="constant")),
    "paper-k0": (VCM, dict(scenario="tracking", estimator="paper-k0")),
    "pid": (VCM, dict(scenario="tracking", controller="pid")),
    "dob": (VCM.override(noise_rms=1e-6), dict(scenario="tracking", estimator="dob")),
    "blend-lag": (TABLE1.override(mode="blend", lookahead=10, noise_rms=2e-7), dict(scenario="tracking", plant="model")),
    "feedforward": (VCM.override(mode="feedforward", ff_stribeck=0.1, ff_stribeck_velocity=2e-3, ff_offset=0.02,
                                 lookahead=20, buildup=2e-5), dict(scenario="tracking")),
    # the drive's delay: the block's command is not delayed, its estimator is fed the command of d calls earlier
    "delayed": (VCM.override(delay_samples=2), dict(scenario="tracking")),
}


#: The cases whose PLCopen XML also runs (rebuilt from the XML alone; blark parses a block in ~15 s).
XML_CASES = {"feedforward"}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_the_function_block_matches_the_python_export_and_the_simulator(name, tmp_path):
    cfg, kw = CASES[name][0], dict(CASES[name][1])
    scenario = kw.pop("scenario")
    kw.setdefault("controller", "pid+observer")
    loop = od.loop.prepare(cfg, scenario, duration=0.6, **kw)
    res = od.sim.run(loop)
    assert not res.metrics["diverged"]
    extra = loop.reference_feedforward() if cfg.compensation.mode != "observer" else ()
    rows = np.column_stack([res.x_ref, res.x_meas, *extra])
    choices = dict(controller=kw["controller"], schedule=res.stiffness_schedule, estimator=res.estimator)
    files = st_files(cfg, **choices)
    block = Program(files[ST]).block(FB_NAME)
    command = np.array([block(*map(float, row))["COMMAND"] for row in rows])
    if name in XML_CASES:  # the PLCopen XML a runtime imports: the same block, the same numbers
        imported = Program(plcopen_source(files[XML])).block(FB_NAME)
        assert np.array_equal([imported(*map(float, row))["COMMAND"] for row in rows], command)
    reference = _python_commands(controller_files(cfg, "python", **choices), rows, tmp_path)
    assert np.max(np.abs(command - reference)) <= 1e-12 * np.max(np.abs(reference))
    d = cfg.hardware.delay_samples  # the simulated drive applies the command of sample n from n + d
    u = cfg.plant.K * command[:len(command) - d] - cfg.plant.G
    assert np.max(np.abs(u - res.u[d:])) <= 1e-12 * np.max(np.abs(res.u))


def _functions_only(text: str) -> str:
    return text[:text.index("\nFUNCTION_BLOCK")] + "\n"


def test_the_helper_functions_parse_and_equal_the_friction_routines():
    program = Program(_functions_only(st_files(VCM)[ST]))
    rng = np.random.default_rng(3)
    s, cf, kappa = VCM.friction.s, VCM.friction.Cf, VCM.friction.kappa
    for _ in range(300):
        direction = float(rng.choice([-1.0, 0.0, 1.0]))
        xr, fr = float(rng.normal(0, 1e-5)), float(rng.uniform(-1, 1))
        x = xr + float(rng.choice([0.0, 1.0])) * float(rng.normal(0, 2.0 / s))
        args = (x, direction, xr, fr)
        assert program.call_function("OD_CoulombN", [*args, s]) == coulomb_normalized(*args, s)
        assert program.call_function("OD_Stiffness", [*args, cf, s, kappa]) == stiffness(*args, cf, s, kappa)


@pytest.mark.slow
def test_the_block_parses_with_blark_declared_as_the_export_says():
    result = blark.parse_source_code(st_files(VCM.override(mode="feedforward"))[ST])
    assert result.exception is None
    items = result.transform().items
    (block,) = [i for i in items if type(i).__name__ == "FunctionBlock"]
    assert str(block.name) == FB_NAME
    declared = {type(d).__name__: [str(v.variable.name) for item in d.items for v in item.variables]
                for d in block.declarations if type(d).__name__ in ("InputDeclarations", "OutputDeclarations")}
    assert declared == {"InputDeclarations": ["x_ref", "x_meas", "v_ref", "w_ff"],
                        "OutputDeclarations": ["command", "v_hat", "f_hat", "f_hat_filtered"]}


def test_the_plcopen_xml_carries_the_same_pous():
    files = st_files(VCM)
    root = ET.fromstring(files[XML].encode())
    ns = {"p": "http://www.plcopen.org/xml/tc6_0201", "x": "http://www.w3.org/1999/xhtml"}
    pous = root.findall(".//p:pou", ns)
    assert [p.get("name") for p in pous] == ["OD_Shape", "OD_CoulombN", "OD_Stiffness", FB_NAME]
    st = files[ST]
    for pou in pous:
        body = pou.find("p:body/p:ST/x:p", ns).text
        statements = body.split("*)\n")[-1] if pou.get("pouType") == "functionBlock" else body
        assert statements in st
    fb = pous[-1]
    inputs = [v.get("name") for v in fb.findall("p:interface/p:inputVars/p:variable", ns)]
    assert inputs == ["x_ref", "x_meas"]
    constants = {v.get("name"): v.find("p:initialValue/p:simpleValue", ns).get("value")
                 for v in fb.findall("p:interface/p:localVars[@constant='true']/p:variable", ns)}
    assert float(constants["OD_DT"]) == VCM.observer.dt
    phi = [v for v in fb.findall("p:interface/p:localVars/p:variable", ns) if v.get("name") == "phi"][0]
    assert phi.find("p:type/p:array/p:dimension", ns).attrib == {"lower": "0", "upper": "3"}


def test_same_inputs_give_the_same_text_without_paths_or_times():
    a, b = st_files(TABLE1), st_files(TABLE1)
    assert a == b
    for text in a.values():
        assert not re.search(r"/(tmp|home|root|work)/|\d{4}-\d\d-\d\dT(?!00:00:00)", text)
    assert "ubuf" not in a[ST] and "DRIVE_" not in a[ST] and "ring_i" not in a[ST]  # no drive delay, no ring


HOSTILE = ["*) END_FUNCTION_BLOCK (*", "]]></x:p><evil/>", "a\nb\u2028c // (* x *)", "IF"]


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_names_reach_comments_only(name):
    files = st_files(dataclasses.replace(VCM, name=name))
    clean = st_files(VCM)
    strip = re.compile(r"\(\* Config .*? \*\)")
    assert strip.sub("", files[ST]) == strip.sub("", clean[ST])  # only the config line differs
    ET.fromstring(files[XML].encode())  # still well-formed
    assert files[ST].count("(*") == files[ST].count("*)")


def test_every_generated_identifier_is_checked():
    text = st_files(TABLE1.override(mode="blend"))[ST]
    declared = re.findall(r"^\s+(\w+) : ", text, flags=re.M)
    assert len(declared) > 50
    for name in declared:
        assert check_st_identifier(name) == name
    block = text[text.index("FUNCTION_BLOCK"):]
    in_block = re.findall(r"^\s+(\w+) : ", block, flags=re.M)
    assert len({n.upper() for n in in_block}) == len(in_block)  # ST does not tell K from k


def test_a_clash_of_names_is_refused(monkeypatch):
    from obsdesign.export import st

    original = st._lreal
    monkeypatch.setattr(st, "_lreal", lambda *names, comment="": original(*("Y1" if n == "y2" else n for n in names),
                                                                            comment=comment))
    with pytest.raises(ValueError, match="identifier: 'Y1' clashes with 'y1'"):
        st_files(VCM)


@pytest.mark.parametrize("name, match", [
    ("elsif", "is an IEC 61131-3 keyword"), ("Lreal", "is an IEC 61131-3 keyword"), ("DT", "keyword"),
    ("a__b", "single inner underscores"), ("x_", "single inner underscores"), ("1x", "letters, digits"),
    ("sqrt", "standard function"),
])
def test_keywords_and_bad_identifiers_are_refused(name, match):
    with pytest.raises(ValueError, match=f"identifier: .*{match}"):
        check_st_identifier(name)
    assert "END_FUNCTION_BLOCK" in ST_KEYWORDS


@pytest.mark.parametrize("value", [0.0, -0.0, 1e-6, -1e-300, 5e-324, 1.7976931348623157e308, 428.9749, 2.0, 1e16])
def test_st_literals_read_back_exactly(value):
    text = st_literal(value)
    assert re.fullmatch(r"-?\d+\.\d+(E[+-]\d+)?", text)
    assert float(text) == value and math.copysign(1, float(text)) == math.copysign(1, value)


def test_st_export_errors_and_files(tmp_path):
    # the drive's delay is not the block's: its command is not delayed, only its estimator's input (a ring of d)
    delayed = st_files(VCM.override(delay_samples=2), what="controller")[ST]
    assert "ring : ARRAY[0..1] OF LREAL" in delayed and "command := total;" in delayed
    with pytest.raises(ValueError, match="waits: .* expected delay_samples >= 1, found 0"):
        st_files(VCM, waits=True)
    with pytest.raises(ValueError, match="waits: applies to what='controller' only"):
        st_files(VCM, what="observer", waits=True)
    with pytest.raises(ValueError, match="schedule: applies to what='controller' only"):
        st_files(VCM, what="observer", schedule="constant")
    paths = export(VCM, "st", tmp_path, what="controller")
    assert sorted(p.name for p in paths) == [ST, XML]
    paths = export(VCM.override(delay_samples=2), "st", tmp_path)
    assert sorted(p.name for p in paths) == ["obsdesign_observer.st", "obsdesign_observer.xml"]


@pytest.mark.slow
@pytest.mark.parametrize("cfg", [VCM, TABLE1.override(noise_rms=2e-7)], ids=["vcm", "table1-noisy"])
def test_the_observer_block_matches_the_python_observer_and_the_simulator(cfg, tmp_path):
    from test_export_fmu import _observer_reference

    res = od.simulate(cfg, "tracking", duration=0.4)  # the default schedule, as the observer export
    u_prev = np.concatenate([[0.0], res.u[:-1]])
    block = Program(st_files(cfg, what="observer")["obsdesign_observer.st"]).block(OBSERVER_FB_NAME)
    out = [block(float(u), float(x)) for u, x in zip(u_prev, res.x_meas)]
    est = np.array([(o["V_HAT"], o["F_HAT"]) for o in out])
    reference = _observer_reference(cfg, u_prev, res.x_meas, tmp_path)
    assert np.all(np.max(np.abs(est - reference), axis=0) <= 1e-12 * np.max(np.abs(reference), axis=0))
    assert np.max(np.abs(est[:, 1] - res.f_hat)) <= 1e-12 * np.max(np.abs(res.f_hat))
