"""``export --what friction-table``: the table against the feed-forward model written here in closed
form, its reported interpolation error recomputed on a finer grid, the C array compiled, bad input."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

import obsdesign as od
from obsdesign.cli import main
from obsdesign.export.friction_table import friction_table, table_files

CFG = od.load_preset("vcm").override(ff_stribeck=0.15, ff_stribeck_velocity=2e-3, ff_offset=0.01, lookahead=30,
                                     buildup=3e-4)


def _model(v):
    fr = CFG.friction
    return fr.Cf + 0.15 * np.exp(-(v / 2e-3) ** 2) + fr.sigma * v


@pytest.mark.parametrize("points", [5, 10, 20])
def test_reported_error_is_the_interpolation_error(points):
    tab = friction_table(CFG, points=points, v_max=0.05, motor_constant=2.0)
    assert len(tab.velocity) <= points and tab.velocity[0] == 0.0
    assert np.allclose(tab.force, _model(tab.velocity), rtol=1e-13)
    assert np.allclose(tab.current, tab.force / 2.0, rtol=1e-15)
    rng = np.random.default_rng(1)
    v = np.concatenate([np.linspace(0, 0.05, 400001), rng.uniform(0, 0.05, 100000)])
    err = np.max(np.abs(_model(v) - np.interp(v, tab.velocity, tab.force)))
    assert tab.max_error * 0.99 <= err <= tab.max_error * 1.01


def test_more_points_bound_the_error_tighter():
    errors = [friction_table(CFG, points=n, v_max=0.05).max_error for n in (4, 8, 16)]
    assert errors[0] > errors[1] > errors[2] > 0
    # a linear model needs two points and no error
    assert friction_table(od.load_preset("vcm"), points=2).max_error == 0.0


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not installed")
def test_c_array_holds_the_csv_values(tmp_path):
    files = table_files(friction_table(CFG, points=6, v_max=0.05, motor_constant=2.0))
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "m.c").write_text('#include <stdio.h>\n#include "friction_table.h"\nint main(void) { int i; '
                                  'for (i = 0; i < OD_FT_POINTS; i++) printf("%.17g,%.17g,%.17g\\n", OD_FT_VELOCITY[i], '
                                  'OD_FT_FORCE[i], OD_FT_CURRENT[i]); printf("%d %.17g\\n", OD_FT_LOOKAHEAD, '
                                  'OD_FT_BUILDUP); return 0; }\n')
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", "-o", str(tmp_path / "m"), str(tmp_path / "m.c")],
                   check=True, capture_output=True)
    out = subprocess.run([str(tmp_path / "m")], capture_output=True, text=True, check=True).stdout.splitlines()
    c_rows = np.array([[float(x) for x in line.split(",")] for line in out[:-1]])
    csv = np.loadtxt(tmp_path / "friction_table.csv", delimiter=",", skiprows=5)
    assert np.array_equal(c_rows, csv)
    assert out[-1].split() == ["30", "0.00029999999999999997"]


@pytest.mark.parametrize("argv, message", [
    (["--velocities", "0,0.01,0.005"], "velocities: expected strictly increasing"),
    (["--format", "python"], "format: the friction table is written as CSV and a C array"),
    (["--what", "controller", "--points", "5"], "argument --points: applies to --what friction-table only"),
])
def test_cli_bad_input(argv, message, tmp_path, capsys):
    args = ["export", "--what", "friction-table", "--format", "c", "-o", str(tmp_path / "out"), *argv]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not (tmp_path / "out").exists()
