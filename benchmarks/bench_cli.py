"""Benchmark: start-up of the ``obsdesign`` command (issues 13 and 19).

Targets: ``obsdesign --help`` and rejected input answer within 1.5x of ``python -c "import numpy"``
(the parser is built before any heavy import; the reference is measured in the same run,
interleaved, so machine load affects both alike); ``obsdesign check`` (table1, the default)
under 1.5 s warm (after one untimed run, so the file system and numba caches are filled).

Issue 19 contract, ratios to the same reference: ``check --preset vcm`` <= 2.5x, ``pid`` and ``loop``
<= 5x, ``export --format c`` <= 3x; ``simulate positioning`` at most 1.0 s plus the kernel's own
time (its ``sim_wall_s``), shown beside numba's own floor (a fresh process calling one trivial cached
``@njit`` function). Each figure is the median of ``repeats`` fresh processes.

Each command is timed with the result memo (:mod:`obsdesign._memo`, filled by the untimed warm-up
run) and with it off (``OBSDESIGN_CACHE=off``: every number computed, as on a first run).

``python benchmarks/bench_cli.py [--repeats N] [--contract [--baseline DIR]]`` (``--contract``: the issue-19
rows only; ``--baseline DIR`` times the same commands of another source tree in the same loop).
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

COMMANDS = {
    "obsdesign --help": ["--help"],
    "obsdesign check --rho -1 (rejected, exit 2)": ["check", "--rho", "-1"],
    "obsdesign simulate walk (rejected, exit 2)": ["simulate", "walk"],
    "obsdesign --version": ["--version"],
}


#: Issue 19: command -> (arguments, largest ratio to ``python -c "import numpy"``).
CONTRACT = {
    "obsdesign check --preset vcm": (["check", "--preset", "vcm"], 2.5),
    "obsdesign pid": (["pid"], 5.0),
    "obsdesign loop": (["loop"], 5.0),
    "obsdesign export --format c": (["export", "--format", "c", "-o", "{tmp}"], 3.0),
}
SIMULATE = ["simulate", "positioning", "--json"]
#: The floor under any command that runs a numba kernel: a fresh process that calls one trivial
#: ``@njit(cache=True)`` function, loaded from numba's cache (numba's import, its CPU target and the
#: SciPy BLAS check it makes while setting the target up).
NUMBA_FLOOR = """
import numpy as np
from numba import njit


@njit(cache=True)
def one(x):
    return x + 1.0
