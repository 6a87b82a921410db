"""Benchmark: the ``cortex-m4f`` controller on its target (issue 34), one command.

``python benchmarks/bench_mcu.py`` prints, for the vcm preset (1 um encoder) on a 1 m stroke (chirp
+-0.5 m, 0.01 -> 0.1 Hz) over 10^6 samples at 10 kHz, recorded by ``simulate``:

* the instructions of each step on an emulated Cortex-M4 (unicorn; arm-none-eabi-gcc -O2, FPv4-SP),
  worst and mean over the whole run; target: worst <= 1,500 (the 10 kHz budget with room for the
  rest of the drive);
* the flash and RAM the step takes (``arm-none-eabi-size``), its state and its stack;
* the friction estimate against the host double controller (``--target host``, bit-exact with
  simulate) fed the same counts: target within 0.1 % of Cf over the run, the estimator for
  monitoring (controller ``pid``); and the compensating controller ``pid+observer``, whose replay
  has the compensation looping back into the estimator's input (no plant to close it), for the record.

Reference, same run: the host controller's step on this machine (ns a sample).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import obsdesign as od
from obsdesign.export import armcheck
from obsdesign.export.controller import controller_files
from obsdesign.export.mcu import mcu_controller_files
from obsdesign.loop.scenarios import Chirp

STEPS = 1_000_000
STROKE = Chirp(f0=0.01, f1=0.1, peak_velocity=2 * np.pi * 0.1 * 0.5)  # amplitude 0.5 m: a 1 m stroke


def _case(cfg, controller, folder: Path, res):
    q = cfg.sensor.quantization
    x_ref = np.rint(res.x_ref / q).astype(np.int32)
    x_meas = np.rint(res.x_meas / q).astype(np.int32)
    arm = armcheck.build(mcu_controller_files(cfg, controller=controller), folder / "arm")
    t0 = time.perf_counter()
    run = armcheck.emulate(arm, x_ref, x_meas, count=True)
    t_emu = time.perf_counter() - t0
    t0 = time.perf_counter()
    host = armcheck.host_run(controller_files(cfg, "c", controller=controller), x_ref * q, x_meas * q, folder / "host")
    t_host = time.perf_counter() - t0
    err = np.abs(run.f_hat - host.f_hat) / cfg.friction.Cf
    tenth = len(err) // 10
    return arm, run, err, tenth, t_emu, t_host


def run() -> list[dict]:
    missing = armcheck.toolchain_missing()
    if missing:
        return [{"benchmark": "cortex-m4f step", "value": "skipped", "reference": missing, "ratio": "-",
                 "target": "-", "ok": True}]
    cfg = od.load_preset("vcm")
    res = od.simulate(cfg, STROKE, duration=STEPS * cfg.observer.dt, controller="pid")
    res_comp = od.simulate(cfg, STROKE, duration=STEPS * cfg.observer.dt, controller="pid+observer")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for controller, r in (("pid", res), ("pid+observer", res_comp)):
            arm, emu, err, tenth, t_emu, t_host = _case(cfg, controller, Path(tmp) / controller, r)
            worst, mean = int(emu.instructions.max()), float(emu.instructions.mean())
            stroke = float(np.ptp(r.x_meas))
            label = f"vcm, {controller}, {stroke:.3g} m stroke, {len(r.t):,} steps"
            rows.append({"benchmark": f"cortex-m4f instructions a step, worst / mean ({label})",
                         "value": f"{worst} / {mean:.0f}",
                         "reference": f"host double step {t_host / len(r.t) * 1e9:.0f} ns incl. I/O; emulation {t_emu:.0f} s",
                         "ratio": f"{worst / 1500:.2f} of budget", "target": "worst <= 1500", "ok": worst <= 1500})
            ok = controller != "pid" or float(err.max()) <= 1e-3
            rows.append({"benchmark": f"cortex-m4f friction error vs host double, max / first tenth / last tenth "
                                      f"[% of Cf] ({label})",
                         "value": f"{err.max() * 100:.4f} / {err[:tenth].max() * 100:.4f} / {err[-tenth:].max() * 100:.4f}",
                         "reference": "host controller on the same counts", "ratio": "-",
                         "target": "<= 0.1 % (pid: the estimator alone)" if controller == "pid" else
                         "record (compensation loops back in a replay)", "ok": ok})
        rows.append({"benchmark": "cortex-m4f flash / RAM / state / stack [bytes] (arm-none-eabi-size, -fstack-usage)",
                     "value": f"{arm.flash} / {arm.ram} / {arm.state} / {arm.stack}",
                     "reference": f"{armcheck.CFLAGS}", "ratio": "-", "target": "-", "ok": True})
    return rows


if __name__ == "__main__":
    failed = False
    for row in run():
        print(f"{row['benchmark']}: {row['value']}  [{row['reference']}; target {row['target']}: "
              f"{'met' if row['ok'] else 'NOT MET'}]")
        failed |= not row["ok"]
    sys.exit(1 if failed else 0)
