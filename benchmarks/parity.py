"""The parity contract of the exported controller (issue 16), in full: a Markdown table.

For each schedule (``estimated``, ``estimated-raw``, ``constant``; estimator ``paper``) and each other
registered estimator (``paper-k0``, ``eso``, ``kalman``, ``dob``), x {default compensation, gain 0.7 +
viscous + deadzone 1e-4 m/s}, x {60 s ``tracking``, the whole ``positioning`` scenario (6 s, both
steps)}, x two noisy configs (``table1``: lag, noise 1 um RMS, 0.1 um quantization; ``vcm``: static,
noise 1 um RMS, 1 um quantization), the exported controller of every language whose toolchain is
present is driven by the simulator's ``x_ref`` and ``x_meas``; the table gives
``max |K command - G - u| / max |u|`` per case and language (``0`` is bit for bit).
The contract is 1e-9.

Usage::

    python benchmarks/parity.py                       # everything (Octave takes about 3 min per 60 s run)
    python benchmarks/parity.py --languages c,js,python --tracking 10

Not run as a test; ``tests/test_controller_export.py`` checks the same cases over short runs.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import obsdesign as od
from obsdesign.export.controller import CompensationSpec, controller_files
from obsdesign.sampled.choices import ESTIMATORS, SCHEDULES

CONFIGS = {
    "table1": lambda: od.load_preset("table1").override(quantization=1e-7),
    "vcm": lambda: od.load_preset("vcm").override(noise_rms=1e-6),
}
KNOBS = {"default": CompensationSpec(), "knobs": CompensationSpec(gain=0.7, viscous=True, deadzone=1e-4)}
CASES = ([("paper", name) for name in SCHEDULES.names() if name != "true"]
         + [(name, "estimated") for name in ESTIMATORS.names() if name != "paper"])
TOOLS = {"python": None, "c": "gcc", "js": "node", "octave": "octave"}
LIMIT = 1e-9

C_DRIVER = r"""
#include <stdio.h>
#include "obsdesign_controller.h"
int main(int argc, char **argv) {
    double r, x;
    obsdesign_controller c;
    FILE *in, *out;
    if (argc != 3 || !(in = fopen(argv[1], "rb")) || !(out = fopen(argv[2], "wb"))) return 2;
    obsdesign_controller_init(&c);
    while (fread(&r, sizeof r, 1, in) == 1 && fread(&x, sizeof x, 1, in) == 1) {
        double cmd = obsdesign_controller_step(&c, r, x);
        fwrite(&cmd, sizeof cmd, 1, out);
    }
    fclose(in);
    fclose(out);
    return 0;
}
"""


def _write(files: dict[str, str], folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text)


def run_python(files, x_ref, x_meas, folder):
    _write(files, folder)
    spec = importlib.util.spec_from_file_location(f"parity_{folder.name}", folder / "obsdesign_controller.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    step = module.Controller().step
    return np.array([step(r, x) for r, x in zip(x_ref.tolist(), x_meas.tolist())])


def run_c(files, x_ref, x_meas, folder):
    _write(files, folder)
    (folder / "driver.c").write_text(C_DRIVER)
    exe = folder / "driver"
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", f"-I{folder}", "-o", str(exe),
                    str(folder / "driver.c"), str(folder / "obsdesign_controller.c"), "-lm"], check=True)
    np.column_stack([x_ref, x_meas]).astype("<f8").tofile(folder / "in.bin")
    subprocess.run([str(exe), str(folder / "in.bin"), str(folder / "out.bin")], check=True)
    return np.fromfile(folder / "out.bin", dtype="<f8")


def run_js(files, x_ref, x_meas, folder):
    _write(files, folder)
    (folder / "in.json").write_text(json.dumps({"x_ref": x_ref.tolist(), "x_meas": x_meas.tolist()}))
    script = (f"import {{ Controller }} from {json.dumps((folder / 'obsdesign_controller.mjs').as_uri())};"
              "import fs from 'fs';"
              f"const d = JSON.parse(fs.readFileSync({json.dumps(str(folder / 'in.json'))}, 'utf8'));"
              "const c = new Controller(); const out = new Float64Array(d.x_ref.length);"
              "for (let i = 0; i < out.length; i++) out[i] = c.step(d.x_ref[i], d.x_meas[i]);"
              f"fs.writeFileSync({json.dumps(str(folder / 'out.bin'))}, Buffer.from(out.buffer));")
    subprocess.run(["node", "--input-type=module", "-e", script], check=True)
    return np.fromfile(folder / "out.bin", dtype="<f8")


def run_octave(files, x_ref, x_meas, folder):
    _write(files, folder)
    np.column_stack([x_ref, x_meas]).astype("<f8").tofile(folder / "in.bin")
    script = ("f = fopen('in.bin', 'r'); d = fread(f, [2, Inf], 'double'); fclose(f);"
              "st = obsdesign_controller_init(); n = columns(d); out = zeros(n, 1);"
              "for i = 1:n [out(i), st] = obsdesign_controller_step(st, d(1, i), d(2, i)); end;"
              "f = fopen('out.bin', 'w'); fwrite(f, out, 'double'); fclose(f);")
    subprocess.run(["octave", "--no-gui", "--quiet", "--no-window-system", "--eval", script], check=True, cwd=folder)
    return np.fromfile(folder / "out.bin", dtype="<f8")


RUNNERS = {"python": run_python, "c": run_c, "js": run_js, "octave": run_octave}


def scenarios(tracking: float):
    return {"tracking": ("tracking", tracking), "positioning": ("positioning", None)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--languages", default=",".join(RUNNERS), help="comma-separated (default: all present)")
    parser.add_argument("--configs", default=",".join(CONFIGS), help="comma-separated of " + ", ".join(CONFIGS))
    parser.add_argument("--tracking", type=float, default=60.0, help="tracking duration [s] (default 60)")
    args = parser.parse_args(argv)
    languages = [name for name in args.languages.split(",") if TOOLS[name] is None or shutil.which(TOOLS[name])]
    missing = sorted(set(args.languages.split(",")) - set(languages))
    rows, worst, t0 = [], 0.0, time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for config_name in args.configs.split(","):
            base = CONFIGS[config_name]()
            for scenario_name, (scenario, duration) in scenarios(args.tracking).items():
                for estimator, schedule in CASES:
                    for knob_name, comp in KNOBS.items():
                        cfg = base.override(gain=comp.gain, viscous=comp.viscous, deadzone=comp.deadzone)
                        res = od.simulate(cfg, scenario, controller="pid+observer", stiffness=schedule,
                                          estimator=estimator, duration=duration)
                        cells = []
                        for language in languages:
                            folder = Path(tmp) / f"{config_name}-{scenario_name}-{estimator}-{schedule}-{knob_name}-{language}"
                            files = controller_files(cfg, language, schedule=schedule, estimator=estimator)
                            command = RUNNERS[language](files, res.x_ref, res.x_meas, folder)
                            u = cfg.plant.K * command - cfg.plant.G
                            rel = float(np.max(np.abs(u - res.u)) / np.max(np.abs(res.u)))
                            worst = max(worst, rel)
                            cells.append("0" if rel == 0.0 else f"{rel:.1e}")
                        rows.append(f"| {config_name} | {scenario_name} ({len(res.u)} samples) | {estimator} | "
                                    f"{schedule if estimator == 'paper' else '-'} | {knob_name} | "
                                    + " | ".join(cells) + " |")
                        print(rows[-1], file=sys.stderr, flush=True)
    print(f"Parity of the exported controller (max |du| / max |u|; 0: bit for bit; contract {LIMIT:g}), "
          f"{time.perf_counter() - t0:.0f} s" + (f"; not installed: {', '.join(missing)}" if missing else ""))
    print()
    print("| config | scenario | estimator | schedule | compensation | " + " | ".join(languages) + " |")
    print("|---|---|---|---|---|" + "---|" * len(languages))
    print("\n".join(rows))
    print()
    print(f"worst: {worst:.3g} ({'within' if worst <= LIMIT else 'BEYOND'} the contract)")
    return 0 if worst <= LIMIT else 1


if __name__ == "__main__":
    sys.exit(main())
