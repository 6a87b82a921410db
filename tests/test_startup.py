"""Imports by need (issue 19): which heavy modules each command loads.

Each command runs in a fresh interpreter (as ``python -m obsdesign``) and reports which of the heavy
modules ended up in ``sys.modules``. The expected sets say what the command computes with:
SymPy only to print symbols (derive, the LaTeX export), python-control where a margin, a
transfer or a Kalman gain is computed (it imports matplotlib itself), SciPy where an optimiser, a
Lyapunov solver or an integral runs (the search of the stability certificate that ``check``
prints; ``export`` and ``simulate``, which print only whether it holds, search only when no
Lyapunov solution of the ends verifies, as for table1's rho = 1.02; numba imports SciPy too),
numba where a kernel runs.

Each command runs twice with its own empty memo folder (:mod:`obsdesign._memo`): the first run
computes and must import what it computes with; the second finds the certificate's searched
Lyapunov matrix, python-control's loop numbers and the noise RMS values on disk and must not import SciPy or
python-control for them (the outputs of both runs are equal).
"""

from __future__ import annotations

import gc
import os
import re
import subprocess
import sys

import pytest

# pint and the log formats' libraries: only a command that reads a log imports them (issue 40)
HEAVY = ("sympy", "control", "scipy", "numba", "matplotlib", "dask", "pint", "pyarrow", "nptdms", "asammdf", "h5py")

CONTROL = {"control", "scipy", "matplotlib"}  # python-control imports SciPy and matplotlib itself
#: name -> (arguments, modules of the first run, of the second run when they differ).
CASES = {
    "check": (["check", "--preset", "vcm"], CONTROL, set()),  # the PID loop's margins beside the verdicts
    "check --json": (["check", "--preset", "table1", "--json"], CONTROL, set()),
    "pid": (["pid", "--preset", "vcm"], CONTROL, set()),
    "loop": (["loop", "--preset", "vcm"], CONTROL, set()),
    "noise": (["noise", "--preset", "vcm"], CONTROL, set()),
    "derive": (["derive", "--variant", "static"], {"sympy"}),
    "derive --format json": (["derive", "--format", "json"], {"sympy"}),
    "export --format c": (["export", "--format", "c", "--preset", "vcm", "-o", "{tmp}"], set()),
    "export --format octave": (["export", "--format", "octave", "--preset", "vcm", "-o", "{tmp}"], set()),
    "export --format js": (["export", "--format", "js", "--preset", "vcm", "-o", "{tmp}"], set()),
    "export --format latex": (["export", "--format", "latex", "--preset", "vcm", "-o", "{tmp}"], {"sympy"}),
    # table1's certificate is tight (rho = 1.02): no Lyapunov solution of the ends verifies, the search runs
    "export --format c --preset table1": (["export", "--format", "c", "--preset", "table1", "-o", "{tmp}"],
                                          {"scipy"}, set()),
    "simulate positioning": (["simulate", "positioning"], {"numba", "scipy"}),
    "config": (["config", "--preset", "vcm"], set()),
    # the report: SymPy for the derivation, python-control for the figures' responses, scipy.signal for the
    # friction loops' low-pass, all kept; a second report imports only numba (with SciPy) and matplotlib
    "report": (["report", "--preset", "vcm", "--no-circle", "--quiet", "-o", "{tmp}.html"],
               {"sympy", "control", "scipy", "numba", "matplotlib"}, {"scipy", "numba", "matplotlib"}),
    "compare": (["compare", "--preset", "vcm", "--plants", "paper", "--scenarios", "excitation", "--seeds", "1",
                 "--out", "{tmp}"], {"control", "scipy", "numba", "matplotlib"}, {"scipy", "numba", "matplotlib"}),
}

_PROBE = ("import sys, runpy\nsys.argv = ['obsdesign', *sys.argv[1:]]\ntry:\n"
          "    runpy.run_module('obsdesign', run_name='__main__')\nexcept SystemExit as e:\n    code = e.code\n"
          "else:\n    code = 0\n"
          f"print('HEAVY', code, ','.join(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)\n")


