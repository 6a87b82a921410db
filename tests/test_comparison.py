"""The estimator comparison: rows, summary verdicts, the ``compare`` command and the report section."""

from __future__ import annotations

import base64
import csv
import json

import numpy as np
import pytest

import obsdesign as od
from obsdesign.cli import main
from obsdesign.comparison import COLUMNS, compare, summarize
from obsdesign.estimators import reference_noise_rms
from obsdesign.report.comparison_section import comparison_section


def _rows(values: dict[str, tuple[float, ...]], metric="friction_rms_error", scenario="excitation"):
    return [{"plant": "paper", "scenario": scenario, "estimator": est, "seed": i, metric: v, "status": "ok"}
            for est, vals in values.items() for i, v in enumerate(vals)]


@pytest.mark.parametrize("values, best, verdict", [
    ({"a": (1.0, 1.1), "b": (1.2, 1.3)}, "a", "win"),             # ranges [1.0, 1.1] < [1.2, 1.3]
    ({"a": (1.0, 1.25), "b": (1.2, 1.3)}, "a", "within spread"),  # ranges overlap
    ({"a": (1.0, 1.0), "b": (1.005, 1.005)}, "a", "tie"),         # no spread, 0.5 % apart
    ({"a": (1.0,), "b": (2.0,)}, "a", "single seed"),
    ({"b": (2.0, 2.0), "a": (1.0, 1.0)}, "a", "win"),             # order of the rows does not matter
])
def test_summary_verdicts(values, best, verdict):
    (s,) = summarize(_rows(values))
    assert (s["best"], s["verdict"]) == (best, verdict)
    assert s["best_mean"] == pytest.approx(np.mean(values[best]))


def test_summary_ignores_failed_estimators():
    rows = _rows({"a": (1.0, 1.1), "b": (0.5, 0.6)})
    rows[2]["status"] = "diverged"
    (s,) = summarize(rows)
    assert s["best"] == "a" and s["verdict"] == "only one estimator completed every seed"


@pytest.fixture(scope="module")
def small():
    cfg = od.load_preset("vcm")
    return cfg, compare(cfg, plants=("paper", "dahl"), estimators=("paper", "dob"),
                        scenarios=("excitation", "positioning"), seeds=1, workers=1)


@pytest.mark.slow
def test_rows_cover_every_case(small):
    _, res = small
    keys = [(r["plant"], r["estimator"], r["scenario"]) for r in res.rows]
    assert keys == [(p, e, s) for p in ("paper", "dahl") for e in ("paper", "dob") for s in ("excitation", "positioning")]
    assert all(set(r) == set(COLUMNS) for r in res.rows)


@pytest.mark.slow
def test_baselines_have_the_paper_noise(small):
    cfg, res = small
    ref = reference_noise_rms(cfg)
    for r in res.rows:
        assert r["friction_noise_rms"] == pytest.approx(ref, rel=1e-6)


@pytest.mark.slow
def test_settling_time_agrees_with_the_simulator_metric(small):
    """step_metrics (comparison) against loop_metrics (simulate): two implementations of one definition."""
    cfg, res = small
    from obsdesign.comparison import SCENARIOS

    spec, duration = SCENARIOS["positioning"]
    sim = od.simulate(cfg, spec, duration=duration, seed=0, keep_trace=False)
    row = next(r for r in res.rows if (r["plant"], r["estimator"], r["scenario"]) == ("paper", "paper", "positioning"))
    assert row["settling_time"] == pytest.approx(np.mean(sim.metrics["settling_time"]), abs=2 * cfg.observer.dt)


@pytest.mark.slow
def test_parallel_rows_equal_serial_rows(small):
    cfg, res = small
    par = compare(cfg, plants=("paper", "dahl"), estimators=("paper", "dob"), scenarios=("excitation", "positioning"),
                  seeds=1, workers=2)
    assert par.rows == res.rows


def test_compare_rejects_bad_names():
    with pytest.raises(ValueError, match="plants: expected one of paper, lugre, dahl, gms, found 'coulomb'"):
        compare(od.load_preset("vcm"), plants=("coulomb",))
    with pytest.raises(ValueError, match="seeds: expected an integer >= 1"):
        compare(od.load_preset("vcm"), seeds=0)


