"""Benchmark: the closed loop with each plant friction model against the paper's plant (issue 19).

The comparison (``obsdesign compare``) spends most of its time in plants of the friction models of
:mod:`obsdesign.friction` (LuGre, Dahl, GMS: 10 Heun substeps a sample, each two force evaluations
and an advance). Each row is the whole ``simulate()`` of the comparison's scenarios (``vcm``, paper
observer) with one plant, in CPU time (``time.process_time``, best of 5), per sample, and its ratio to
the paper's plant in the same run.

``python benchmarks/bench_friction_plants.py [--baseline DIR]``: ``--baseline`` runs the same measurement
with another source tree first on ``PYTHONPATH`` (in a fresh process, its own numba cache) and adds the
ratio of this tree to it per plant and scenario; the outputs of both are compared array for array.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time

PLANTS = ("paper", "lugre", "dahl", "gms")


def measure(repeats: int = 5) -> dict:
    """``{plant: {scenario: [ns per sample, digest of the outputs]}}`` of this interpreter's obsdesign."""
    import numpy as np

    import obsdesign as od
    from obsdesign.comparison import SCENARIOS, plant_config
    from obsdesign.sim.simulate import simulate

    cfg = od.load_preset("vcm")
    out: dict = {}
    for plant in PLANTS:
        pc = plant_config(cfg, plant)
        out[plant] = {}
        for name, (spec, duration) in SCENARIOS.items():
            simulate(cfg, spec, plant=pc, duration=duration, seed=0)  # numba cache, memory
            best = float("inf")
            for _ in range(repeats):
                t0 = time.process_time()
                res = simulate(cfg, spec, plant=pc, duration=duration, seed=0)
                best = min(best, time.process_time() - t0)
            arrays = b"".join(np.ascontiguousarray(getattr(res, k)).tobytes()
                              for k in ("x", "v", "f", "v_hat", "f_hat", "f_hat_filtered", "u"))
            out[plant][name] = [best / len(res.t) * 1e9, hashlib.sha256(arrays).hexdigest()]
    return out


def run(baseline: str | None = None) -> list[dict]:
    this = measure()
    base = None
    if baseline:
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "PYTHONPATH": baseline, "NUMBA_CACHE_DIR": cache}
            code = f"import sys; sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r}); " \
                   "import json, bench_friction_plants as b; print(json.dumps(b.measure()))"
            text = subprocess.run([sys.executable, "-c", code], env=env, cwd=cache, check=True,
                                  capture_output=True, text=True).stdout
            base = json.loads(text.splitlines()[-1])
    rows = []
    for plant in PLANTS:
        for name, (ns, digest) in this[plant].items():
            paper = this["paper"][name][0]
            row = {"benchmark": f"simulate, {plant} plant, {name}", "value": f"{ns:.0f} ns/sample",
                   "reference": f"paper plant: {paper:.0f} ns/sample", "ratio": f"{ns / paper:.2f}", "target": "",
                   "ok": True}
            if base is not None:
                b_ns, b_digest = base[plant][name]
                row["reference"] += f"; baseline tree {b_ns:.0f} ns/sample, this / baseline {ns / b_ns:.2f}"
                row["ok"] = digest == b_digest
                row["target"] = "same outputs as the baseline"
            rows.append(row)
    return rows


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", metavar="DIR", help="also measure the source tree DIR (before)")
    for r in run(ap.parse_args().baseline):
        print(r)
