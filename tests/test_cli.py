import contextlib
import io
import json
import subprocess
import sys

import pytest

from obsdesign.cli import main


def run_process(*args):
    return subprocess.run([sys.executable, "-m", "obsdesign", *args], capture_output=True, text=True)


def run(*args):
    """In-process run of the command with its exit status and captured streams."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


@pytest.mark.parametrize("args, code", [pytest.param(["check", "--rho", "0.98"], 1, marks=pytest.mark.slow),
                                        (["check", "--rho", "x"], 2),
                                        pytest.param(["derive"], 0, marks=pytest.mark.slow)])
def test_real_process_exit_status(args, code):
    proc = run_process(*args)
    assert proc.returncode == code and "Traceback" not in proc.stderr


def test_derive_json_holds_the_gain_rule(capsys):
    assert main(["derive", "--variant", "lag", "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["variant"] == "lag"
    assert doc["gain_rule"]["L1"] == "2*sqrt(kappa)*rho/sqrt(m)"
    assert {"label", "title", "text", "latex"} <= set(doc["steps"][0])


def test_derive_latex_is_a_document(capsys):
    assert main(["derive", "--variant", "static", "--format", "latex"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("\\documentclass") and out.rstrip().endswith("\\end{document}")
    assert "eq:3:3:7" in out


def test_derive_text(capsys):
    assert main(["derive"]) == 0
    out = capsys.readouterr().out
    assert "variant 'lag'" in out and "Gain L2 (eq:3:3:4)" in out


@pytest.mark.parametrize(
    "args, match",
    [
        (["derive", "--variant", "dynamic"], "argument --variant: invalid choice: 'dynamic'"),
        (["derive", "--format", "pdf"], "argument --format: invalid choice: 'pdf'"),
        (["nosuch"], "invalid choice: 'nosuch'"),
        ([], "the following arguments are required: command"),
    ],
)
def test_bad_input_exits_2_with_one_line(args, match):
    proc = run(*args)
    assert proc.returncode == 2
    assert proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and match in lines[0] and "Traceback" not in proc.stderr


def run_json(*args):
    proc = run(*args)
    assert proc.stderr == ""
    return proc.returncode, json.loads(proc.stdout)


def test_check_stable_exits_0_with_the_contract_keys():
    code, doc = run_json("check", "--preset", "table1", "--rho", "1.02", "--json")
    assert code == 0
    assert {"L1", "L2", "stable", "eigenvalues_real", "observable", "dominant_pole", "fastest_pole", "conditions"} <= set(doc)
    assert doc["stable"] is True and doc["dominant_pole"] == pytest.approx(-2.4388, abs=1e-3)
    assert all({"name", "holds", "detail"} == set(c) for c in doc["conditions"])


def test_check_unstable_exits_1_and_names_the_condition():
    code, doc = run_json("check", "--preset", "table1", "--rho", "0.98", "--json")
    assert code == 1 and doc["stable"] is False
    assert {"Proposition 1: L_2 < sigma/beta"} <= {c["name"] for c in doc["conditions"] if not c["holds"]}
    proc = run("check", "--preset", "table1", "--rho", "0.98")
    assert proc.returncode == 1 and "FAIL" in proc.stdout and "Proposition 1: L_2 < sigma/beta" in proc.stdout


def test_check_with_a_config_file(tmp_path):
    import obsdesign as od

    path = tmp_path / "axis.toml"
    od.load_preset("vcm").override(rho=2.0).save(path)
    code, doc = run_json("check", "--config", str(path), "--json")
    assert code == 0 and doc["L2"] == pytest.approx(8000 * (1 - 4))


def test_pid_json_matches_the_paper():
    code, doc = run_json("pid", "--preset", "vcm", "--json")
    assert code == 0
    assert set(doc) >= {"k", "T_I", "kp", "ki", "kd", "omega_s", "max_S_achieved", "phase_margin_deg"}
    assert doc["kp"] == pytest.approx(429, rel=5e-3) and doc["ki"] == pytest.approx(4348, rel=5e-3)
    assert doc["kd"] == pytest.approx(2.67, rel=5e-3) and doc["max_S_achieved"] <= 1 / doc["k"]


def test_pid_from_flags():
    code, doc = run_json("pid", "--phi", "0.05", "--tau", "0.01", "--max-s", "0.01", "--phase-margin", "45", "--json")
    import math

    k = 100.0
    assert doc["k"] == k and doc["T_I"] == pytest.approx(1 / (k * 0.05 * math.sqrt(2)), rel=1e-12)  # eq:pidTime


def test_noise_json():
    code, doc = run_json("noise", "--preset", "vcm", "--rho", "4", "--noise-rms", "1e-6", "--noise-bandwidth", "1000", "--json")
    assert code == 0 and set(doc) >= {"direct_gain", "rms_raw", "rms_filtered"}
    assert doc["direct_gain"] == pytest.approx(-120000.0)
    assert 0 < doc["rms_filtered"] < doc["rms_raw"]


@pytest.mark.parametrize(
    "args, match",
    [
        (["check", "--rho", "abc"], "argument --rho: expected a finite number > 0, found 'abc'"),
        (["check", "--rho", "-1"], "argument --rho: expected a finite number > 0, found '-1'"),
        (["check", "--kappa", "nan"], "argument --kappa: expected a finite number > 0, found 'nan'"),
        (["check", "--preset", "nope"], "argument --preset: invalid choice: 'nope'"),
        (["check", "--preset", "vcm", "--config", "x.toml"], "not allowed with argument"),
        (["check", "--config", "/no/such/file.toml"], "config: expected an existing TOML file, found '/no/such/file.toml'"),
        (["check", "--preset", "vcm", "--variant", "lag"], "friction.beta"),
        (["pid", "--phase-margin", "95"], "argument --phase-margin: expected a finite number > 0 and < 90 deg, found '95'"),
        (["pid", "--phase-margin", "0"], "argument --phase-margin"),
        (["pid", "--max-s", "-0.1"], "argument --max-s: expected a finite number > 0, found '-0.1'"),
        (["noise", "--noise-rms", "-1e-6"], "argument --noise-rms: expected a finite number >= 0, found '-1e-6'"),
        (["noise", "--noise-bandwidth", "0"], "argument --noise-bandwidth"),
    ],
)
def test_design_commands_reject_bad_input(args, match):
    proc = run(*args)
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and match in lines[0] and "Traceback" not in proc.stderr


def test_bad_toml_values_exit_2(tmp_path):
    path = tmp_path / "bad.toml"
    import obsdesign as od

    path.write_text(od.load_preset("vcm").to_toml().replace("rho = 4.0", "rho = -4.0"))
    proc = run("check", "--config", str(path))
    assert proc.returncode == 2 and proc.stderr.strip() == "obsdesign: error: observer.rho: expected a finite number > 0, found -4.0"


def test_simulate_json_and_exports(tmp_path):
    out, plot = tmp_path / "trace.npz", tmp_path / "trace.svg"
    code, doc = run_json("simulate", "positioning", "--preset", "vcm", "--duration", "1.0", "--step-down", "0.8",
                         "--out", str(out), "--plot", str(plot), "--json")
    assert code == 0
    assert {"rms_error", "max_error", "settling_time", "steady_state_error", "observer_rms_error_v",
            "observer_rms_error_f", "diverged", "sim_wall_s"} <= set(doc)
    assert len(doc["settling_time"]) == 2 and doc["diverged"] is False
    import numpy as np

    with np.load(out) as z:
        assert z.files == ["t", "x", "x_meas", "v", "f", "v_hat", "f_hat", "f_hat_filtered", "u", "x_ref", "e"]
        assert doc["max_error"] == pytest.approx(np.max(np.abs(z["e"])))
    assert plot.read_text().rstrip().endswith("</svg>")


def test_simulate_csv(tmp_path):
    out = tmp_path / "c.csv"
    code, doc = run_json("simulate", "constant", "--duration", "0.05", "--out", str(out), "--json")
    assert code == 0 and out.read_text().splitlines()[0] == "t,x,x_meas,v,f,v_hat,f_hat,f_hat_filtered,u,x_ref,e"
    assert len(out.read_text().splitlines()) == 501


@pytest.mark.parametrize(
    "args, match",
    [
        (["simulate", "walk"], "argument scenario: invalid choice: 'walk'"),
        (["simulate", "tracking", "--out", "t.txt"], "argument --out: expected a file ending in .csv or .npz, found 't.txt'"),
        (["simulate", "tracking", "--plot", "t.pdf"], "argument --plot: expected a file ending in .svg or .png"),
        (["simulate", "tracking", "--out", "/no/such/dir/t.csv"], "argument --out: directory '/no/such/dir' does not exist"),
        (["simulate", "tracking", "--dt", "0"], "argument --dt: expected a finite number > 0, found '0'"),
        (["simulate", "tracking", "--seed", "1.5"], "argument --seed: expected an integer >= 0, found '1.5'"),
        (["simulate", "tracking", "--stiffness", "guess"], "argument --stiffness: invalid choice: 'guess'"),
        (["simulate", "constant", "--controller", "pid"], "controller: scenario 'constant' needs 'open-loop', found 'pid'"),
        (["simulate", "positioning", "--step-up", "4"], "step_down: expected step_up < step_down < duration"),
    ],
)
def test_simulate_rejects_bad_input(args, match, tmp_path):
    proc = run(*args)
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and match in lines[0]
    assert list(tmp_path.iterdir()) == []
