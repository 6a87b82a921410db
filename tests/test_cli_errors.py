"""Every CLI error is one line with the documented exit status (the review's tables A, C and E).

Exit statuses (docs/cli.md): 0 success, 1 a check failed, 2 bad input or environment,
3 internal error. Each case names the id of the reliability review it covers.
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import obsdesign as od
from obsdesign.cli import main

LONG = "a" * 5000
PRESET = os.path.join(os.path.dirname(od.__file__), "presets", "vcm.toml")


def run(capsys, *argv):
    """``main(argv)`` in process: (status, stdout, stderr lines)."""
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err.strip().splitlines()


def one_line(capsys, argv, match, status=2):
    code, _, err = run(capsys, *argv)
    assert code == status and len(err) == 1, (code, err)
    assert match in err[0] and "Traceback" not in err[0], err[0]
    return err[0]


@pytest.fixture
def fx(tmp_path):
    """Fixture files of the review (fx/)."""
    (tmp_path / "latin.toml").write_bytes(Path(PRESET).read_bytes().replace(b'name = "vcm"', b'name = "caf\xe9"'))
    (tmp_path / "binary.toml").write_bytes(bytes(range(256)) * 4)
    (tmp_path / "big.toml").write_text(Path(PRESET).read_text().replace("rho = 4.0", "rho = 1" + "0" * 400))
    (tmp_path / "existing_dir.csv").mkdir()
    (tmp_path / "dir.svg").mkdir()
    (tmp_path / "report_dir.html").mkdir()
    (tmp_path / "ex_cdir" / "obsdesign_observer.c").mkdir(parents=True)
    return tmp_path


@pytest.mark.parametrize("argv, match", [
    (["check", "--config", ""], "argument --config: expected the path of a TOML file, found ''"),  # p29
    (["simulate", "positioning", "--config", ""], "argument --config: expected the path of a TOML file"),  # p34
    (["check", "--config", LONG], "config: cannot read 'aaaa"),  # p31
    (["check", "--config", "{fx}/latin.toml"], "latin.toml: expected UTF-8 text (TOML), found the byte 0xe9"),  # p26
    (["check", "--config", "{fx}/binary.toml"], "binary.toml: expected UTF-8 text"),  # p27
    (["export", "--format", "c", "--config", "{fx}/latin.toml", "-o", "{fx}/e"], "latin.toml: expected UTF-8"),  # e10
    (["check", "--config", "{fx}/big.toml"], "observer.rho: expected a finite number > 0, found an integer of 401"),  # x6
    (["simulate", "positioning", "--duration", "1e9"], "--duration/--dt: expected at most 1e+08 samples"),  # s6
    (["simulate", "positioning", "--dt", "1e-12"], "--duration/--dt: expected at most 1e+08 samples"),  # s7
    (["simulate", "positioning", "--out", "/proc/x.csv"], "argument --out: cannot write '/proc/x.csv'"),  # s14
    (["simulate", "positioning", "--out", "{fx}/existing_dir.csv"], "--out: expected a file, found the folder"),  # s16
    (["simulate", "positioning", "--out", "{fx}/" + LONG + ".csv"], "argument --out: cannot "),  # s23
    (["simulate", "positioning", "--plot", "/proc/x.svg"], "argument --plot: cannot write '/proc/x.svg'"),  # s33
    (["simulate", "positioning", "--plot", "{fx}/dir.svg"], "--plot: expected a file, found the folder"),  # x1
    (["export", "--format", "c", "-o", "/proc/ex"], "argument -o/--output: cannot write '/proc/ex'"),  # e4
    (["export", "--format", "c", "-o", "{fx}/" + LONG], "argument -o/--output: cannot use"),  # e8
    (["export", "--format", "c", "-o", ""], "argument -o/--output: expected a folder name, found ''"),
    (["export", "--format", "c", "-o", "{fx}/ex_cdir"], "'obsdesign_observer.c' in"),  # x2
    (["report", "-o", "{fx}/report_dir.html"], "argument -o/--output: expected a file, found the folder"),  # r2
    (["report", "-o", "/proc/r.html"], "argument -o/--output: cannot write '/proc/r.html'"),  # r3
    (["report", "-o", ""], "argument -o/--output: expected a file name, found ''"),  # r4
    (["report", "-o", "{fx}/" + LONG + ".html"], "argument -o/--output: cannot "),  # r7
    (["check", "--rho", "1e308"], "overflows to non-finite numbers with --rho 1e+308"),  # c9
    (["check", "--kappa", "1e300"], "with --kappa 1e+300"),  # c12
    (["pid", "--tau", "1e300"], "with --tau 1e+300"),  # q6
    (["pid", "--max-s", "1e-300"], "with --max-s 1e-300"),  # q7
])
def test_bad_input_is_one_line_with_status_2(capsys, fx, argv, match):
    before = sorted(p.name for p in fx.iterdir())
    line = one_line(capsys, [a.replace("{fx}", str(fx)) for a in argv], match)
    assert len(line) < 700
    assert sorted(p.name for p in fx.iterdir()) == before  # nothing half-written
    assert list((fx / "ex_cdir").iterdir()) == [fx / "ex_cdir" / "obsdesign_observer.c"]


def test_output_paths_are_checked_before_the_work(capsys, fx, monkeypatch):
    import obsdesign.report.html as html
    import obsdesign.sim as sim

    def forbidden(*args, **kwargs):
        raise AssertionError("the expensive work started before the output path was checked")

    monkeypatch.setattr(html, "write_report", forbidden)
    monkeypatch.setattr(sim, "simulate", forbidden)
    one_line(capsys, ["report", "-o", str(fx / "report_dir.html")], "found the folder")
    one_line(capsys, ["report", "-o", "/proc/r.html"], "cannot write")
    one_line(capsys, ["simulate", "positioning", "--out", "/proc/x.csv"], "cannot write")
    one_line(capsys, ["simulate", "positioning", "--duration", "1e9"], "samples")


@pytest.mark.parametrize("summary, match", [
    ("[]", "expected a JSON object with the keys runs"),  # x8 / E21
    ("{", "is not valid UTF-8 JSON"),
    (b"\xff\xfe", "is not valid UTF-8 JSON"),
    (json.dumps({"runs": "x"}), "summary.json"),
])
def test_a_malformed_sweep_summary_is_one_line(capsys, tmp_path, summary, match):
    folder = tmp_path / "sw"
    folder.mkdir()
    (folder / "summary.json").write_bytes(summary if isinstance(summary, bytes) else summary.encode())
    for name in ("summary_map.svg", "summary_distributions.svg"):
        (folder / name).write_text("<svg xmlns='http://www.w3.org/2000/svg'/>")
    line = one_line(capsys, ["report", "--quiet", "--sweep", str(folder), "-o", str(tmp_path / "r.html")], match)
    assert "summary.json" in line
    assert not (tmp_path / "r.html").exists()


def test_a_sweep_figure_that_is_not_svg_is_named(capsys, tmp_path):  # x9
    folder = tmp_path / "sw"
    folder.mkdir()
    (folder / "summary.json").write_text(json.dumps({"runs": 0, "ok": 0, "diverged": 0, "failed": 0,
                                                     "resumed_runs": 0, "wall_s": 0.0, "metric": "rms_error",
                                                     "best": {}}))
    (folder / "summary_map.svg").write_text("<html>no figure</html>")
    (folder / "summary_distributions.svg").write_text("<svg/>")
    one_line(capsys, ["report", "--quiet", "--sweep", str(folder), "-o", str(tmp_path / "r.html")],
             "summary_map.svg' is not an SVG figure")


def test_an_internal_error_exits_3_with_a_hint_and_never_1(capsys, monkeypatch):
    import obsdesign.design as design

    def broken(*args, **kwargs):
        raise KeyError("boom")

    monkeypatch.setattr(design, "check_stability", broken)
    line = one_line(capsys, ["check"], "obsdesign: internal error: KeyError: 'boom'", status=3)
    assert "please report it" in line and "OBSDESIGN_DEBUG=1" in line
    monkeypatch.setenv("OBSDESIGN_DEBUG", "1")
    code, _, err = run(capsys, "check")
    assert code == 3 and err[0] == "Traceback (most recent call last):" and "please report it" in err[-1]


@pytest.mark.parametrize("error, status", [(MemoryError(), 2), (OverflowError("x"), 2), (OSError(28, "full"), 2),
                                           (RuntimeError("x"), 3), (ZeroDivisionError("x"), 3)])
def test_check_exits_1_only_for_a_failed_check(capsys, monkeypatch, error, status):
    import obsdesign.design as design

    def broken(*args, **kwargs):
        raise error

    monkeypatch.setattr(design, "check_stability", broken)
    code, out, err = run(capsys, "check")
    assert code == status and len(err) == 1 and out == ""
    monkeypatch.undo()
    assert run(capsys, "check", "--rho", "0.98")[0] == 1  # a genuinely failed check (c13)


def _cli(*argv, **kwargs):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    env.pop("OBSDESIGN_DEBUG", None)
    return subprocess.run([sys.executable, "-m", "obsdesign", *argv], stderr=subprocess.PIPE, text=True, env=env,
                          timeout=120, **kwargs)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")
@pytest.mark.parametrize("argv", [["check", "--json"],  # m1, m2; the derivation in a fresh interpreter is slow
                                  pytest.param(["derive", "--format", "json"], marks=pytest.mark.slow)])
def test_a_full_stdout_is_one_line_and_status_2(argv):
    with open("/dev/full", "w") as full:
        proc = _cli(*argv, stdout=full)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == ["obsdesign: error: cannot write to standard output "
                                                "(No space left on device)"]


SETPRIV = shutil.which("setpriv")


@pytest.mark.slow
@pytest.mark.skipif(not (SETPRIV and os.geteuid() == 0), reason="needs root and setpriv to drop DAC capabilities")
def test_unreadable_and_unwritable_paths_without_dac_capabilities(tmp_path):  # p6, s15, e5, r6
    (tmp_path / "u.toml").write_text(Path(PRESET).read_text())
    (tmp_path / "u.toml").chmod(0)
    (tmp_path / "ro").mkdir()
    (tmp_path / "ro").chmod(0o555)
    drop = [SETPRIV, "--bounding-set=-dac_override,-dac_read_search", sys.executable, "-m", "obsdesign"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    cases = [(["check", "--config", str(tmp_path / "u.toml")], "config: cannot read"),
             (["simulate", "positioning", "--out", str(tmp_path / "ro" / "x.csv")], "--out: cannot write"),
             (["export", "--format", "c", "-o", str(tmp_path / "ro")], "-o/--output: cannot write"),
             (["export", "--format", "c", "-o", str(tmp_path / "ro" / "new")], "-o/--output: cannot write"),
             (["report", "-o", str(tmp_path / "ro" / "r.html")], "-o/--output: cannot write")]
    for argv, match in cases:
        proc = subprocess.run(drop + argv, capture_output=True, text=True, env=env, timeout=120)
        lines = proc.stderr.strip().splitlines()
        assert proc.returncode == 2 and len(lines) == 1 and match in lines[0] and "Permission denied" in lines[0], \
            (argv, proc.stderr)
    assert list((tmp_path / "ro").iterdir()) == []


def test_numpy_scalars_are_accepted_and_huge_integers_refused():  # a11, a12, a14
    cfg = od.load_preset("vcm")
    assert cfg.override(rho=np.int64(4)).observer.rho == 4.0 and cfg.override(rho=np.float32(2.5)).observer.rho == 2.5
    assert type(cfg.override(kappa=np.int32(8000)).friction.kappa) is float
    with pytest.raises(ValueError, match=r"observer.rho: expected a finite number > 0, found an integer of 401 digits"):
        cfg.override(rho=10**400)


def test_warnings_of_a_successful_command_are_one_line_each(capsys, monkeypatch):  # L6
    import warnings

    import obsdesign.design.pid as design  # pid_from_config's verification (the PID the config carries)

    real = design.design_pid

    def noisy(**kwargs):
        for _ in range(3):
            warnings.warn("Mean of empty slice\nsecond line", RuntimeWarning)
        return real(**kwargs)

    monkeypatch.setattr(design, "design_pid", noisy)
    code, out, err = run(capsys, "pid", "--json")
    assert code == 0 and json.loads(out)["kp"] > 0
    assert err == ["obsdesign: warning: Mean of empty slice"]
    monkeypatch.setattr(design, "design_pid", lambda **kw: (warnings.warn("dropped"), 1 / 0))
    code, out, err = run(capsys, "pid")
    assert code == 3 and len(err) == 1 and "ZeroDivisionError" in err[0]  # warnings of a failed run are dropped


def test_unstable_designs_are_flagged_by_noise_and_export(capsys, tmp_path):  # n8, e7
    code, out, err = run(capsys, "noise", "--rho", "0.5", "--json")
    assert code == 0 and isinstance(json.loads(out), dict)  # still one strict JSON object on stdout
    assert len(err) == 1 and err[0].startswith("obsdesign: warning: the observer design fails check (")
    assert "Proposition 1: L_2" in err[0]  # rho < 1 makes L2 = kappa (1 - rho^2) > 0 fail the bound
    code, out, err = run(capsys, "export", "--format", "c", "--rho", "0.5", "-o", str(tmp_path / "ex"))
    assert code == 0 and len(err) == 1 and "the exported observer diverges" in err[0]
    assert (tmp_path / "ex" / "obsdesign_observer.c").is_file()
    code, out, err = run(capsys, "noise", "--rho", "4", "--json")
    assert code == 0 and err == []


def test_vary_with_a_non_ascii_digit_names_the_flag(capsys):  # w21
    one_line(capsys, ["sweep", "--scenario", "positioning", "--vary", "rho=1:2:\u00b2", "--out", "x"],
             "--vary rho: expected an integer N >= 1, found '\u00b2'")


@pytest.mark.parametrize("argv", [["--vary", "rho=1:2:100000000"], ["--samples", str(10**12)],
                                  ["--vary", "rho=1:2:4000", "--vary", "kappa=1:2:4000"]])  # w30, w31
def test_huge_sweeps_are_refused_before_the_plan(capsys, tmp_path, argv):
    one_line(capsys, ["sweep", "--scenario", "positioning", *argv, "--out", str(tmp_path / "sw")],
             "--vary/--samples: expected at most 1e+06 runs (grid points x samples)")
    assert not (tmp_path / "sw").exists()


def test_the_report_study_of_a_diverging_design_says_so():  # m5, m6 (the report failed on None metrics)
    from obsdesign import studies

    cfg = od.load_preset("vcm").override(rho=0.5)  # an unstable observer: the compensated runs diverge
    study = studies.experiments_study(cfg)
    assert any(None in metrics["steady_state_error"] for metrics in study.positioning.values())
    texts = {c.statement: c for c in study.claims}
    ss = texts["observer compensation reaches zero steady-state error, PID does not"]
    assert "none (diverged)" in ss.measured and ss.reproduced is False


def test_the_observer_export_has_the_simulators_schedule_and_no_warning(capsys, tmp_path):
    """The observer export runs the simulator's default schedule 'estimated' with its reversal hysteresis
    (issue 34): under sensor noise (table1) it is written without a warning, the threshold in the code."""
    code, _, err = run(capsys, "export", "--format", "python", "--preset", "table1", "-o", str(tmp_path / "a"))
    assert code == 0 and err == []
    assert "REVERSAL_THRESHOLD = 4e-06" in (tmp_path / "a" / "obsdesign_observer.py").read_text()
    code, _, err = run(capsys, "export", "--format", "c", "--preset", "table1", "-o", str(tmp_path / "b"))
    assert code == 0 and err == [] and "#define OD_REVERSAL_THRESHOLD 3.9999999999999998e-06" in (
        tmp_path / "b" / "obsdesign_observer.c").read_text()


def test_the_controller_export_has_the_simulators_schedule_and_no_warning(capsys, tmp_path):
    """--what controller exports the default 'estimated' schedule with its hysteresis: no warning; --stiffness and
    --estimator choose as in simulate ('true' cannot be deployed), and apply to --what controller only."""
    code, out, err = run(capsys, "export", "--what", "controller", "--format", "c", "--preset", "table1",
                         "--estimator", "dob", "-o", str(tmp_path / "a"))
    assert code == 0 and err == [] and "OD_E_PHI_1_1" in (tmp_path / "a" / "obsdesign_controller.c").read_text()
    code, _, err = run(capsys, "export", "--what", "controller", "--format", "js", "--preset", "table1",
                       "--stiffness", "constant", "-o", str(tmp_path / "b"))
    from obsdesign.sampled.choices import SCHEDULES

    constant = f"SCHEDULE: {float(SCHEDULES.code('constant'))},"  # the simulator's code of the schedule
    assert code == 0 and err == [] and constant in (tmp_path / "b" / "obsdesign_controller.mjs").read_text()
    code, _, err = run(capsys, "export", "--what", "controller", "--format", "c", "--stiffness", "true", "-o",
                       str(tmp_path / "c"))
    assert code == 2 and len(err) == 1 and "--stiffness" in err[0] and "'true'" in err[0]
    code, _, err = run(capsys, "export", "--format", "c", "--estimator", "eso", "-o", str(tmp_path / "d"))
    assert code == 2 and err == ["obsdesign export: argument --estimator: applies to --what controller only, "
                                 "found 'eso'"]
