"""Run every benchmark and print (or, with --write, record) a Markdown table.

Usage: ``python benchmarks/run.py [--write]`` (``make bench`` runs it with --write).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_certificate  # noqa: E402
import bench_cli  # noqa: E402
import bench_compare  # noqa: E402
import bench_data  # noqa: E402
import bench_derive  # noqa: E402
import bench_friction_plants  # noqa: E402
import bench_identify  # noqa: E402
import bench_mcu  # noqa: E402
import bench_report  # noqa: E402
import bench_sim  # noqa: E402
import bench_sweep  # noqa: E402
import bench_tune  # noqa: E402

SUITES = {
    "Symbolic derivation (issue 2)": bench_derive.run,
    "Closed-loop simulator (issue 4)": bench_sim.run,
    "Friction-model plants (issue 19)": bench_friction_plants.run,
    "Sweeps (issue 6)": bench_sweep.run_all,
    "Measured data (issue 10)": bench_data.run,
    "Identification (issue 17)": bench_identify.run,
    "Command-line start-up (issue 13)": bench_cli.run,
    "Estimator comparison (issue 11)": bench_compare.run,
    "Stability certificate (issue 18)": bench_certificate.run,
    "Tuning (issue 18)": bench_tune.run,
    "Report (issue 19)": bench_report.run,
    "Controller on a Cortex-M4 (issue 34)": bench_mcu.run,
}


#: The section of RESULTS.md that benchmarks/parity.py owns.
PARITY_HEADING = "## Controller export parity (issue 16)"


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, {platform.system()} {platform.machine()}"


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", action="store_true", help="write benchmarks/RESULTS.md")
    args = ap.parse_args()
    lines = ["# Benchmark results", "",
             f"Recorded {datetime.date.today().isoformat()} on: {machine()}.", "",
             "Re-run with `make bench`. Each row compares against a reference measured in the same run.", ""]
    failed = False
    for title, suite in SUITES.items():
        rows = suite()
        lines += [f"## {title}", "", "| benchmark | value | reference (same run) | ratio | target | met |",
                  "|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['benchmark']} | {r['value']} | {r['reference']} | {r['ratio']} | {r['target']} | {'yes' if r['ok'] else 'NO'} |")
            failed |= not r["ok"]
        lines.append("")
    text = "\n".join(lines)
    print(text)
    if args.write:
        # the parity section is written by benchmarks/parity.py (an hour with Octave): kept as it is
        old = (HERE / "RESULTS.md").read_text() if (HERE / "RESULTS.md").exists() else ""
        kept = old[old.index(PARITY_HEADING):] if PARITY_HEADING in old else ""
        (HERE / "RESULTS.md").write_text(text + ("\n" + kept if kept else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
