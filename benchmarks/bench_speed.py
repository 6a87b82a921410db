"""Benchmark: the three speed ratios of issue 37 (points 1, 2 and 5), each against a reference of the same run.

1. ``obsdesign report --preset vcm -o report.html`` (the Makefile's ``report`` target) warm, against
   ``python -c "import numpy"``: at most 40x. Optionally (``--cold``) the first report of a fresh checkout:
   empty numba cache, empty result memo, empty matplotlib cache (``NUMBA_CACHE_DIR``,
   ``OBSDESIGN_CACHE_DIR``, ``MPLCONFIGDIR`` set to empty folders): under 90 s on 2 cores.
2. The README's ``obsdesign simulate positioning --controller pid+observer --plot pos.svg`` (with ``--json``
   to read the kernel's own wall time ``sim_wall_s``): the whole command minus the kernel, against the kernel:
   at most 5x. The overhead is split into what a fresh process pays before any of the package's code runs:
   numba's floor (a process calling one cached ``@njit`` function) and matplotlib's (``import
   matplotlib.figure``: the command draws without pyplot), both measured in the same rounds.
3. The simulator's kernel (``obsdesign.sim.kernel.run_loop``, 60 s of ``tracking`` on ``vcm`` at 10 kHz,
   PID + observer, warm) against the plain C loop of the same work (``benchmarks/c/closed_loop.c``, gcc -O2,
   called through ctypes; its outputs checked against the kernel's): at most 1.1x.

Method (the machine may be shared): every measurement alternates with its reference in rounds
(reference, measurement, reference, ...), so a passing load falls on both; each ratio is the median over
rounds of the round's own ratio, and the spread (smallest and largest round) is printed beside it. The load
average (1 minute) before and after is printed with every row.

``python benchmarks/bench_speed.py [--rounds N] [--cold] [--baseline DIR]``; ``python benchmarks/run.py --only 37 --write``
runs it and records its section in ``benchmarks/RESULTS.md``.
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
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

#: Issue 37's targets.
REPORT_RATIO = 40.0
FIRST_REPORT_S = 90.0
SIMULATE_OVERHEAD_RATIO = 5.0
KERNEL_RATIO = 1.1

#: How the rows were measured (printed under the table in RESULTS.md).
METHOD = ("Method: each measurement alternates with its reference in rounds (`python -c \"import numpy\"` "
          "before and after each report and each simulate; C, numba, C for the kernel), fresh processes for "
          "the commands (warm numba cache and result memo: one untimed run first), CPU time of one process "
          "for the kernel against C; each ratio is the median of the rounds' own ratios, the spread of the "
          "rounds beside it; the load average is read before and after. The simulate overhead is split "
          "into numba's floor (a fresh process calling one cached `@njit` function, minus `import numpy`) "
          "and `import matplotlib.figure` (the command draws on a plain Figure, without pyplot), measured in "
          "the same rounds; the first report's CPU time is the user + system time of the command and its "
          "helper process. `python benchmarks/run.py --only 37 "
          "--write` re-runs it and replaces this section (with `OBSDESIGN_BENCH_COLD=1` the first report of a fresh "
          "checkout too: empty numba cache, memo and matplotlib cache; `python benchmarks/bench_speed.py --cold` "
          "prints it).")

NUMPY = [sys.executable, "-c", "import numpy"]
CLI = [sys.executable, "-m", "obsdesign"]
REPORT = ["report", "--preset", "vcm", "-o", "report.html"]
SIMULATE = ["simulate", "positioning", "--controller", "pid+observer", "--plot", "pos.svg", "--json"]
#: What ``simulate --plot`` imports of matplotlib (a plain Figure, no pyplot: obsdesign.report.figures).
MPL = [sys.executable, "-c", "import matplotlib; matplotlib.use('Agg'); import matplotlib.figure"]
NUMBA_FLOOR = """
from numba import njit


@njit(cache=True)
def one(x):
    return x + 1.0
"""


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def _wall(argv: list[str], cwd: str, env: dict | None = None, cpu: list | None = None) -> tuple[float, str]:
    """Wall time and stdout of a command; its CPU time (user + system, its children included: the
    report's helper) appended to ``cpu`` when given."""
    c0 = _children_cpu()
    t0 = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, cwd=cwd, env=env)
    wall = time.perf_counter() - t0
    if cpu is not None:
        cpu.append(_children_cpu() - c0)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} exited {proc.returncode}: {proc.stderr.strip()[-500:]}")
    return wall, proc.stdout


def _numpy(cwd: str, n: int = 3) -> float:
    """The reference: the median of ``n`` fresh ``python -c "import numpy"``."""
    return statistics.median(_wall(NUMPY, cwd)[0] for _ in range(n))


