"""Honest numerics: automatic substeps against closed forms, refusals, divergence labels, quantizer,
seed and initial-estimate checks, and the design's warnings in simulate and noise."""

import dataclasses
import math
import subprocess
import sys

import numpy as np
import pytest

import obsdesign as od
from obsdesign.loop.numerics import MAX_STEP_RATE, substeps_for
from obsdesign.sim import prepare, run


def cli(*args):
    return subprocess.run([sys.executable, "-m", "obsdesign", *args], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("preset", ["table1", "vcm"])
@pytest.mark.parametrize("plant", ["physical", "model"])
def test_presets_keep_ten_substeps(preset, plant):
    cfg = od.load_preset(preset)
    if plant == "model" and cfg.friction.beta is None and cfg.observer.variant == "lag":
        pytest.skip("model lag needs beta")
    assert substeps_for(cfg, cfg.observer.dt, 10, plant=plant) == 10
    assert prepare(cfg, "constant", plant=plant, duration=0.1).n_sub == 10


def test_stiff_viscous_plant_adapts_and_matches_the_closed_form():
    """m = 0.538 kg, sigma = 1e6 N s/m, 1 N: x(t) = F/sigma (t - tau (1 - exp(-t/tau))), tau = m/sigma.

    Coulomb friction is made negligible (Cf = 1e-12 N), so the plant is linear. The old fixed
    10 substeps (h = 1e-5 s, h sigma/m = 18.6 > 2) blew this up to 4.4e9 m."""
    cfg = od.load_preset("vcm").override(sigma=1e6, Cf=1e-12)
    loop = prepare(cfg, "constant", duration=1.0)
    tau = cfg.plant.m / cfg.friction.sigma
    assert loop.n_sub == math.ceil(cfg.observer.dt / tau / MAX_STEP_RATE)  # 930 by the rule h/tau <= 0.2
    res = run(loop)
    assert res.metrics["diverged"] is False and res.metrics["divergence"] is None
    t = np.arange(loop.n_samples) * cfg.observer.dt
    exact = 1.0 / cfg.friction.sigma * (t - tau * (1.0 - np.exp(-t / tau)))
    np.testing.assert_allclose(res.x, exact, rtol=1e-6, atol=1e-15)


def test_forced_unstable_step_is_labelled_numerical_and_a_bad_design_physical():
    cfg = od.load_preset("vcm").override(sigma=1e6, Cf=1e-12)
    loop = prepare(cfg, "constant", duration=1.0)
    res = run(dataclasses.replace(loop, n_sub=10))  # h sigma/m = 18.6: outside Heun's stability interval
    assert res.metrics["diverged"] is True and res.metrics["divergence"] == "numerical"
    bad = od.simulate(od.load_preset("vcm").override(rho=0.5), "positioning", duration=3.5, keep_trace=False)
    assert bad.metrics["diverged"] is True and bad.metrics["divergence"] == "physical"


def test_a_measurement_out_of_scale_is_labelled_measurement_without_overflow_warnings():
    """Review 2026-12-01 xe8: --noise-rms 1e300 was 'physical' (the plant stayed at 2.5e-7 m) with an overflow warning."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an overflow in the RMS values would fail here
        res = od.simulate(od.load_preset("vcm").override(noise_rms=1e300), "positioning", duration=3.5,
                          keep_trace=False)
    assert res.metrics["diverged"] is True and res.metrics["divergence"] == "measurement"
    assert res.metrics["rms_error"] < 1e-3  # the plant itself stayed put


@pytest.mark.parametrize(
    "override, match",
    [
        ({"m": 1e-6}, r"sigma/m = 2\.11e\+07 1/s \(plant\.m = 1e-06, friction\.sigma = 21\.1\).*more than 1000"),
        ({"m": 1e-9}, r"plant\.m = 1e-09"),
    ],
)
def test_plant_beyond_the_bound_is_refused_naming_its_parameters(override, match):
    with pytest.raises(ValueError, match=match):
        od.simulate(od.load_preset("vcm").override(**override), "constant", duration=0.1)


def test_tiny_beta_is_refused_naming_beta():
    with pytest.raises(ValueError, match=r"1/beta = 1e\+12 1/s \(friction\.beta = 1e-12\)"):
        od.simulate(od.load_preset("table1").override(beta=1e-12), "excitation", duration=0.1)


def test_large_dt_gets_more_substeps():
    cfg = od.load_preset("vcm").override(dt=0.5)
    # the pre-sliding spring sqrt(kappa/m) = 121.94 1/s: 0.5 * 121.94 / 0.2 = 304.8
    assert prepare(cfg, "positioning").n_sub == math.ceil(0.5 * math.sqrt(8000 / 0.538) / 0.2) == 305


def test_quantizer_does_not_overflow():
    """Rounding a 1e20 m measurement to 1 um: before, numba's int64 floor pinned it at -9.22e12 m."""
    cfg = od.load_preset("vcm").override(noise_rms=1e20)
    loop = prepare(cfg, "constant", duration=0.01)
    res = run(loop)
    assert res.x_meas[0] == pytest.approx(loop.noise[0], rel=1e-12)
    assert abs(res.x_meas[0]) > 1e13
    assert res.metrics["diverged"] is True


@pytest.mark.parametrize(
    "kw, exc, match",
    [
        ({"seed": None}, ValueError, "seed: expected an integer >= 0, found None"),
        ({"seed": -1}, ValueError, "seed: expected an integer >= 0, found -1"),
        ({"seed": 1.5}, ValueError, "seed: expected an integer >= 0, found 1.5"),
        ({"initial_estimate": (1.0,)}, ValueError, r"initial_estimate: expected a pair \(v_hat, f_hat\)"),
        ({"initial_estimate": 3.0}, ValueError, "initial_estimate: expected a pair"),
        ({"initial_estimate": (0.0, float("nan"))}, ValueError, "initial_estimate: expected a finite number"),
        ({"substeps": 10**9}, ValueError, "substeps: expected an integer >= 1 and <= 1000, found 1000000000"),
        ({"substeps": 0}, ValueError, "substeps: expected an integer >= 1 and <= 1000, found 0"),
    ],
)
def test_bad_simulate_options(kw, exc, match):
    with pytest.raises(exc, match=match):
        od.simulate(od.load_preset("vcm"), "constant", duration=0.1, **kw)


def _closed_form_unstable(rho, m=0.538, kappa=8000.0):
    """Static variant: eigenvalues -rho sqrt(kappa/m) +- sqrt((kappa - k)/m); largest at k = 0."""
    return -rho * math.sqrt(kappa / m) + math.sqrt(kappa / m) >= 0.0


@pytest.mark.parametrize("rho", [0.5, 0.9, 1.5, 4.0])
def test_design_warnings_flag_exactly_the_unstable_designs(rho):
    notes = od.design.design_warnings(od.load_preset("vcm").override(rho=rho))
    assert any(n.startswith("the observer design fails check") for n in notes) == _closed_form_unstable(rho)


@pytest.mark.slow
def test_simulate_prints_the_checks_warning_once_and_keeps_exit_0():
    proc = cli("simulate", "positioning", "--dt", "0.01", "--duration", "3.5", "--json")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.strip().splitlines()
    # fastest pole of vcm: -rho sqrt(kappa/m) - sqrt(kappa/m) = -5 * 121.94 = -609.7 1/s; times 0.01 s = 6.1
    assert len(lines) == 1 and lines[0].startswith("obsdesign: warning: fastest observer pole -609.7 1/s") and "6.1 > 1" in lines[0]
    proc = cli("simulate", "positioning", "--duration", "3.5", "--json")
    assert proc.returncode == 0 and proc.stderr == ""


@pytest.mark.slow
def test_noise_warns_for_an_unstable_design():
    proc = cli("noise", "--preset", "vcm", "--rho", "0.5")
    assert proc.returncode == 0
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("obsdesign: warning: the observer design fails check")
    assert cli("noise", "--preset", "vcm").stderr == ""


@pytest.mark.slow
def test_simulate_refusal_is_one_line_exit_2(tmp_path):
    cfg = tmp_path / "m.toml"
    text = (od.load_preset("vcm").to_toml()).replace("m = 0.538", "m = 1e-06")
    cfg.write_text(text)
    proc = cli("simulate", "constant", "--config", str(cfg))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "more than 1000 substeps" in lines[0] and "plant.m = 1e-06" in lines[0]


@pytest.mark.slow
def test_clipped_open_loop_force_is_warned():
    """table1: K = 3.28 N/V, u_max = 10 V, G = 0, so the actuator gives at most 32.8 N."""
    proc = cli("simulate", "constant", "--input-force", "1e30", "--duration", "0.1", "--json")
    assert proc.returncode == 0
    line = proc.stderr.strip().splitlines()
    assert len(line) == 1 and "reaches 1e+30 N" in line[0] and "[-32.8, 32.8] N" in line[0]
    assert cli("simulate", "constant", "--input-force", "32", "--duration", "0.1", "--json").stderr == ""
