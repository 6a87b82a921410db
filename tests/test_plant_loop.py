"""Margins of the sampled loop around the simulated plant (obsdesign.design.plant_loop) against a frequency
response measured on the simulator: sines on a ramp (gross sliding, no reversal) through the nonlinear
loop of ``simulate`` (PID, the drive's delay, the paper's friction, Heun substeps), ``L = T / (1 - T)`` from
the DFT of the position at the sines' bins; the phase margin where the measured ``|L|`` crosses 0 dB."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from _loop_axes import config_2khz, rotary_4khz  # noqa: E402

import obsdesign as od
from obsdesign.design.plant_loop import plant_loop, plant_loops, simulated_plant
from obsdesign.design.sampled_loop import sampled_loop
from obsdesign.sim import prepare, run

#: loop2k and the rotary axis with the paper's PID (crossover 0.67 and 1.3 krad/s, pinned; also ``auto``'s choice
#: there, where the sampled design would cost the crossover): the loops these measurements were written for; the
#: sampled design is measured in :data:`SAMPLED_CASES`.
CASES = {"vcm": od.load_preset("vcm"), "vcm-d2": od.load_preset("vcm").override(delay_samples=2),
         "loop2k": config_2khz(design="paper"), "loop2k-d1": config_2khz(design="paper").override(delay_samples=1),
         "rotary-4k-d1": rotary_4khz(1).override(design="paper"), "table1-lag": od.load_preset("table1")}


def measured_loop(cfg, omegas, *, amplitude=1e-6, speed=None, settle=2.0, window=1.0, controller="pid"):
    """``L(j w)`` measured on the simulator at (the DFT bins nearest to) ``omegas`` [rad/s]: the reference is a
    ramp of ``speed`` (default: 100 times the sines' largest velocity) plus sines of ``amplitude``; no noise,
    no encoder. Returns the bins' frequencies and ``L``."""
    cfg = cfg.override(quantization=0.0, noise_rms=0.0)
    dt = cfg.observer.dt
    n_win = int(round(window / dt))
    n = int(round(settle / dt)) + n_win
    bins = np.unique(np.round(np.asarray(omegas) * n_win * dt / (2 * math.pi)).astype(int))
    w = 2 * math.pi * bins / (n_win * dt)
    speed = 100 * amplitude * w.max() if speed is None else speed
    t = np.arange(n) * dt
    sines = amplitude * np.sin(np.outer(t, w)).sum(axis=1)
    loop = prepare(cfg, "tracking", controller=controller, duration=n * dt)
    loop = dataclasses.replace(loop, x_ref=speed * t + sines, noise=np.zeros(n))
    res = run(loop)
    assert not res.metrics["diverged"]
    assert np.all(np.diff(res.x[n // 4:]) > 0)  # sliding: the motion never reverses
    y = (res.x - speed * t)[-n_win:]
    r = sines[-n_win:]
    Y, R = np.fft.rfft(y)[bins], np.fft.rfft(r)[bins]
    T = Y / R
    return w, T / (1 - T)


def crossing(w, L):
    """Where the measured ``|L|`` crosses 1 (log-log interpolation) and the phase margin there [deg]."""
    mag = np.log(np.abs(L))
    i = int(np.nonzero((mag[:-1] > 0) & (mag[1:] <= 0))[0][0])
    f = mag[i] / (mag[i] - mag[i + 1])
    wc = math.exp(math.log(w[i]) + f * (math.log(w[i + 1]) - math.log(w[i])))
    ph = np.unwrap(np.angle(L))
    return wc, math.degrees(ph[i] + f * (ph[i + 1] - ph[i])) + 180.0


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_sliding_margins_are_those_measured_on_the_simulator(name):
    import control as ct

    cfg = CASES[name]
    pl = plant_loop(cfg)
    wc = pl.crossover_rad_s
    w, L = measured_loop(cfg, wc * np.array([0.7, 0.85, 0.95, 1.05, 1.2, 1.5]))
    # the model's L at the same frequencies: C(z) z^-d H_zoh(z), built here from python-control's pieces
    sl = sampled_loop(cfg)
    dt, d = cfg.observer.dt, cfg.hardware.delay_samples
    model = sl.C * ct.tf([1.0], [1.0] + [0.0] * d, dt) * ct.c2d(simulated_plant(cfg), dt, "zoh")
    Lm = np.array([complex(model(np.exp(1j * x * dt))) for x in w])
    np.testing.assert_allclose(20 * np.log10(np.abs(L)), 20 * np.log10(np.abs(Lm)), atol=0.5)
    np.testing.assert_allclose(np.degrees(np.angle(L / Lm)), 0.0, atol=1.0)
    wc_meas, pm_meas = crossing(w, L)
    assert pm_meas == pytest.approx(pl.phase_margin_deg, abs=1.0)
    assert wc_meas == pytest.approx(wc, rel=0.02)


#: The same axes with the sampled design (crossover 58-95 rad/s, integrator zero 2.4-3.7 rad/s): its slow integral
#: needs 6 s of ramp before the window (after 2 s the rotary axis's phase is 53-60 deg off).
SAMPLED_CASES = {"loop2k": config_2khz(design="sampled"), "loop2k-d1": config_2khz(1, design="sampled"),
                 "rotary-4k-d1": rotary_4khz(1).override(design="sampled")}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SAMPLED_CASES))
def test_the_sampled_pids_sliding_margins_are_those_measured_on_the_simulator(name):
    """Issue 33: the sampled PID of loop2k and the rotary axis has the simulated plant's phase margin within 1 deg
    of the one measured on the simulator, and it meets its target."""
    from obsdesign.design.pid_sampled import resolve_pid

    cfg = SAMPLED_CASES[name]
    assert resolve_pid(cfg).design == "sampled"
    pl = plant_loop(cfg)
    w, L = measured_loop(cfg, pl.crossover_rad_s * np.array([0.7, 0.85, 0.95, 1.05, 1.2, 1.5]), settle=6.0)
    wc_meas, pm_meas = crossing(w, L)
    assert pm_meas == pytest.approx(pl.phase_margin_deg, abs=1.0)
    assert wc_meas == pytest.approx(pl.crossover_rad_s, rel=0.02)
    assert abs(pm_meas - cfg.pid.phase_margin_deg) <= 3.0


def test_the_design_model_is_not_the_simulated_plant_on_vcm():
    """vcm: the PID's design model (tau = 0.006675 s) has 60 deg, the simulated plant (m / sigma = 0.0255 s) 44 deg;
    the measured loop sides with the simulated plant."""
    cfg = od.load_preset("vcm")
    pl, sl = plant_loop(cfg), sampled_loop(cfg)
    assert sl.phase_margin_deg == pytest.approx(60.0, abs=0.1)
    assert pl.phase_margin_deg == pytest.approx(44.07, abs=0.01)  # the fidelity review of 2026-12-04
    w, L = measured_loop(cfg, pl.crossover_rad_s * np.array([0.8, 0.95, 1.05, 1.25]))
    assert abs(crossing(w, L)[1] - pl.phase_margin_deg) < 1.0 < abs(crossing(w, L)[1] - sl.phase_margin_deg)


def test_the_plant_is_the_design_model_where_tau_is_m_over_sigma():
    """loop2k has tau = m / sigma and phi = K tau / m: the two loops are one (to rounding)."""
    cfg = config_2khz()
    assert plant_loop(cfg).phase_margin_deg == pytest.approx(sampled_loop(cfg).phase_margin_deg, abs=1e-6)


def test_rest_is_a_bound_and_says_so():
    loops = plant_loops(od.load_preset("vcm"))
    assert loops["sliding"].note == ""
    assert "bound" in loops["rest"].note and "hysteretic" in loops["rest"].note
    H = simulated_plant(od.load_preset("vcm"), regime="rest")
    assert float(np.real(H(0.0))) == pytest.approx(3.28 / 8000.0)  # K / kappa: a spring at DC


def test_lag_viscous_enters_the_plant():
    """table1 (beta = 1 ms): H = K (beta s + 1) / (s (m s (beta s + 1) + sigma)), checked at one frequency."""
    cfg = od.load_preset("table1")
    pl, fr = cfg.plant, cfg.friction
    s = 1j * 300.0
    expected = pl.K / (s * (pl.m * s + fr.sigma / (fr.beta * s + 1)))
    assert complex(simulated_plant(cfg)(s)) == pytest.approx(expected, rel=1e-12)


def test_loop_json_gives_the_measured_phase_margin_of_the_rotary_axis(tmp_path):
    """The issue's criterion: `loop --json` on a 4 kHz rotary config with one sample of delay gives the simulated
    plant's phase margin within 1 deg of the frequency response measured on the simulator."""
    import contextlib
    import io
    import json

    from obsdesign.cli import main

    cfg = CASES["rotary-4k-d1"]  # the paper's PID: the loop the criterion was measured on (see CASES)
    path = tmp_path / "rot.toml"
    cfg.save(path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["loop", "--config", str(path), "--json"]) == 0
    doc = json.loads(out.getvalue())
    sliding = doc["simulated_plant"]["sliding"]
    assert sliding["delay_samples"] == 1 and "sliding" in sliding["system"]
    w, L = measured_loop(cfg, sliding["crossover_rad_s"] * np.array([0.85, 0.95, 1.05, 1.2]))
    assert crossing(w, L)[1] == pytest.approx(sliding["phase_margin_deg"], abs=1.0)
    assert doc["sampled"]["phase_margin_deg"] == pytest.approx(sampled_loop(cfg).phase_margin_deg, abs=1e-9)
    assert "bound" in doc["simulated_plant"]["rest"]["note"]


@pytest.mark.parametrize("name", ["loop2k-d1", "rotary-4k-d1"])
def test_the_compensated_loop_with_the_drives_delay_is_the_measured_one(name):
    """tune's margin (obsdesign.design.compensated_loop: the estimator fed the controller's own command, the
    drive's delay before the plant) against the loop measured with pid+observer in sliding (the observer's
    stiffness is 0 there, so the loop is linear); these axes have tau = m / sigma (design model = plant)."""
    from obsdesign.design.compensated_loop import compensated_loop
    from obsdesign.estimators import reference_estimator

    # the paper's PID (crossover near 1.3 krad/s), as measured when this test was written; with the sampled
    # design (crossover 92 rad/s) the model says 57.65 deg where 59.30 is measured on rotary-4k-d1 (left open)
    cfg = CASES[name].override(design="paper")
    pm, stable, _ = compensated_loop(cfg, reference_estimator(cfg), cfg.compensation.gain)
    wc = plant_loop(cfg).crossover_rad_s
    w, L = measured_loop(cfg, wc * np.array([0.75, 0.9, 1.0, 1.1, 1.3]), controller="pid+observer")
    assert stable and crossing(w, L)[1] == pytest.approx(pm, abs=1.0)
