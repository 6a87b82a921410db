"""Run every benchmark and print (or, with --write, record) a Markdown table.

Usage: ``python benchmarks/run.py [--write] [--only TEXT]`` (``make bench`` runs it with --write).
``--only TEXT`` runs the suites whose title contains TEXT (``--only 37``: the speed contract of issue 37:
the report, simulate's overhead and the kernel against C); with ``--write`` their sections of RESULTS.md
are replaced (or added at the end) and the rest of the file is kept.
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
import bench_speed  # noqa: E402
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
    "Speed contract: report, simulate, kernel (issue 37)": bench_speed.run,
}


#: A suite's method, printed under its table.
NOTES = {"Speed contract: report, simulate, kernel (issue 37)": bench_speed.METHOD}

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


def _section(title: str, rows: list[dict]) -> list[str]:
    lines = [f"## {title}", "", f"Recorded {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC on: "
             f"{machine()}; load average {', '.join(f'{x:.1f}' for x in os.getloadavg())} (1, 5, 15 min) at the end.",
             "", "| benchmark | value | reference (same run) | ratio | target | met |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['benchmark']} | {r['value']} | {r['reference']} | {r['ratio']} | {r['target']} | "
                     f"{'yes' if r['ok'] else 'NO'} |")
    return lines + ([""] + [NOTES[title]] if title in NOTES else []) + [""]


def replace_sections(old: str, sections: dict[str, str]) -> str:
    r"""``old`` (RESULTS.md) with each ``## title`` section replaced by its new text, or added at the end
    when it is not there yet.

    >>> replace_sections("# R\n\n## a\n\nold\n\n## b\n\nkept\n", {"a": "## a\n\nnew\n"})
    '# R\n\n## a\n\nnew\n\n## b\n\nkept\n'
    >>> replace_sections("# R\n\n## b\n\nkept\n", {"a": "## a\n\nnew\n"})
    '# R\n\n## b\n\nkept\n\n## a\n\nnew\n'
    """
    text = old
    for title, body in sections.items():
        head = f"## {title}\n"
        if head in text:
            start = text.index(head)
            end = text.find("\n## ", start + len(head))
            text = text[:start] + body.rstrip("\n") + ("\n\n" + text[end + 1:] if end >= 0 else "\n")
        else:
            text = text.rstrip("\n") + "\n\n" + body.rstrip("\n") + "\n"
    return text


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", action="store_true", help="write benchmarks/RESULTS.md")
    ap.add_argument("--only", metavar="TEXT", help="only the suites whose title contains TEXT (e.g. 37)")
    args = ap.parse_args()
    suites = {t: s for t, s in SUITES.items() if args.only is None or args.only in t}
    if not suites:
        ap.error(f"--only: no suite's title contains {args.only!r}; titles: {', '.join(SUITES)}")
    lines = ["# Benchmark results", "",
             f"Recorded {datetime.date.today().isoformat()} on: {machine()}.", "",
             "Re-run with `make bench`. Each row compares against a reference measured in the same run.", ""]
    failed = False
    sections = {}
    for title, suite in suites.items():
        rows = suite()
        section = _section(title, rows)
        sections[title] = "\n".join(section)
        lines += section
        failed |= not all(r["ok"] for r in rows)
    text = "\n".join(lines)
    print(text)
    if args.write:
        old = (HERE / "RESULTS.md").read_text() if (HERE / "RESULTS.md").exists() else ""
        if args.only is not None:
            (HERE / "RESULTS.md").write_text(replace_sections(old, sections))
        else:
            # the parity section is written by benchmarks/parity.py (an hour with Octave): kept as it is
            kept = old[old.index(PARITY_HEADING):] if PARITY_HEADING in old else ""
            (HERE / "RESULTS.md").write_text(text + ("\n" + kept if kept else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
