"""Capture the stdout, stderr, exit status and written files of a fixed set of CLI calls.

Used to show that a change leaves every output byte-identical (issue 19, "outputs unchanged"):

    PYTHONPATH=/path/to/old  python tools/capture_outputs.py /tmp/before
    PYTHONPATH=/path/to/new  python tools/capture_outputs.py /tmp/after
    diff -r /tmp/before /tmp/after

Each case gets a folder ``<out>/<name>/`` holding ``stdout``, ``stderr``, ``status`` and the files the
command wrote (its ``-o``/``--out`` target). Paths of the temporary folder are replaced by ``<OUT>``.
Each command runs in its case's folder: ``python -m`` puts the working directory first on ``sys.path``,
so a run from inside a source tree would import that tree's package instead of ``PYTHONPATH``'s.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

CASES: dict[str, list[str]] = {}
for preset in ("vcm", "table1"):
    CASES[f"check-{preset}"] = ["check", "--preset", preset]
    CASES[f"check-{preset}-json"] = ["check", "--preset", preset, "--json"]
    CASES[f"pid-{preset}"] = ["pid", "--preset", preset]
    CASES[f"pid-{preset}-json"] = ["pid", "--preset", preset, "--json"]
    CASES[f"loop-{preset}"] = ["loop", "--preset", preset]
    CASES[f"loop-{preset}-json"] = ["loop", "--preset", preset, "--json"]
    CASES[f"noise-{preset}"] = ["noise", "--preset", preset]
    CASES[f"noise-{preset}-json"] = ["noise", "--preset", preset, "--json"]
    for fmt in ("latex", "python", "c", "octave", "js"):
        CASES[f"export-{fmt}-{preset}"] = ["export", "--format", fmt, "--preset", preset, "-o", "{out}"]
    CASES[f"export-controller-c-{preset}"] = ["export", "--format", "c", "--what", "controller",
                                             "--preset", preset, "-o", "{out}"]
for variant in ("lag", "static"):
    CASES[f"derive-{variant}"] = ["derive", "--variant", variant]
CASES["check-vcm-rho098"] = ["check", "--preset", "vcm", "--rho", "0.98"]
CASES["check-table1-lag-json"] = ["check", "--preset", "table1", "--variant", "lag", "--json"]
CASES["simulate-positioning"] = ["simulate", "positioning"]
CASES["simulate-positioning-json"] = ["simulate", "positioning", "--json", "--out", "{out}/run.npz"]
CASES["simulate-excitation-json"] = ["simulate", "excitation", "--json", "--duration", "0.5"]
CASES["simulate-tracking-kalman-json"] = ["simulate", "tracking", "--estimator", "kalman", "--json",
                                          "--duration", "0.5"]
CASES["config-vcm"] = ["config", "--preset", "vcm"]
# the metrics of many runs (step metrics on a sweep's rows, the comparison's settling times and overshoots)
CASES["sweep-positioning"] = ["sweep", "--scenario", "positioning", "--vary", "rho=1.5:4:3", "--uncertain",
                              "Cf=0.3:0.4", "--samples", "2", "--duration", "4", "--workers", "1", "--out", "{out}/sw"]
CASES["sweep-tracking"] = ["sweep", "--scenario", "tracking", "--vary", "rho=1.5:4:2", "--duration", "2",
                           "--workers", "1", "--out", "{out}/sw"]
CASES["compare-vcm"] = ["compare", "--preset", "vcm", "--seeds", "1", "--workers", "1", "--out", "{out}/cmp", "--json"]
# issue 17, the axis's units: the other controller exports, the friction table and the report of a preset
for fmt in ("python", "octave", "js"):
    CASES[f"export-controller-{fmt}-vcm"] = ["export", "--format", fmt, "--what", "controller", "--preset", "vcm",
                                             "-o", "{out}"]
for fmt in ("c", "python"):
    CASES[f"export-friction-table-{fmt}-vcm"] = ["export", "--format", fmt, "--what", "friction-table",
                                                 "--preset", "vcm", "--motor-constant", "3.28", "-o", "{out}"]
CASES["config-table1"] = ["config", "--preset", "table1"]
CASES["report-vcm"] = ["report", "--preset", "vcm", "--no-circle", "--quiet", "-o", "{out}/report.html"]
# issue 17, identify's default cut-off: the EMPS record ({emps}, skipped where it is missing) and a log given by
# OBSDESIGN_CAPTURE_LOG (a CSV with columns t, x, u in SI units: e.g. a 10 kHz closed-loop record)
EMPS = os.environ.get("OBSDESIGN_EMPS", str(Path(__file__).resolve().parents[2] / "shared/data/emps/DATA_EMPS.mat"))
_EMPS_COLS = ["--position", "qm", "--input", "vir", "--time", "t", "--input-gain", "35.15065188", "--bootstrap", "50"]
CASES["identify-emps-json"] = ["identify", "{emps}", *_EMPS_COLS, "--json", "-o", "{out}/emps.toml"]
CASES["identify-emps-filter-hz"] = ["identify", "{emps}", *_EMPS_COLS, "--filter-hz", "50"]
CASES["identify-log-json"] = ["identify", "{log}", "--position", "x", "--input", "u", "--time", "t", "--bootstrap", "50",
                              "--json", "-o", "{out}/log.toml"]


def main(out: str, only: list[str]) -> None:
    root = Path(out)
    for name, args in CASES.items():
        if only and name not in only:
            continue
        folder = root / name
        files = folder / "files"
        files.mkdir(parents=True, exist_ok=True)
        log = os.environ.get("OBSDESIGN_CAPTURE_LOG", "")
        if ("{emps}" in args and not Path(EMPS).is_file()) or ("{log}" in args and not log):
            continue
        argv = [a.replace("{out}", str(files)).replace("{emps}", EMPS).replace("{log}", log) for a in args]
        proc = subprocess.run([sys.executable, "-m", "obsdesign", *argv], capture_output=True, text=True,
                              env={**os.environ, "COLUMNS": "100"}, cwd=folder)
        for stream, text in (("stdout", proc.stdout), ("stderr", proc.stderr)):
            (folder / stream).write_text(text.replace(str(files), "<OUT>"))
        (folder / "status").write_text(f"{proc.returncode}\n")
        print(name, proc.returncode, flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
