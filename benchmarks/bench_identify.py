"""Benchmark: ``identify`` without output-error refinement (issue 17), warm.

* ``identify(trace)`` over the EMPS record (24,841 samples at 1 kHz; the synthetic record of
  ``bench_data`` when the file is absent): the bounded fits with and without the Stribeck term,
  the model selection, the pre-sliding fit and the 400-replicate moving-block bootstrap.
* ``identify`` over the slow synthetic Stribeck log of the tests (48,000 samples at 2 kHz, the
  Stribeck term kept: its columns are decimated at every ``vs`` the fit tries).
* Reference, same run: the IDIM-LS alone (``n_boot=0``, ``stribeck='off'``), the procedure before
  issue 17, so the ratio is the price of the bounded fit and the intervals.

Target (issue 17): under 1 s warm.
"""

from __future__ import annotations

import sys
from pathlib import Path

from _timing import best_of
from bench_data import _trace

from obsdesign.data import Trace, identify

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))


def run() -> list[dict]:
    from _axis_logs import DT, GAIN, axis_log

    trace, label = _trace()
    log = axis_log("slow")
    slow = Trace(t=log["t"], position=log["x"], force=log["i"] * GAIN, sample_time=DT, source="slow")
    rows = []
    for tr, name in ((trace, label), (slow, "slow Stribeck log")):
        identify(tr)  # warm-up (SciPy imports)
        whole = best_of(lambda: identify(tr), 5)
        plain = best_of(lambda: identify(tr, n_boot=0, stribeck="off"), 5)
        rows.append({"benchmark": f"identify() over the {name} ({tr.samples} samples, warm)",
                     "value": f"{whole * 1e3:.0f} ms", "reference": f"IDIM-LS alone: {plain * 1e3:.0f} ms",
                     "ratio": f"{whole / plain:.1f}", "target": "< 1 s", "ok": whole < 1.0})
    return rows


if __name__ == "__main__":
    for row in run():
        print(f"| {row['benchmark']} | {row['value']} | {row['reference']} | {row['ratio']} | {row['target']} | "
              f"{'yes' if row['ok'] else 'NO'} |")
