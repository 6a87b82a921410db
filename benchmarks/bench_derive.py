"""Benchmark: symbolic derivation of both variants in a fresh process.

Target (issue 2): ``derive()`` of both variants in a fresh process under 3 s,
instant when cached. The reference in the same run is a fresh process that only
imports SymPy: the ratio says how much the derivation costs beyond SymPy itself.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time

CHILD_DERIVE = """
import time; t0 = time.perf_counter()
import obsdesign
t1 = time.perf_counter()
obsdesign.derive("lag"); obsdesign.derive("static")
t2 = time.perf_counter()
for _ in range(1000):
    obsdesign.derive("lag")
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, (t3 - t2) / 1000)
"""
CHILD_REFERENCE = "import sympy, numpy"


def _wall(code: str) -> tuple[float, str]:
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return time.perf_counter() - t0, out


def run(repeats: int = 5) -> list[dict]:
    _wall(CHILD_DERIVE)  # warm the file system cache
    derive_wall, reference_wall, inner = [], [], []
    for _ in range(repeats):
        w, out = _wall(CHILD_DERIVE)
        derive_wall.append(w)
        inner.append([float(x) for x in out.split()])
        reference_wall.append(_wall(CHILD_REFERENCE)[0])
    dw, rw = statistics.median(derive_wall), statistics.median(reference_wall)
    imp, der, cached = (statistics.median(col) for col in zip(*inner))
    return [
        {"benchmark": "derive both variants, fresh process (wall)", "value": f"{dw:.2f} s",
         "reference": f"python -c 'import sympy, numpy': {rw:.2f} s", "ratio": f"{dw / rw:.2f}",
         "target": "< 3 s", "ok": dw < 3.0},
        {"benchmark": "  of which import obsdesign", "value": f"{imp:.2f} s", "reference": "", "ratio": "", "target": "", "ok": True},
        {"benchmark": "  of which derive('lag') + derive('static')", "value": f"{der:.2f} s", "reference": "", "ratio": "", "target": "", "ok": True},
        {"benchmark": "derive('lag') cached", "value": f"{cached * 1e6:.2f} us",
         "reference": f"first call: {der:.2f} s", "ratio": f"{cached / der:.1e}", "target": "instant", "ok": cached < 1e-4},
    ]


if __name__ == "__main__":
    for row in run():
        print(row)