def _load() -> float:
    return os.getloadavg()[0]


def _loadavg() -> str:
    """The 1, 5 and 15 minute load averages (``/proc/loadavg``)."""
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def _spread(values: list[float]) -> str:
    return f"{min(values):.2f}-{max(values):.2f}"


def report_rows(rounds: int, cold: bool, baseline: str | None = None) -> list[dict]:
    """Issue 37 point 1: the warm report against ``import numpy``, alternating; the cold one optionally;
    with ``baseline`` (a source tree put first on ``PYTHONPATH``) that tree's report in the same rounds."""
    rows = []
    base_env = {**os.environ, "PYTHONPATH": baseline} if baseline else None
    with tempfile.TemporaryDirectory() as tmp:
        load0 = _loadavg()
        if cold:
            with tempfile.TemporaryDirectory() as empty:
                env = {**os.environ, **{k: os.path.join(empty, k) for k in ("NUMBA_CACHE_DIR", "OBSDESIGN_CACHE_DIR",
                                                                           "MPLCONFIGDIR")}}
                ref = _numpy(tmp)
                cpu: list = []
                first = _wall(CLI + REPORT, tmp, env, cpu)[0]
                ref = (ref + _numpy(tmp)) / 2
            rows.append({"benchmark": "first `obsdesign report --preset vcm` (empty numba cache, memo and matplotlib "
                                      "cache: a fresh checkout's `make report`)",
                         "value": f"{first:.1f} s (CPU {cpu[0]:.1f} s, both processes)",
                         "reference": f"import numpy {ref:.3f} s; load {load0} before, {_loadavg()} after",
                         "ratio": f"{first / ref:.0f}", "target": f"< {FIRST_REPORT_S:g} s", "ok": first < FIRST_REPORT_S})
        _wall(CLI + REPORT, tmp)  # warm: numba cache, memo, file system
        if baseline:
            _wall(CLI + REPORT, tmp, base_env)
        load0 = _load()
        ratios, walls, refs, base = [], [], [], []
        for _ in range(rounds):
            ref = _numpy(tmp)
            wall = _wall(CLI + REPORT, tmp)[0]
            if baseline:
                base.append(_wall(CLI + REPORT, tmp, base_env)[0])
            ref = (ref + _numpy(tmp)) / 2
            ratios.append(wall / ref)
            walls.append(wall)
            refs.append(ref)
        ratio = statistics.median(ratios)
        rows.append({"benchmark": f"`obsdesign report --preset vcm -o report.html` warm ({rounds} rounds, each "
                                  "between two references)",
                     "value": f"{statistics.median(walls):.2f} s ({_spread(walls)})",
                     "reference": f"import numpy {statistics.median(refs):.3f} s ({_spread(refs)}); "
                                  f"round ratios {_spread(ratios)}; load {load0:.1f}-{_load():.1f}",
                     "ratio": f"{ratio:.1f}", "target": f"<= {REPORT_RATIO:g}", "ok": ratio <= REPORT_RATIO})
        if baseline:
            b_ratio = statistics.median(b / r for b, r in zip(base, refs))
            rows.append({"benchmark": f"  the same report of the tree before ({baseline}), same rounds",
                         "value": f"{statistics.median(base):.2f} s ({_spread(base)})",
                         "reference": f"import numpy, the same references; this tree / before: "
                                      f"{statistics.median(w / b for w, b in zip(walls, base)):.2f}",
                         "ratio": f"{b_ratio:.1f}", "target": "", "ok": True})
    return rows


