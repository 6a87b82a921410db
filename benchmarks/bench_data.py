"""Benchmark: the observer over measured data (``obsdesign.data.observe``).

* ``observe(cfg, trace)`` over the EMPS record (24,841 samples at 1 kHz; a synthetic
  record of the same length when the file is absent: set ``OBSDESIGN_EMPS``), warm,
  best of 7: the whole call (observer design, filter arrays, the kernel, the reversal
  count of the trace) and the kernel ``observe_loop`` alone.
* Reference, same run: ``kernel.run_loop`` of the identified config over a ``simulate``
  run of equal length (24,841 samples, PID + observer): the whole closed-loop sample
  (plant substeps, PID, observer step) per sample. The observer step is one part of it, so
  the offline kernel must not cost more per sample.

Target (issue 10): the whole ``observe`` call under 0.1 s after warm-up.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from _timing import best_of

import obsdesign as od
from obsdesign.data import Trace, identify, load_trace, observe
from obsdesign.sampled import sampled_controller
from obsdesign.sampled.kernel import observe_loop
from obsdesign.sim import kernel

HERE = Path(__file__).resolve().parent
EMPS = Path(os.environ.get("OBSDESIGN_EMPS") or HERE.parents[1] / "shared" / "data" / "emps" / "DATA_EMPS.mat")
N = 24_841


def _trace() -> tuple[Trace, str]:
    if EMPS.is_file():
        return load_trace(EMPS, position="qm", input="vir", time="t", input_gain=35.15065188), "EMPS record"
    t = np.arange(N) * 1e-3
    x = 0.05 * np.sin(2 * np.pi * 0.2 * t)
    v = np.gradient(x, 1e-3)
    force = 95.0 * np.gradient(v, 1e-3) + 200.0 * v + 20.0 * np.sign(v) - 3.0
    return Trace(t=t, position=x, force=force, sample_time=1e-3, source="synthetic"), "synthetic record"


def _best(fn) -> float:
    return best_of(fn, 7)


def run() -> list[dict]:
    trace, label = _trace()
    cfg = identify(trace).to_config(name="bench")
    observe(cfg, trace)  # warm-up (JIT from the cache, python-control imports)
    whole = _best(lambda: observe(cfg, trace))

    obs, est, _ = sampled_controller(cfg).kernel_args()
    x, u = np.ascontiguousarray(trace.position), np.ascontiguousarray(trace.force - cfg.plant.G)
    out = [np.empty(trace.samples) for _ in range(4)]
    k_true = np.zeros(trace.samples)

    def loop():
        observe_loop(obs, est, x, u, k_true, *out)

    loop()
    offline = _best(loop)

    sim = od.sim.prepare(cfg, od.sim.Positioning(step_size=1e-3, step_up=1.0, step_down=12.0),
                         controller="pid+observer", duration=trace.samples * cfg.observer.dt)
    sim_out = kernel.empty_outputs(sim.n_samples)
    sim_args = sim.kernel_args()
    kernel.run_loop(*sim_args, sim_out)
    closed = _best(lambda: kernel.run_loop(*sim_args, sim_out))
    ns_off, ns_closed = offline / trace.samples * 1e9, closed / sim.n_samples * 1e9
    return [
        {"benchmark": f"observe() over the {label} ({trace.samples} samples, warm, whole call)",
         "value": f"{whole * 1e3:.1f} ms", "reference": f"simulate kernel, {sim.n_samples} samples: {closed * 1e3:.1f} ms",
         "ratio": f"{whole / closed:.2f}", "target": "< 100 ms", "ok": whole < 0.1},
        {"benchmark": "  of which the kernel observe_loop", "value": f"{offline * 1e3:.2f} ms ({ns_off:.0f} ns/sample)",
         "reference": f"closed-loop sample (plant, PID, observer): {ns_closed:.0f} ns", "ratio": f"{ns_off / ns_closed:.2f}",
         "target": "<= 1 (a part of the closed-loop sample)", "ok": ns_off <= ns_closed},
    ]


if __name__ == "__main__":
    for row in run():
        print(f"| {row['benchmark']} | {row['value']} | {row['reference']} | {row['ratio']} | {row['target']} | "
              f"{'yes' if row['ok'] else 'NO'} |")