def test_cli_writes_the_table_and_the_report_reads_it(tmp_path, capsys):
    out = tmp_path / "cmp"
    status = main(["compare", "--plants", "paper", "--estimators", "paper,dob", "--scenarios", "excitation",
                   "--seeds", "2", "--workers", "1", "--out", str(out), "--json"])
    assert status == 0
    payload = json.loads(capsys.readouterr().out)
    with open(out / "compare.csv", newline="") as fh:
        reader = csv.DictReader(fh)
        assert tuple(reader.fieldnames) == COLUMNS
        rows = list(reader)
    assert len(rows) == 4 and {r["status"] for r in rows} == {"ok"}
    assert payload["summary"][0]["best"] in ("paper", "dob")
    section = comparison_section(out)
    assert len(section["rows"]) == 4 and section["svg_src"].startswith("data:image/svg+xml;base64,")
    assert b"<svg" in base64.b64decode(section["svg_src"].split(",", 1)[1])


@pytest.mark.parametrize("argv, message", [
    (["compare", "--plants", "paper,coulomb"], "argument --plants: expected names from paper, lugre, dahl, gms, found 'coulomb'"),
    (["compare", "--seeds", "0"], "argument --seeds"),
    (["compare", "--estimators", "eso,eso"], "argument --estimators: expected distinct names"),
])
def test_cli_bad_input_is_one_line(tmp_path, capsys, argv, message):
    out = tmp_path / "cmp"
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_report_section_rejects_a_foreign_folder(tmp_path):
    with pytest.raises(ValueError, match="compare: expected a folder written by 'obsdesign compare'"):
        comparison_section(tmp_path)


def _synthetic_trace(tmp_path):
    """A noise-free axis with known Coulomb-viscous friction and an offset (as docs/measured-data.md)."""
    dt = 1e-3
    t = np.arange(20_000) * dt
    x = 0.05 * np.sin(2 * np.pi * 0.5 * t) + 0.01 * np.sin(2 * np.pi * 2.3 * t)
    v = np.gradient(x, dt)
    u_volt = (2.0 * np.gradient(v, dt) + 30.0 * v + 1.5 * np.sign(v) - 0.4) / 4.0
    path = tmp_path / "axis.csv"
    np.savetxt(path, np.column_stack([t, x, u_volt]), delimiter=",", header="t,x,u_volt", comments="")
    return path


def test_data_rows_follow_the_identified_friction(tmp_path):
    from obsdesign.comparison_data import compare_data
    from obsdesign.data import load_trace

    trace = load_trace(_synthetic_trace(tmp_path), position="x", input="u_volt", time="t", input_gain=4.0)
    rows = {r["estimator"]: r for r in compare_data(trace, estimators=("paper", "kalman"))}
    for name in ("paper", "kalman"):
        assert rows[name]["status"] == "ok" and rows[name]["scenario"] == "data"
        # Coulomb level 1.5 N, offset -0.4 N. The estimates lag the sign jumps at the reversals (about
        # 0.37 N RMS); leaving the offset in the force adds 0.4 N (sqrt(0.37^2 + 0.4^2) = 0.54 N)
        assert rows[name]["friction_rms_error"] < 0.45
        assert rows[name]["velocity_rms_error"] < 0.02 * np.sqrt(np.mean(np.gradient(trace.position, 1e-3) ** 2))


def test_cli_data_needs_column_names(tmp_path, capsys):
    assert main(["compare", "--data", str(_synthetic_trace(tmp_path)), "--out", str(tmp_path / "cmp")]) == 2
    assert "needs --position NAME and --input NAME" in capsys.readouterr().err
    assert not (tmp_path / "cmp").exists()


