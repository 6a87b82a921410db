"""EMPS benchmark: identification, design and the observer on a real positioning axis.
===================================================================================

Runs the whole measured-data path on a copy of the benchmark's ``DATA_EMPS.mat`` (A. Janot,
M. Gautier, M. Brunot, "Data Set and Reference Models of EMPS", 2019): load the record,
identify the inverse dynamic model, write the design config, check it, run the observer over
the record, draw the fit and the estimates.

Asserts: M, Fv and Fc within 0.1 % and the offset within 2 % of the published model; the
written config loads back equal and passes every stability condition; the observer's velocity
is within 1 % RMS of the zero-phase derivative; its friction estimate differs from the
identified Coulomb friction ``Cf sign(v)`` (the offset is fed forward as the load G) by an RMS
within 1.25 times the RMS residual of the inverse model itself.

Usage: ``python analysis/emps.py path/to/DATA_EMPS.mat [--out DIR]``
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import obsdesign as od
from obsdesign.data import identify, load_trace, model_friction_state, observe
from obsdesign.data.trace import zero_phase_velocity
from obsdesign.report.data_section import fit_figure, observation_figure
from obsdesign.report.figures import save_figure

from _common import OUT

GAIN = 35.15065188  # N/V: vir is the controller's output voltage
PUBLISHED = {"m": 95.1089, "sigma": 203.5034, "Cf": 20.3935, "offset": -3.1648}
TOLERANCE = {"m": 1e-3, "sigma": 1e-3, "Cf": 1e-3, "offset": 2e-2}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])  # __doc__ is empty in the gallery
    ap.add_argument("data", help="the benchmark's DATA_EMPS.mat")
    ap.add_argument("--out", default=str(OUT), help="folder for the outputs")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    trace = load_trace(args.data, position="qm", input="vir", time="t", input_gain=GAIN)
    ident = identify(trace)
    print(ident)
    for name, ref in PUBLISHED.items():
        ours = getattr(ident, name)
        rel = (ours - ref) / abs(ref)
        print(f"{name}: {ours:.6g} (published {ref:.6g}, {100 * rel:+.3f} %)")
        assert abs(rel) <= TOLERANCE[name], f"{name} differs from the published model by {100 * rel:.3f} %"

    cfg = ident.to_config(name="emps")
    cfg.save(out / "emps.toml")
    back = od.load_config(out / "emps.toml")
    assert back.to_toml() == cfg.to_toml(), "the written config does not load back equal"
    stability = od.check_stability(back)
    assert stability.all_hold, f"stability conditions fail: {stability.failed()}"
    print(f"config: {out / 'emps.toml'}; every stability condition holds")

    obs = observe(back, trace)
    w3 = model_friction_state(ident, trace, back)
    v = zero_phase_velocity(trace.position, trace.sample_time)
    a = np.gradient(v, trace.sample_time)
    residual = trace.force - (ident.m * a + ident.sigma * v + ident.Cf * np.sign(v) + ident.offset)
    rms_residual = float(np.sqrt(np.mean(residual[50:-50] ** 2)))
    rms_error = float(np.sqrt(np.mean((obs.f_hat - w3) ** 2)))
    rms_error_f = float(np.sqrt(np.mean((obs.f_hat_filtered - w3) ** 2)))
    v_error = float(np.sqrt(np.mean((obs.v_hat - v) ** 2)) / np.sqrt(np.mean(v**2)))
    print(obs)
    print(f"friction estimate minus Cf sign(v): RMS {rms_error:.3f} N raw, {rms_error_f:.3f} N filtered; "
          f"inverse-model residual RMS {rms_residual:.3f} N; velocity error {100 * v_error:.3f} % RMS")
    assert v_error < 0.01, f"velocity estimate off by {100 * v_error:.2f} % RMS"
    assert rms_error < 1.25 * rms_residual, f"friction estimate error {rms_error:.3f} N > 1.25 x {rms_residual:.3f} N"

    save_figure(fit_figure(ident, trace), out / "emps_fit.png")
    save_figure(observation_figure(obs, w3), out / "emps_observer.png")
    obs.to_csv(out / "emps_observer.csv")
    print(f"figures: {out / 'emps_fit.png'}, {out / 'emps_observer.png'}")


if __name__ == "__main__":
    main()