def simulate_rows(rounds: int) -> list[dict]:
    """Issue 37 point 2: the README's simulate, wall minus kernel against the kernel; the floors beside."""
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "numba_floor.py").write_text(NUMBA_FLOOR)
        floor_cmd = [sys.executable, "-c", "import numba_floor; numba_floor.one(1.0)"]
        _wall(floor_cmd, tmp)  # fills its cache
        _wall(CLI + SIMULATE, tmp)  # warm
        load0 = _load()
        ratios, overheads, kernels, numba_f, mpl_f, refs, cpus = [], [], [], [], [], [], []
        for _ in range(rounds):
            refs.append(_numpy(tmp))
            wall, out = _wall(CLI + SIMULATE, tmp, cpu=cpus)
            kernel = float(json.loads(out)["sim_wall_s"])
            numba_f.append(_wall(floor_cmd, tmp)[0])
            mpl_f.append(_wall(MPL, tmp)[0])
            overheads.append(wall - kernel)
            kernels.append(kernel)
            ratios.append((wall - kernel) / kernel)
        ratio = statistics.median(ratios)
        over, kern = statistics.median(overheads), statistics.median(kernels)
        ref, nf, mf = statistics.median(refs), statistics.median(numba_f), statistics.median(mpl_f)
        return [
            {"benchmark": "README's `simulate positioning --controller pid+observer --plot pos.svg`: wall minus "
                          f"kernel ({rounds} rounds)",
             "value": f"{over:.3f} s ({_spread(overheads)})",
             "reference": f"its kernel (sim_wall_s) {kern:.3f} s ({_spread(kernels)}); round ratios {_spread(ratios)}; "
                          f"the command's CPU time {statistics.median(cpus):.2f} s; load {load0:.1f}-{_load():.1f}",
             "ratio": f"{ratio:.1f}", "target": f"<= {SIMULATE_OVERHEAD_RATIO:g}", "ok": ratio <= SIMULATE_OVERHEAD_RATIO},
            {"benchmark": "  of the overhead: numba's floor (fresh process, one cached @njit call) / "
                          "`import matplotlib.figure` (what the command imports) / import numpy",
             "value": f"{nf:.3f} / {mf:.3f} / {ref:.3f} s",
             "reference": f"beyond the two floors: {over - (nf - ref) - mf:.3f} s", "ratio": "", "target": "",
             "ok": True},
        ]


def kernel_rows(rounds: int) -> list[dict]:
    """Issue 37 point 2: the numba kernel against the plain C loop of the same work, alternating (C, numba, C).

    CPU time of this process (``time.process_time``): both loops are single-threaded arithmetic, and on a
    shared machine the CPU time is what the loop costs, the wall time also what the scheduler takes away.
    """
    import bench_sim

    loop = bench_sim._inputs(60.0)
    n = len(loop.x_ref)
    lib = bench_sim._c_library()
    load0 = _load()
    bench_sim._numba(loop, 1)  # warm
    clock = time.process_time
    ratios, t_nb, t_c, same = [], [], [], 0.0
    for _ in range(rounds):
        tc, out_c = bench_sim._c(loop, 1, lib, clock)
        tn, out = bench_sim._numba(loop, 1, clock)
        tc = (tc + bench_sim._c(loop, 1, lib, clock)[0]) / 2
        same = max(same, max(float(np.max(np.abs(out_c[k] - out[k])) / max(np.max(np.abs(out[k])), 1e-300))
                             for k in out_c))
        ratios.append(tn / tc)
        t_nb.append(tn)
        t_c.append(tc)
    ratio = statistics.median(ratios)
    ns, ns_c = statistics.median(t_nb) / n * 1e9, statistics.median(t_c) / n * 1e9
    return [{"benchmark": f"numba kernel, 60 s tracking at 10 kHz, vcm, pid+observer, CPU time ({rounds} rounds)",
             "value": f"{ns:.0f} ns/sample", "reference": f"plain C loop (gcc -O2), same work: {ns_c:.0f} ns/sample; "
                                                          f"round ratios {_spread(ratios)}; outputs' max relative "
                                                          f"difference {same:.1e}; load {load0:.1f}-{_load():.1f}",
             "ratio": f"{ratio:.2f}", "target": f"<= {KERNEL_RATIO:g}", "ok": ratio <= KERNEL_RATIO and same < 1e-9}]


def run(rounds: int = 5, cold: bool = False, baseline: str | None = None) -> list[dict]:
    """The rows of issue 37's section of RESULTS.md (``OBSDESIGN_BENCH_BASELINE``: a tree before, for
    the report's before/after row; ``OBSDESIGN_BENCH_COLD=1``: the first report too, as ``--cold``)."""
    baseline = baseline or os.environ.get("OBSDESIGN_BENCH_BASELINE") or None
    cold = cold or os.environ.get("OBSDESIGN_BENCH_COLD") == "1"
    return report_rows(rounds, cold, baseline) + simulate_rows(rounds) + kernel_rows(rounds)


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--cold", action="store_true", help="also the first report (empty caches; minutes)")
    ap.add_argument("--only", choices=("report", "simulate", "kernel"))
    ap.add_argument("--baseline", metavar="DIR", help="also time the report of the source tree DIR (before)")
    opts = ap.parse_args()
    rows = ({"report": lambda: report_rows(opts.rounds, opts.cold, opts.baseline),
             "simulate": lambda: simulate_rows(opts.rounds),
             "kernel": lambda: kernel_rows(opts.rounds)}[opts.only]() if opts.only
            else run(opts.rounds, opts.cold, opts.baseline))
    for row in rows:
        print(row)
