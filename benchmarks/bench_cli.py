"""Benchmark: start-up of the ``obsdesign`` command (issue 13).

Targets: ``obsdesign --help`` and rejected input answer within 1.5x of ``python -c "import numpy"``
(the parser is built before any heavy import; the reference is measured in the same run,
interleaved, so machine load affects both alike); ``obsdesign check`` (table1, the default)
under 1.5 s warm (after one untimed run, so the file system and numba caches are filled).
Each figure is the median of ``repeats`` fresh processes.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time

COMMANDS = {
    "obsdesign --help": ["--help"],
    "obsdesign check --rho -1 (rejected, exit 2)": ["check", "--rho", "-1"],
    "obsdesign simulate walk (rejected, exit 2)": ["simulate", "walk"],
    "obsdesign --version": ["--version"],
}


def _wall(argv: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(argv, capture_output=True, text=True)
    return time.perf_counter() - t0


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
    return rows


if __name__ == "__main__":
    for row in run():
        print(row)
