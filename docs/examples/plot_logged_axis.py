"""
From a logged axis to an exported controller
============================================

The example log shipped with the package (:func:`obsdesign.datasets.example_log`: a simulated
voice-coil axis under PID control, 8 s at 1 kHz, with known mass 0.8 kg, viscous friction
12 N s/m and Coulomb friction 0.9 N) is identified, turned into a complete design config,
checked, run through the observer, and exported as the whole sampled controller in C99.

Asserts: the identification recovers the mass, the viscous and the Coulomb friction within 5 %
of the values the log was made with; the config passes every stability condition; the exported
C source carries the identified friction.
"""

import tempfile
from pathlib import Path

import obsdesign as od
from obsdesign.data import identify, load_trace, model_friction_state, observe
from obsdesign.datasets import example_log
from obsdesign.export.controller import controller_files
from obsdesign.report.data_section import observation_figure

# %%
# Load the log (its columns: time ``t`` [s], displacement ``x`` [m], force ``u`` [N]) and
# identify the inverse dynamic model ``u = m a + sigma v + Cf sign(v) + offset``.
trace = load_trace(example_log(), position="x", input="u", time="t")
ident = identify(trace)
truth = {"m": 0.8, "sigma": 12.0, "Cf": 0.9}  # obsdesign/datasets/make_example_log.py
for name, value in truth.items():
    found = getattr(ident, name)
    print(f"{name:6s} identified {found:.4g}, made with {value:g} ({100 * (found / value - 1):+.1f} %)")
    assert abs(found / value - 1) < 0.05, (name, found, value)

# %%
# A complete config for this axis (observer, PID, sensor from the log's noise and resolution),
# checked against the paper's stability conditions.
cfg = ident.to_config(name="axis")
report = od.check_stability(cfg)
print(report)
assert report.stable

# %%
# The observer over the record, against the identified model's friction ``Cf sign(v)``.
obs = observe(cfg, trace)
observation_figure(obs, model_friction_state(ident, trace, cfg))

# %%
# The whole sampled controller (observer, low-pass, stiffness schedule, PID with compensation)
# as C99 source for the axis' own controller board.
with tempfile.TemporaryDirectory() as tmp:
    for name, text in controller_files(cfg, "c").items():
        (Path(tmp) / name).write_text(text, encoding="utf-8")
        print(f"{name}: {len(text.splitlines())} lines")
    source = (Path(tmp) / "obsdesign_controller.c").read_text(encoding="utf-8")
assert f"#define OD_CF {cfg.friction.Cf!r}" in source and f"#define OD_SIGMA {cfg.friction.sigma!r}" in source
print("\n".join(line for line in source.splitlines() if line.startswith(("#define OD_CF", "#define OD_KP"))))
