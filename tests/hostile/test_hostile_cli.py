"""The reliability review's hostile cases of 2026-12-04, one table per command: each argument list with its
exit status and the text its one line must hold (issue 36). Every case runs under a deadline
(``conftest.DEADLINE``): a hang fails.

Each case failed on the code before issue 36 (commit 5089376), as the review found: ``--bootstrap 1e9``
ran on, ``delay_samples = 1e9`` was accepted (the C export then asked for 8 GB), a 5 MB CSV field ended in
exit 3, and the rest exited 0 silently. ``--fix`` against ``--bounds`` was already refused (kept here).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

import obsdesign as od

PRESET = Path(od.__file__).parent / "presets" / "vcm.toml"


def _log(path: Path, *, dt: float = 5e-4, duration: float = 4.0) -> Path:
    """A synthetic axis log ``t,x,u``: m = 1.5 kg, sigma = 10 N s/m, Cf = 2 N, offset 0.2 N (peak |u| 2.9 N)."""
    rng = np.random.default_rng(0)
    t = np.arange(int(round(duration / dt))) * dt
    w, a, ph = 2 * np.pi * np.array([0.3, 0.8, 1.9]), np.array([0.01, 0.004, 0.001]), rng.uniform(0, 6, 3)
    x = (a[:, None] * np.sin(w[:, None] * t + ph[:, None])).sum(0)
    v = (a[:, None] * w[:, None] * np.cos(w[:, None] * t + ph[:, None])).sum(0)
    acc = -(a[:, None] * w[:, None] ** 2 * np.sin(w[:, None] * t + ph[:, None])).sum(0)
    u = 1.5 * acc + 10 * v + 2.0 * np.sign(v) + 0.2 + rng.normal(0, 0.01, t.size)
    np.savetxt(path, np.c_[t, x + rng.normal(0, 1e-7, t.size), u], delimiter=",", header="t,x,u", comments="")
    return path


def _config(path: Path, section: str, line: str) -> Path:
    text = PRESET.read_text()
    if f"[{section}]" in text:
        text = text.replace(f"[{section}]\n", f"[{section}]\n{line}\n", 1)
    else:
        text = text.replace("[sources]", f"[{section}]\n{line}\n\n[sources]", 1)
    path.write_text(text)
    return path


@pytest.fixture
def files(tmp_path):
    f = {"log": _log(tmp_path / "log.csv"), "rotary": tmp_path / "rotary.csv", "field": tmp_path / "field.csv"}
    t = np.arange(2000) * 1e-4  # the vcm preset's rate
    np.savetxt(f["rotary"], np.c_[t, 0.1 * np.sin(20 * t), np.cos(20 * t)], delimiter=",", header="t,x,u",
               comments="")
    f["field"].write_text("t,x,u\n0," + "1" * 5_000_000 + ",0\n")
    f["delay"] = _config(tmp_path / "delay.toml", "hardware", "delay_samples = 1000000000")
    f["derivative"] = _config(tmp_path / "derivative.toml", "pid", "derivative_N = 1e300")
    f["deadzone"] = _config(tmp_path / "deadzone.toml", "compensation", "deadzone = 1e300")
    f["offset"] = _config(tmp_path / "offset.toml", "compensation", "ff_offset = -1e300")
    f["velocity"] = _config(tmp_path / "velocity.toml", "compensation", "ff_stribeck_velocity = 1e-300")
    f["out"] = tmp_path / "out"
    return f


IDENT = ("identify", "{log}", "--position", "x", "--input", "u", "--time", "t")
EXPERIMENT = ("experiment", "--stroke", "0.05", "--speed", "0.1", "--force", "5", "--mass", "0.5", "--dt", "1e-3",
              "--c", "{out}.c")

CASES = [
    # identify
    ("bootstrap-huge", (*IDENT, "--bootstrap", "1000000000"), 2, "--bootstrap: expected an integer >= 0 and <= 100000"),
    ("field-5MB", ("identify", "{field}", "--position", "x", "--input", "u", "--time", "t"), 2,
     "at most 100000 characters"),
    ("fix-twice", (*IDENT, "--fix", "m=1", "--fix", "m=2"), 2, "--fix: expected each parameter once"),
    ("bounds-twice", (*IDENT, "--bounds", "m=1:2", "--bounds", "m=0.5:3"), 2, "--bounds: expected each parameter"),
    ("fix-against-bounds", (*IDENT, "--bootstrap", "0", "--fix", "sigma=5", "--bounds", "sigma=1:2"), 2,
     "either fixed or bounded"),
    ("u-max-below-peak", (*IDENT, "--bootstrap", "0", "--u-max", "1"), 2, "--u-max: expected at least the log's peak"),
    # observe
    ("rotary-log-linear-config", ("observe", "{rotary}", "--preset", "vcm", "--position", "x", "--input", "u", "--time",
                                  "t", "--position-unit", "rad"), 2, "expected a rotary axis"),
    # export
    ("delay-1e9", ("export", "--format", "c", "--what", "controller", "--config", "{delay}", "-o", "{out}"), 2,
     "hardware.delay_samples: expected an integer >= 0 and <= 10000"),
    ("derivative-N", ("export", "--format", "c", "--what", "controller", "--config", "{derivative}", "-o", "{out}"), 2,
     "pid.derivative_N: expected"),
    ("deadzone", ("export", "--format", "c", "--what", "controller", "--config", "{deadzone}", "-o", "{out}"), 2,
     "compensation.deadzone: expected"),
    ("ff-offset", ("export", "--format", "python", "--what", "controller", "--config", "{offset}", "-o", "{out}"), 2,
     "compensation.ff_offset: expected"),
    ("ff-stribeck-velocity", ("export", "--format", "js", "--what", "controller", "--config", "{velocity}", "-o",
                              "{out}"), 2, "compensation.ff_stribeck_velocity: expected"),
    ("motor-constant-tiny", ("export", "--format", "c", "--what", "friction-table", "--motor-constant", "1e-300", "-o",
                             "{out}"), 2, "--motor-constant: expected"),
    ("v-max-huge", ("export", "--format", "c", "--what", "friction-table", "--v-max", "1e300", "-o", "{out}"), 2,
     "--v-max: expected"),
    ("points-huge", ("export", "--format", "c", "--what", "friction-table", "--points", "100000000", "-o", "{out}"), 2,
     "--points: expected an integer >= 2 and <= 1000"),
    # experiment
    ("name-int", (*EXPERIMENT, "--name", "int"), 2, "--name: expected an identifier that is no keyword"),
    ("name-python", (*EXPERIMENT, "--name", "lambda"), 2, "a keyword of Python"),
    ("name-octave", (*EXPERIMENT, "--name", "endfunction"), 2, "a keyword of Octave/MATLAB"),
    ("name-js", (*EXPERIMENT, "--name", "debugger"), 2, "a keyword of JavaScript"),
    ("name-reserved", (*EXPERIMENT, "--name", "__x"), 2, "reserved"),
    # simulate
    ("circle-modes-empty", ("simulate", "circle", "--modes", ""), 2, "--modes: expected a comma list"),
    ("circle-modes-commas", ("simulate", "circle", "--modes", " , ,"), 2, "--modes: expected a comma list"),
    ("circle-out", ("simulate", "circle", "--out", "{out}.csv"), 2, "--out: not with circle"),
    ("circle-revolutions", ("simulate", "circle", "--revolutions", "1000000000"), 2,
     "--revolutions: expected an integer >= 1 and <= 1000"),
    # loop, tune
    ("loop-delay", ("loop", "--delay", "1000000000"), 2, "--delay: expected an integer >= 0 and <= 10000"),
    ("tune-delay", ("tune", "--delay-samples", "1000000000"), 2, "--delay-samples: expected an integer >= 0 and <= 10000"),
    # sweep
    ("sweep-all-fail", ("sweep", "--scenario", "positioning", "--vary", "deadzone=-2:-1:2", "--workers", "1",
                        "--out", "{out}"), 2, "all 2 runs failed; the first (run 0): ValueError"),
]


@pytest.mark.parametrize("name, argv, status, match", CASES, ids=[c[0] for c in CASES])
def test_a_hostile_case_ends_in_one_line(name, argv, status, match, files, cli):
    argv = [a.format(**files) for a in argv]
    code, out, err = cli(*argv)
    err = [line for line in err if not re.fullmatch(r"sweep: \d+/\d+ runs, [0-9.]+ s", line)]  # progress
    assert code == status, (code, err)
    assert len(err) == 1 and match in err[0] and "Traceback" not in err[0], err
    written = sorted(p.name for p in Path(files["out"]).parent.iterdir())
    assert not any(n.startswith("out") for n in written) or name == "sweep-all-fail", written  # nothing half-written


def test_a_sweep_with_a_failed_run_still_exits_0(files, cli):
    """Only a sweep whose every run fails is an error: one failed run of two is a row that says so."""
    code, out, err = cli("sweep", "--scenario", "positioning", "--vary", "deadzone=-1:0:2", "--workers", "1",
                         "--out", files["out"])
    assert code == 0, err
    rows = (files["out"] / "results.csv").read_text().splitlines()
    assert sum(",failed," in r for r in rows) == 1 and sum(",ok," in r for r in rows) == 1


def test_the_api_refuses_the_same_values():
    from obsdesign.data.experiment import design_experiment
    from obsdesign.export.friction_table import friction_table

    cfg = od.load_preset("vcm")
    for override, match in ((dict(delay_samples=10**9), "delay_samples"), (dict(derivative_N=1e300), "derivative_N"),
                            (dict(derivative_N=1e-300), "derivative_N"), (dict(buildup=1e300), "buildup"),
                            (dict(ff_stribeck=1e300), "ff_stribeck")):
        with pytest.raises(ValueError, match=match):
            cfg.override(**override)
    with pytest.raises(ValueError, match="motor_constant"):
        friction_table(cfg, motor_constant=1e-300)
    with pytest.raises(ValueError, match="v_max"):
        friction_table(cfg, v_max=1e300)
    exp = design_experiment(stroke=0.05, speed=0.1, force=5.0, mass=0.5, dt=1e-3, blocks=1)
    for word in ("int", "while", "None", "function", "end", "class", "_Bool", "__reserved"):
        with pytest.raises(ValueError, match="name: expected"):
            exp.c_source(word)
    assert "const double axis_x[" in exp.c_source("axis_x")


def test_identify_api_refuses_a_huge_bootstrap(files, within):
    from obsdesign.data import identify, load_trace

    trace = load_trace(files["log"], position="x", input="u", time="t")
    with within(60), pytest.raises(ValueError, match="n_boot: expected an integer >= 0 and <= 100000"):
        identify(trace, n_boot=10**9)


def test_the_keyword_lists_hold_every_keyword_of_the_running_python():
    """An independent source for one list: the interpreter's own ``keyword`` module."""
    import keyword

    from obsdesign.export.literals import KEYWORDS

    assert set(keyword.kwlist) <= KEYWORDS["Python"]
    assert {"int", "return", "_Bool", "restrict"} <= KEYWORDS["C"]
    assert {"end", "function", "endfunction", "unwind_protect"} <= KEYWORDS["Octave/MATLAB"]
    assert {"let", "yield", "await", "enum"} <= KEYWORDS["JavaScript"]


def test_the_ceilings_are_documented():
    """Each ceiling the code enforces is written in docs/cli.md's table of limits."""
    from obsdesign import _memo, _validate

    text = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    for value in (_validate.MAX_BOOTSTRAP, _validate.MAX_DELAY_SAMPLES, _validate.MAX_CSV_LINE, _memo.MAX_ENTRY_BYTES):
        assert f"{value:,}" in text or str(value) in text, value
    assert os.fspath("The result memo") in text and "trust" in text
