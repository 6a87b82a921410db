"""Benchmark: ``tune`` (issue 18), the vcm preset and an identified-like config, on this machine's cores.

* ``tune(cfg, constraints=Constraints(min_phase_margin_deg=15))`` on ``vcm``, and on ``vcm`` with the PID
  plant matched to the observer's model (``tau = m / sigma``, as an identified config has it), one run each
  (the search is deterministic; the first run includes the imports and the JIT cache);
* reference, same run: one evaluation of the start (objective, certificate, loop), so the ratio says how
  many evaluations' worth the whole search costs.

Target (issue 18): ``tune`` on 2 cores under 60 s.
"""

from __future__ import annotations

import time

import obsdesign as od
from obsdesign.design.tune import Constraints, evaluate, tune


def run() -> list[dict]:
    rows = []
    vcm = od.load_preset("vcm")
    matched = vcm.override(tau=vcm.plant.m / vcm.friction.sigma)
    evaluate(vcm)  # warm-up: imports, the numba cache
    for name, cfg in (("vcm", vcm), ("vcm, tau = m / sigma", matched)):
        t0 = time.perf_counter()
        evaluate(cfg)
        t_eval = time.perf_counter() - t0
        t0 = time.perf_counter()
        res = tune(cfg, constraints=Constraints(min_phase_margin_deg=15.0))
        t = time.perf_counter() - t0
        rows.append({"benchmark": f"tune estimate-error, {name} ({res.evaluations} designs, "
                                  f"{res.before:.4g} -> {res.after:.4g} N)",
                     "value": f"{t:.1f} s", "reference": f"one evaluation of the start: {t_eval * 1e3:.0f} ms",
                     "ratio": f"{t / t_eval:.0f}", "target": "< 60 s", "ok": t < 60.0})
    return rows


if __name__ == "__main__":
    for row in run():
        print(row)
