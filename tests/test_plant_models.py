"""Plant friction models, model mismatch, estimators and the schedule hysteresis, through ``simulate``.

Expected values are closed forms (steady sliding of a mass under a constant force) or
independent computations (SciPy root finding, an offline run of the estimator on the
recorded signals), never numbers copied from a run.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.optimize

import obsdesign as od
from obsdesign.estimators import run_offline, tune
from obsdesign.plant_spec import PlantFrictionSpec
from obsdesign.sim import ConstantForce, Excitation


def with_friction(cfg, model, **parameters):
    return dataclasses.replace(cfg, plant_friction=PlantFrictionSpec(model=model, parameters=parameters))


@pytest.fixture(scope="module")
def vcm():
    return od.load_preset("vcm")


def test_no_table_is_the_paper_plant(vcm):
    a = od.simulate(vcm, "excitation", duration=1.0)
    b = od.simulate(with_friction(vcm, "paper"), "excitation", duration=1.0)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.f_hat, b.f_hat)


def test_lugre_slides_at_the_stribeck_level(vcm):
    cfg = with_friction(vcm, "lugre", vs=0.02)  # a Stribeck velocity the steady speed feels
    res = od.simulate(cfg, ConstantForce(force=1.0), duration=2.0)
    Cf, Fs, vs, sigma = 0.35, 1.5 * 0.35, 0.02, vcm.friction.sigma

    def balance(v):
        return Cf + (Fs - Cf) * math.exp(-(v / vs) ** 2) + sigma * v - 1.0

    v_ss = scipy.optimize.brentq(balance, 1e-6, 1.0)
    assert res.v[-1] == pytest.approx(v_ss, rel=1e-4)
    # static variant: the estimated state is the friction less its viscous part, g(v)
    assert res.f[-1] == pytest.approx(1.0 - sigma * v_ss, rel=1e-4)


@pytest.mark.parametrize("model, params, force, expected", [
    # Dahl: sign(v) Cf + sigma v + offset
    ("dahl", {"offset": 0.1}, 1.0, (1.0 - 0.35 - 0.1) / 21.1),
    # paper plant, negative side: -Cf_neg + sigma_neg v
    ("paper", {"Cf_neg": 0.2, "sigma_neg": 10.0}, -1.0, -(1.0 - 0.2) / 10.0),
    ("lugre", {"Cf_neg": 0.25, "sigma_neg": 15.0}, -1.0, -(1.0 - 0.25) / 15.0),
    ("gms", {"sigma_neg": 15.0, "Cf_neg": 0.3}, -1.0, -(1.0 - 0.3) / 15.0),
])
def test_asymmetry_and_offset_set_the_sliding_speed(vcm, model, params, force, expected):
    res = od.simulate(with_friction(vcm, model, **params), ConstantForce(force=force), duration=3.0)
    assert res.v[-1] == pytest.approx(expected, rel=2e-3)


@pytest.mark.parametrize("model", ["paper", "lugre", "dahl", "gms"])
def test_each_model_runs_in_closed_loop(vcm, model):
    res = od.simulate(with_friction(vcm, model), "positioning", duration=4.0)
    assert not res.metrics["diverged"]
    # stiction (lugre, gms) and PID integral action hunt around the target (a limit cycle of
    # tens of um), so ask for a bounded error, not settling: within 20 % of the 1 mm step
    assert np.max(np.abs(res.e[-5000:])) < 0.2e-3


def test_true_schedule_uses_the_model_stiffness(vcm):
    res = od.simulate(with_friction(vcm, "lugre"), ConstantForce(force=1.0), stiffness="true", duration=1.0)
    # at rest the bristles have stiffness sigma0 = 1e5 > kappa: the schedule clips at kappa
    assert res.stiffness[0] == vcm.friction.kappa
    # in steady sliding z = g / sigma0, so dF/dx = sigma0 (1 - sigma0 z / g) = 0
    assert abs(res.stiffness[-1]) < 1e-6 * vcm.friction.kappa


def test_plant_config_is_what_is_simulated(vcm):
    heavy = vcm.override(m=2 * vcm.plant.m, Cf=0.2)
    mismatched = od.simulate(vcm, "excitation", plant=heavy, duration=1.0)
    designed_heavy = od.simulate(heavy, "excitation", duration=1.0)
    # open loop: the plant's motion is that of the heavy config, whatever the observer's design
    np.testing.assert_array_equal(mismatched.x, designed_heavy.x)
    assert not np.array_equal(mismatched.f_hat, designed_heavy.f_hat)


@pytest.mark.parametrize("name", ["eso", "kalman", "dob"])
def test_linear_estimators_in_the_loop_match_an_offline_run(vcm, name):
    res = od.simulate(vcm, "positioning", estimator=name, duration=4.0)
    est = tune(name, vcm)
    v_hat, f_hat = run_offline(est, res.u, res.x_meas)
    np.testing.assert_allclose(res.v_hat, v_hat, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.f_hat, f_hat, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(res.f_hat_filtered, res.f_hat)  # compensates unfiltered
    assert all(t is not None for t in res.metrics["settling_time"])


@pytest.mark.parametrize("name", ["eso", "kalman", "dob"])
def test_linear_estimators_converge_in_steady_sliding(vcm, name):
    res = od.simulate(vcm, ConstantForce(force=1.0), estimator=name, duration=3.0)
    assert res.f_hat[-1] == pytest.approx(res.f[-1], abs=0.02)  # Coulomb level 0.35 N, quantization noise


def test_hysteresis_under_slow_noisy_excitation():
    """Review 2026-11-23 section 4: 1 N RMS over 1 Hz, 1 um noise, table1 model plant, rho 1.02."""
    cfg = od.load_preset("table1")
    err = {}
    for schedule in ("true", "estimated", "estimated-raw"):
        res = od.simulate(cfg, Excitation(force_rms=1.0, bandwidth=1.0), plant="model", stiffness=schedule,
                          duration=10.0, seed=1)
        err[schedule] = float(np.sqrt(np.mean((res.f_hat - res.f) ** 2)))
    assert err["estimated"] < 1.5 * err["true"]
    assert err["estimated-raw"] > 2.0 * err["true"]  # the defect the hysteresis removes


@pytest.mark.parametrize("table, exc, match", [
    ({"model": "coulomb"}, ValueError, r"plant_friction.model: expected one of paper, lugre, dahl, gms, found 'coulomb'"),
    ({"model": "lugre", "sigma0": -1.0}, ValueError, r"lugre.sigma0: expected a finite number in \[0.01, 1e\+12\] N/m \(N m/rad on a rotary axis\)"),
    ({"model": "dahl", "Fs": 1.0}, ValueError, r"dahl: unknown parameter 'Fs'"),
    ({"model": "paper", "offset": "x"}, TypeError, r"offset: expected a real number"),
])
def test_bad_plant_friction_tables(vcm, table, exc, match):
    data = vcm.to_dict()
    data["plant_friction"] = table
    with pytest.raises(exc, match=match):
        od.Config.from_dict(data)


def test_plant_friction_toml_round_trip(vcm):
    cfg = with_friction(vcm, "gms", N=3, offset=0.05, Cf_neg=0.3)
    back = od.Config.from_toml(cfg.to_toml())
    assert back == cfg
    assert back.plant_friction.parameters["N"] == 3


def test_model_plant_rejects_other_friction(vcm):
    with pytest.raises(ValueError, match="plant: the 'model' plant has the paper's friction"):
        od.simulate(with_friction(vcm, "dahl"), "excitation", plant="model", duration=1.0)