"""
#: Issue 19: ``simulate positioning`` wall minus its kernel's own time, at most this [s].
SIMULATE_OVERHEAD = 1.0


def _wall(argv: list[str], env: dict | None = None) -> float:
    t0 = time.perf_counter()
    subprocess.run(argv, capture_output=True, text=True, env=env)
    return time.perf_counter() - t0


def _cpu_children() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _timed(argv: list[str], env: dict | None = None) -> tuple[float, float]:
    """Wall time and CPU time (user + system, the child's) of one run: on a loaded machine the CPU
    time is what the command costs, the wall time what the user waits."""
    c0 = _cpu_children()
    wall = _wall(argv, env)
    return wall, _cpu_children() - c0


def _simulate(cli: list[str], env: dict | None = None) -> tuple[float, float, float]:
    """Wall time of ``simulate positioning``, the kernel's own time it reports (``sim_wall_s``), CPU time."""
    c0, t0 = _cpu_children(), time.perf_counter()
    proc = subprocess.run(cli + SIMULATE, capture_output=True, text=True, check=True, env=env)
    wall = time.perf_counter() - t0
    return wall, float(json.loads(proc.stdout)["sim_wall_s"]), _cpu_children() - c0


def contract(repeats: int = 7, baseline: str | None = None) -> list[dict]:
    """The issue-19 rows: each command interleaved with the reference, medians of ``repeats``.

    ``baseline``: a source tree (put first on ``PYTHONPATH``) whose same commands are timed in the
    same loop, for a before/after comparison under the same load.
    """
    numpy_cmd = [sys.executable, "-c", "import numpy"]
    cli = [sys.executable, "-m", "obsdesign"]
    envs = {"": None, "(memo off)": {**os.environ, "OBSDESIGN_CACHE": "off"}}  # obsdesign._memo: warm vs none
    if baseline is not None:
        envs["before"] = {**os.environ, "PYTHONPATH": baseline}
    with tempfile.TemporaryDirectory() as tmp:
        commands = {name: [a.replace("{tmp}", tmp) for a in args] for name, (args, _) in CONTRACT.items()}
        for env in envs.values():
            for args in commands.values():  # warm the file system and numba caches
                _wall(cli + args, env)
            _simulate(cli, env)
        with open(os.path.join(tmp, "numba_floor.py"), "w") as f:
            f.write(NUMBA_FLOOR)
        floor_cmd = [sys.executable, "-c", f"import sys; sys.path.insert(0, {tmp!r}); import numba_floor; "
                                            "numba_floor.one(1.0)"]
        _wall(floor_cmd)  # compiles and fills its cache
        reference, floor = [], []
        times = {(tag, name): [] for tag in envs for name in commands}
        sim = {tag: [] for tag in envs}
        for _ in range(repeats):
            floor.append(_wall(floor_cmd))
            for name, args in commands.items():
                reference.append(_timed(numpy_cmd))
                for tag, env in envs.items():
                    times[tag, name].append(_timed(cli + args, env))
            for tag, env in envs.items():
                sim[tag].append(_simulate(cli, env))
    ref = statistics.median(w for w, _ in reference)
    ref_cpu = statistics.median(c for _, c in reference)
    rows = []
    for (tag, name), values in times.items():
        value, limit = statistics.median(w for w, _ in values), CONTRACT[name][1]
        cpu = statistics.median(c for _, c in values)
        rows.append({"benchmark": f"{name} (issue 19){' ' + tag if tag else ''}", "value": f"{value:.3f} s",
                     "reference": f"python -c 'import numpy': {ref:.3f} s (CPU: {cpu:.2f} s against {ref_cpu:.2f} s, "
                                  f"ratio {cpu / ref_cpu:.2f})",
                     "ratio": f"{value / ref:.2f}", "target": f"<= {limit}", "ok": value <= limit * ref})
    numba_floor = statistics.median(floor)
    rows.append({"benchmark": "numba's own start-up: a fresh process calling one cached @njit function",
                 "value": f"{numba_floor:.3f} s", "reference": f"python -c 'import numpy': {ref:.3f} s",
                 "ratio": f"{numba_floor / ref:.2f}", "target": "", "ok": True})
    for tag, runs in sim.items():
        wall = statistics.median(w for w, _, _ in runs)
        overhead = statistics.median(w - k for w, k, _ in runs)
        kernel = statistics.median(k for _, k, _ in runs)
        cpu = statistics.median(c - k for _, k, c in runs)
        rows.append({"benchmark": f"obsdesign simulate positioning (issue 19): wall minus kernel{' ' + tag if tag else ''}",
                     "value": f"{overhead:.3f} s",
                     "reference": f"wall {wall:.3f} s, kernel (sim_wall_s) {kernel:.3f} s, CPU minus kernel {cpu:.2f} s; "
                                  f"beyond numba's own start-up {wall - kernel - numba_floor:.3f} s",
                     "ratio": "", "target": f"<= {SIMULATE_OVERHEAD} s", "ok": overhead <= SIMULATE_OVERHEAD})
    return rows


def run(repeats: int = 7) -> list[dict]:
    numpy_cmd = [sys.executable, "-c", "import numpy"]
    cli = [sys.executable, "-m", "obsdesign"]
    for argv in (numpy_cmd, cli + ["--help"], cli + ["check"]):
        _wall(argv)  # warm the file system cache
    times = {name: [] for name in COMMANDS}
    reference, check = [], []
    for _ in range(repeats):
        for name, args in COMMANDS.items():
            reference.append(_wall(numpy_cmd))
            times[name].append(_wall(cli + args))
        check.append(_wall(cli + ["check"]))
    ref = statistics.median(reference)
    rows = []
    for name, values in times.items():
        value = statistics.median(values)
        rows.append({"benchmark": name, "value": f"{value:.3f} s",
                     "reference": f"python -c 'import numpy': {ref:.3f} s", "ratio": f"{value / ref:.2f}",
                     "target": "<= 1.5", "ok": value <= 1.5 * ref})
    value = statistics.median(check)
    rows.append({"benchmark": "obsdesign check (table1, warm)", "value": f"{value:.2f} s",
                 "reference": f"python -c 'import numpy': {ref:.3f} s", "ratio": f"{value / ref:.1f}",
                 "target": "< 1.5 s", "ok": value < 1.5})
    return rows + contract(repeats)


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--contract", action="store_true", help="only the issue-19 rows")
    ap.add_argument("--baseline", metavar="DIR", help="with --contract: also time the source tree DIR (before)")
    opts = ap.parse_args()
    rows = contract(opts.repeats, opts.baseline) if opts.contract else run(opts.repeats)
    for row in rows:
        print(row)