@pytest.mark.slow
def test_rule_rate_tunes_the_baselines_to_the_papers_slowest_pole(tmp_path):
    """``compare(rule='rate')``: the ESO's triple pole sits at the paper observer's dominant pole
    (-sqrt(kappa/m)(rho - 1) for the vcm design, in closed form), its noise column is that tuning's, and
    the CLI records the rule in summary.json."""
    import json
    import math
    import subprocess
    import sys

    from obsdesign.comparison import compare
    from obsdesign.estimators import friction_noise_rms, noise_level, tune

    cfg = od.load_preset("vcm")
    dominant = math.sqrt(cfg.friction.kappa / cfg.plant.m) * (cfg.observer.rho - 1.0)
    rate = tune("eso", cfg, rule="rate")
    assert rate.params["omega_o"] == pytest.approx(dominant, rel=1e-9)
    res = compare(cfg, plants=("paper",), estimators=("eso",), scenarios=("positioning",), seeds=1, workers=1,
                  rule="rate")
    eta, band = noise_level(cfg)
    assert res.rule == "rate"
    assert res.rows[0]["friction_noise_rms"] == pytest.approx(friction_noise_rms(rate, eta, band), rel=1e-12)
    assert res.rows[0]["friction_noise_rms"] != pytest.approx(friction_noise_rms(tune("eso", cfg), eta, band),
                                                              rel=1e-3)
    with pytest.raises(ValueError, match="rule: expected one of noise, rate, min-error, found 'fast'"):
        compare(cfg, plants=("paper",), estimators=("eso",), scenarios=("positioning",), seeds=1, rule="fast")
    out = tmp_path / "cmp"
    run = subprocess.run([sys.executable, "-m", "obsdesign", "compare", "--plants", "paper", "--estimators", "eso",
                          "--scenarios", "positioning", "--seeds", "1", "--workers", "1", "--rule", "rate", "--out",
                          str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert json.loads((out / "summary.json").read_text())["rule"] == "rate"
    bad = subprocess.run([sys.executable, "-m", "obsdesign", "compare", "--rule", "min", "--out", str(out)],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) <= 2 and "--rule" in bad.stderr


def _untunable_dob():
    """vcm with a 4 kHz low-pass: the paper's filtered estimate is noisier than the DOB at the top of its
    knob range, so the noise rule cannot tune the DOB; the ESO and the Kalman filter still reach it."""
    return od.load_preset("vcm").override(omega_co=2 * np.pi * 4000)


def test_a_baseline_that_cannot_be_tuned_is_a_row_and_the_others_run():
    from obsdesign.comparison import NOT_TUNED, not_tuned
    from obsdesign.estimators import tune

    cfg = _untunable_dob()
    with pytest.raises(ValueError, match="noise rule: no knob"):
        tune("dob", cfg)
    kw = dict(plants=("paper",), scenarios=("excitation",), seeds=1, workers=1)
    res = compare(cfg, estimators=("paper", "dob", "eso"), **kw)
    assert [r["estimator"] for r in res.rows] == ["paper", "dob", "eso"]
    dob = res.rows[1]
    assert dob["status"].startswith(NOT_TUNED + "noise rule: no knob in [")
    assert all(dob[c] is None for c in COLUMNS[4:-1]) and set(dob) == set(COLUMNS)
    assert not_tuned(res.rows) == {"dob": dob["status"][len(NOT_TUNED):]}
    # the others ran as they do without the DOB in the list
    alone = compare(cfg, estimators=("paper", "eso"), **kw)
    assert [res.rows[0], res.rows[2]] == alone.rows and {r["status"] for r in alone.rows} == {"ok"}
    (s,) = summarize(res.rows)
    assert {s["best"], s["runner_up"]} == {"paper", "eso"}


def test_cli_reports_the_untuned_baseline_and_exits_0_unless_nothing_ran(tmp_path, capsys):
    from jinja2 import Environment, PackageLoader

    path = tmp_path / "axis.toml"
    _untunable_dob().save(path)
    out = tmp_path / "cmp"
    argv = ["compare", "--config", str(path), "--plants", "paper", "--scenarios", "excitation", "--seeds", "1",
            "--workers", "1"]
    assert main([*argv, "--estimators", "paper,dob", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "dob    not tuned, not run: noise rule: no knob" in text
    with open(out / "compare.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["status"][:10] for r in rows] == ["ok", "not tuned:"] and rows[1]["friction_rms_error"] == ""
    payload = json.loads((out / "summary.json").read_text())
    assert list(payload["not_tuned"]) == ["dob"] and payload["not_tuned"]["dob"].startswith("noise rule: no knob")
    section = comparison_section(out)
    assert section["runs"] == 1 and section["not_tuned"] == payload["not_tuned"]
    env = Environment(loader=PackageLoader("obsdesign.report", "templates"), autoescape=True)
    env.filters["num"] = str
    html = env.get_template("_comparison.html.j2").render(comparison=section)
    assert "<tr><td>dob</td><td class=\"text wide\">noise rule: no knob in [" in html
    # nothing could run: one line, exit 2, no folder
    out2 = tmp_path / "cmp2"
    assert main([*argv, "--estimators", "dob", "--out", str(out2)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "no estimator could be tuned, found dob: noise rule" in err
    assert not out2.exists()


def test_data_rows_name_a_baseline_that_cannot_be_tuned(tmp_path, monkeypatch):
    """compare_data: a tuning failure (injected for the DOB) is that estimator's row with its reason; the Kalman
    row is the one computed without the DOB in the list."""
    import obsdesign.comparison_data as cd
    from obsdesign.comparison import NOT_TUNED
    from obsdesign.data import load_trace

    trace = load_trace(_synthetic_trace(tmp_path), position="x", input="u_volt", time="t", input_gain=4.0)
    alone = cd.compare_data(trace, estimators=("kalman",))
    real_tune = cd.tune

    def tune(name, cfg, **kw):
        if name == "dob":
            raise ValueError("noise rule: no knob in [0.001, 100000] reaches the target")
        return real_tune(name, cfg, **kw)

    monkeypatch.setattr(cd, "tune", tune)
    rows = cd.compare_data(trace, estimators=("dob", "kalman"))
    assert rows[0]["status"] == NOT_TUNED + "noise rule: no knob in [0.001, 100000] reaches the target"
    assert all(rows[0][c] is None for c in COLUMNS[4:-1]) and rows[0]["plant"] == f"data:{trace.source}"
    assert rows[1] == alone[0] and alone[0]["status"] == "ok"


def test_equal_seeds_draw_no_negative_error_bar():
    """Three equal seeds (an axis without random noise) whose rounded mean lies an ulp outside them
    (0.7 three times: 0.7 - 1.1e-16; 0.1 three times: 0.1 + 1.4e-17): the figure draws (it raised in
    matplotlib, exit 2 after the CSV was written) with error bars of zero."""
    from obsdesign.report.comparison_section import comparison_figure

    assert float(np.mean([0.7] * 3)) < 0.7 and float(np.mean([0.1] * 3)) > 0.1
    rows = [{"plant": "paper", "estimator": e, "scenario": "positioning", "seed": s, "friction_rms_error": v,
             "status": "ok"} for e, v in (("paper", 0.7), ("eso", 0.1)) for s in range(3)]
    from matplotlib.container import ErrorbarContainer

    fig = comparison_figure(rows)
    bars = [c for c in fig.axes[0].containers if isinstance(c, ErrorbarContainer)]
    assert len(bars) == 2
    for c in bars:
        for seg in c.lines[2][0].get_segments():
            assert abs(seg[1][1] - seg[0][1]) < 1e-15


@pytest.mark.slow  # a comparison of 3 seeds in a fresh interpreter
def test_cli_three_seeds_of_an_axis_without_noise(tmp_path):
    import subprocess
    import sys

    out = tmp_path / "c3"
    proc = subprocess.run([sys.executable, "-m", "obsdesign", "compare", "--preset", "vcm", "--seeds", "3", "--plants",
                           "paper", "--estimators", "paper,eso", "--out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert (out / "compare.svg").is_file()


def test_a_run_that_raises_fails_its_own_row_only(monkeypatch):
    """Runs that share work are made together; when one of them raises, each runs on its own and only the
    failing row says "failed" (as when every row was simulated alone)."""
    import obsdesign.comparison as comparison

    real_run = comparison.run

    def run(loop):
        if loop.estimator == "eso":
            raise ArithmeticError("eso blew up")
        return real_run(loop)

    def shared(loops):
        for loop in loops:
            run(loop)
        return [real_run(loop) for loop in loops]

    monkeypatch.setattr(comparison, "run", run)
    monkeypatch.setattr(comparison, "run_shared", shared)
    cfg = od.load_preset("vcm")
    plant = comparison.plant_config(cfg, "paper")
    tasks = [(cfg, plant, e, "excitation", 0, 0.0) for e in ("paper", "eso", "paper-k0")]
    rows = comparison.compare_rows(tasks)
    assert [r["status"] for r in rows] == ["ok", "failed: ArithmeticError: eso blew up", "ok"]
    assert rows[0]["friction_rms_error"] > 0 and rows[1]["friction_rms_error"] is None
