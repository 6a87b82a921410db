import json
import subprocess
import sys

import pytest

from obsdesign.cli import main


def run(*args):
    return subprocess.run([sys.executable, "-m", "obsdesign", *args], capture_output=True, text=True)


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