#: Cases that repeat what another case shows (the same modules), and the two longest (SymPy's derivation,
#: numba's kernels: 4 s each): in ``make test`` only.
SLOW = {"check --json", "noise", "derive --format json", "export --format octave", "export --format js",
        "export --format latex", "export --format c --preset table1", "derive", "simulate positioning", "report",
        "compare"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in CASES])
def test_command_imports_only_what_it_computes_with(name, tmp_path):
    args, *expected = CASES[name]
    env = {**os.environ, "OBSDESIGN_CACHE_DIR": str(tmp_path / "memo")}
    outputs = []
    for run, want in enumerate([expected[0], expected[-1]]):
        argv = [a.replace("{tmp}", str(tmp_path / f"out{run}")) for a in args]
        proc = subprocess.run([sys.executable, "-c", _PROBE, *argv], capture_output=True, text=True, timeout=600,
                              env=env)
        line = [ln for ln in proc.stderr.splitlines() if ln.startswith("HEAVY ")][-1]
        _, code, loaded = (line.split(" ", 2) + [""])[:3]
        assert code == "0", proc.stderr
        assert set(filter(None, loaded.split(","))) == want, f"{name}, run {run + 1}: {loaded}"
        text = proc.stdout.replace(str(tmp_path / f"out{run}"), "OUT")
        outputs.append(re.sub(r"(wall\S*:?\s*)[0-9.e+-]+", r"\1T", text))  # wall times differ
    assert outputs[0] == outputs[1]


def test_the_program_exits_with_main_s_status_and_its_heap_frozen():
    """``python -m obsdesign`` (and the ``obsdesign`` script, :func:`obsdesign.cli.run`) exits with the status
    of :func:`obsdesign.cli.main` after :func:`gc.freeze`, so the interpreter's last collections skip the run's
    objects; in-process callers of ``main`` keep a collectable heap."""
    probe = ("import gc, sys, runpy\nsys.argv = ['obsdesign', *sys.argv[1:]]\ntry:\n"
             "    runpy.run_module('obsdesign', run_name='__main__')\nexcept SystemExit as e:\n"
             "    print('EXIT', e.code, gc.get_freeze_count() > 0)\n")
    for args, status in ((["config", "--preset", "vcm"], 0), (["check", "--rho", "-1"], 2)):
        proc = subprocess.run([sys.executable, "-c", probe, *args], capture_output=True, text=True, timeout=600)
        assert proc.stdout.splitlines()[-1] == f"EXIT {status} True", proc.stdout + proc.stderr
    from obsdesign.cli import main

    assert main(["--version"]) == 0 and gc.get_freeze_count() == 0


@pytest.mark.slow  # a fresh interpreter and the kernel from numba's cache (4 s)
def test_simulate_plot_draws_without_pyplot(tmp_path):
    """``simulate --plot`` (the README's example) draws its trace figure on a plain matplotlib Figure: pyplot
    (its backend registry, a figure manager per figure) is not imported (issue 37)."""
    probe = _PROBE.replace("print('HEAVY'", "print('PYPLOT', 'matplotlib.pyplot' in sys.modules, file=sys.stderr)"
                                            "\nprint('HEAVY'")
    out = tmp_path / "pos.svg"
    proc = subprocess.run([sys.executable, "-c", probe, "simulate", "positioning", "--controller", "pid+observer",
                           "--plot", str(out)], capture_output=True, text=True, timeout=600,
                          env={**os.environ, "OBSDESIGN_CACHE_DIR": str(tmp_path / "memo")})
    assert "HEAVY 0 " in proc.stderr and "matplotlib" in proc.stderr, proc.stderr
    assert "PYPLOT False" in proc.stderr, proc.stderr
    assert out.read_text().startswith("<?xml") and "</svg>" in out.read_text()
