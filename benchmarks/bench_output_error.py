"""Output-error refinement of s on the EMPS record (issue 17: under 30 s on 2 cores).

Run: ``PYTHONPATH=. python benchmarks/bench_output_error.py /path/to/DATA_EMPS.mat``. Reference in the same
run: ``identify`` of the same record (the static fit the refinement starts from).
"""

from __future__ import annotations

import sys
import time

from obsdesign.data import identify, load_trace
from obsdesign.data.output_error import refine


def main(path: str) -> None:
    tr = load_trace(path, position="qm", input="vir", time="t", input_gain=35.15065188)
    ident = identify(tr)
    t0 = time.perf_counter()
    refine(tr, ident, parameters=("s",))
    first = time.perf_counter() - t0
    for names in (("s",), ("s", "Cf", "offset")):
        best = min(_timed(tr, ident, names) for _ in range(3))
        print(f"refine {','.join(names)}: {best:.3f} s warm (first call with JIT cache load {first:.2f} s)")
    ref = min(_timed_identify(tr) for _ in range(3))
    print(f"identify (reference): {ref:.3f} s")


def _timed(tr, ident, names) -> float:
    t0 = time.perf_counter()
    refine(tr, ident, parameters=names)
    return time.perf_counter() - t0


def _timed_identify(tr) -> float:
    t0 = time.perf_counter()
    identify(tr)
    return time.perf_counter() - t0


if __name__ == "__main__":
    main(sys.argv[1])
