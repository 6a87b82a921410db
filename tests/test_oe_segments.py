"""Segment output error (obsdesign.data.oe_segments) and the refinement's command line (issue 32, point 5)."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest
from _axis_logs import AXES, axis_trace, noisy_log, simulate_axis

from obsdesign.data import identify
from obsdesign.data.oe_segments import segment_bounds, simulate_segments
from obsdesign.data.output_error import RefineFailed, refine
from obsdesign.friction.registry import FRICTION_MODELS


def _pp(m_cf=1e-12):
    """LuGre with a negligible Coulomb level: a pure inertia."""
    return np.array(FRICTION_MODELS["lugre"]._layout({"Cf": m_cf, "Cf_neg": m_cf, "sigma": 0.0, "sigma_neg": 0.0,
                                                      "offset": 0.0, "Fs": m_cf, "vs": 1.0, "sigma0": 1e3,
                                                      "sigma1": 0.0}))


def test_segment_bounds_tile_the_record():
    rows = segment_bounds(1000, 300, skip=50)
    assert rows.tolist() == [[50, 300], [350, 300], [650, 300]]   # the last ends at 950 = 1000 - 50 (exclusive)
    assert segment_bounds(1000, 300, skip=51).shape == (2, 2)


def test_held_input_is_the_double_integral():
    """Under a force held over each sample a free inertia moves by the closed form
    x[k+1] = x[k] + v[k] dt + u[k] dt^2 / (2 m), v[k+1] = v[k] + u[k] dt / m (the review's exact reference)."""
    rng = np.random.default_rng(4)
    dt, m, n = 1e-3, 0.7, 200
    u = rng.normal(0.0, 1.0, 2 * n)
    out = np.empty((2, n))
    starts = np.array([0, n])
    x0, v0 = np.array([0.1, -0.2]), np.array([0.5, 0.0])
    assert simulate_segments(_pp(), u, starts, n, x0, v0, np.zeros(2), m, dt, 4, True, out)
    for i in range(2):
        x, v = x0[i], v0[i]
        ref = []
        for k in range(n):
            ref.append(x)
            f = u[starts[i] + k]
            x, v = x + v * dt + f * dt**2 / (2 * m), v + f * dt / m
        np.testing.assert_allclose(out[i], ref, rtol=0, atol=1e-12)


def test_interpolated_input_is_the_double_integral_of_a_ramp():
    """Logged as it acted: the force ramps linearly between samples; exact for a ramp with midpoint substeps
    up to the substeps' O(h^2) error, compared with the closed form of the cubic."""
    dt, m, n = 1e-3, 2.0, 100
    u = np.linspace(0.0, 1.0, n + 1)
    t = np.arange(n) * dt
    exact = t**3 / (n * dt) / (6 * m)
    err = []
    for n_sub in (16, 32, 64):
        out = np.empty((1, n))
        assert simulate_segments(_pp(), u, np.array([0]), n, np.zeros(1), np.zeros(1), np.zeros(1), m, dt, n_sub,
                                 False, out)
        err.append(np.max(np.abs(out[0] - exact)))
    assert err[-1] < 1e-3 * np.max(exact)
    assert 3.5 < err[0] / err[1] < 4.5 and 3.5 < err[1] / err[2] < 4.5   # second order in the substep


def _log(name, seed, duration):
    spec = dict(AXES[name], duration=duration)
    return spec, axis_trace(spec, noisy_log(spec, simulate_axis(spec), seed))


@pytest.mark.slow
def test_segment_fit_recovers_the_linear_axis_and_profiles_sigma0():
    """LuGre sigma0 = 1e6 N/m on the 1 kHz linear axis (held input, no delay; 8 s). identify reads this log's timing
    wrong ('sample', 1 late): the segment fit finds that the truth's reading fits better and calls nothing
    identifiable. With the timing given: every parameter within its interval, sigma0 within 5 %, the static ones
    within 0.1 %, sigma and Cf within their intervals; the profile over sigma0 has one minimum within the interval
    it reports."""
    spec, tr = _log("linear-1k-hold-d0", 3, 8.0)
    wrong = refine(tr, identify(tr), parameters=("m",), model="lugre")
    if identify(tr).input_timing != "hold" or identify(tr).delay_samples != 0:
        assert not any(wrong[n]["identifiable"] for n in wrong.fit.names)
        assert "--input-timing hold --delay-samples 0" in wrong.warning, wrong.warning
    ref = refine(tr, identify(tr, input_timing="hold", delay_samples=0), parameters=("sigma0",), model="lugre")
    assert not ref.warning, ref.warning
    for name, rel in (("m", 1e-3), ("sigma", 1e-3), ("Cf", 1e-3), ("sigma0", 0.05)):
        p = ref[name]
        assert p["value"] == pytest.approx(spec[name], rel=rel), name
        assert p["low"] <= p["value"] <= p["high"], (name, p)
        if name in ("sigma", "Cf"):  # the intervals of m and sigma0 are narrower than their spread on this axis
            assert p["low"] <= spec[name] <= p["high"], (name, p)  # (m covered in 6 of 19 draws: the report)
    assert ref["sigma0"]["identifiable"], ref["sigma0"]["note"]
    grid, cost = ref.fit.profiles["sigma0"]
    k = int(np.argmin(cost))
    assert 0 < k < grid.size - 1 and ref["sigma0"]["low"] <= ref["sigma0"]["value"] <= ref["sigma0"]["high"]
    assert ref.fit.segment_samples == 100 and "L = 100 samples" in str(ref)


@pytest.mark.slow
def test_a_tiny_time_budget_is_one_line_and_exit_1(tmp_path):
    """Stopped before a first fit: one line 'could not be identified', exit 1, no traceback."""
    from obsdesign.cli import main

    spec, tr = _log("linear-1k-hold-d0", 1, 3.0)
    path = tmp_path / "lin.csv"
    np.savetxt(path, np.column_stack([tr.t, tr.position, tr.force / spec["gain"]]), delimiter=",",
               header="t [s],x [m],i [A]", comments="", fmt="%.17g")
    proc = subprocess.run([sys.executable, "-m", "obsdesign", "identify", str(path), "--time", "t", "--position", "x",
                           "--input", "i", "--input-gain", "6.5", "--refine", "sigma0", "--refine-model", "lugre",
                           "--time-budget", "1e-6"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 1, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if "could not be identified" in ln]
    assert len(lines) == 1 and "time budget" in lines[0] and "Traceback" not in proc.stderr
    with pytest.raises(RefineFailed, match="time budget"):
        refine(tr, identify(tr), parameters=("s",), time_budget=1e-6)
    assert main  # the in-process entry point is the one the examples test drives


def _help_examples() -> list[tuple[str, str]]:
    """Each ``--refine`` example of ``identify --help`` with its model: the quoted names before '(paper)' are for the
    default model, those after 'with --refine-model lugre' for LuGre."""
    from obsdesign.cli import build_parser

    text = " ".join(build_parser("identify")._subparsers._group_actions[0].choices["identify"].format_help().split())
    part = text[text.index("--refine NAMES refine"):text.index("--refine-model MODEL plant")]
    paper, _, lugre = part.partition("(paper)")
    return [(name, "paper") for name in re.findall(r"'([^']+)'", paper)] + \
        [(name, "lugre") for name in re.findall(r"'([^']+)'", lugre.split("(a segment fit")[0])]


def test_the_help_shows_examples_for_both_models():
    ex = _help_examples()
    assert ("s", "paper") in ex and ("sigma0", "lugre") in ex and len(ex) == 4


@pytest.mark.slow
@pytest.mark.parametrize("names, model", _help_examples())
def test_every_help_example_runs(names, model, tmp_path, capsys):
    """Each example of the help on a small generated log (the linear 1 kHz axis, 4 s): exit 0 and a JSON refinement
    in the axis's units."""
    from obsdesign.cli import main

    spec, tr = _log("linear-1k-hold-d0", 2, 4.0)
    path = tmp_path / "lin.csv"
    np.savetxt(path, np.column_stack([tr.t, tr.position, tr.force / spec["gain"]]), delimiter=",",
               header="t [s],x [m],i [A]", comments="", fmt="%.17g")
    args = ["identify", str(path), "--time", "t", "--position", "x", "--input", "i", "--input-gain", "6.5",
            "--refine", names, "--refine-model", model, "--json"]
    assert main(args) == 0, capsys.readouterr().err
    out = json.loads(capsys.readouterr().out)["refinement"]
    assert set(names.split(",")) <= set(out["parameters"])


@pytest.mark.slow
def test_rotary_refine_speaks_rotary_units(tmp_path, capsys):
    """The rotary 4 kHz axis (held input, 1 sample late, 2^20 counts/rev): the refinement's units are the axis's."""
    from obsdesign.cli import main

    spec, tr = _log("rotary-4k-hold-d2", 0, 2.0)
    path = tmp_path / "rot.csv"
    np.savetxt(path, np.column_stack([tr.t, tr.position, tr.force / spec["gain"]]), delimiter=",",
               header="t [s],x [rad],i [A]", comments="", fmt="%.17g")
    args = ["identify", str(path), "--time", "t", "--position", "x", "--input", "i", "--input-gain", "0.1",
            "--refine", "sigma0", "--refine-model", "lugre", "--segment", "0.05", "--time-budget", "120"]
    assert main(args) == 0
    text = capsys.readouterr().out
    head = text[text.index("Output-error refinement"):text.index("Identification")]
    assert "kg m^2" in head and "N m/rad" in head and "rad (" in head
    units = dict(re.findall(r"^  (\w+)\s+\S+ (.+?)  95 %", head, flags=re.M))
    assert units == {"m": "kg m^2", "sigma": "N m s/rad", "Cf": "N m", "offset": "N m", "sigma0": "N m/rad",
                     "sigma1": "N m s/rad"}, units
    rows = [re.search(r"^\s+\w+\s+(\S+) .*95 % \[(\S+), (\S+)\]", line) for line in head.splitlines()]
    assert sum(r is not None for r in rows) == 6
    for row in filter(None, rows):   # every interval holds its point estimate
        value, low, high = map(float, row.groups())
        assert low <= value <= high, row.group(0)
