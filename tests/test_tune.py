"""Tuning (design/tune.py), the predicted error of the compensated estimate (estimators/prediction.py),
the min-error rule, ``obsdesign tune`` and integer sweep axes."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
import scipy.signal

import obsdesign as od
from obsdesign.cli import main
from obsdesign.design import certify
from obsdesign.design.compensated_loop import compensated_loop as _loop
from obsdesign.design.sampled_loop import sampled_loop
from obsdesign.design.tune import Constraints, evaluate, tune
from obsdesign.estimators import build, friction_noise_rms, noise_level, reference_estimator, run_offline
from obsdesign.estimators import tune as tune_estimator
from obsdesign.estimators.prediction import lag_moments, predict_error

EMPS = Path(os.environ.get("OBSDESIGN_EMPS") or
            Path(__file__).resolve().parents[1].parent / "shared" / "data" / "emps" / "DATA_EMPS.mat")
needs_emps = pytest.mark.skipif(not EMPS.is_file(), reason=f"EMPS data not found at {EMPS} (set OBSDESIGN_EMPS)")


def _telegraph_run(cfg, est, rate, seconds, seed=0):
    """RMS of f - f_hat for a random telegraph Coulomb friction through the exactly sampled physical plant
    (u = 0, no noise): static ``m v' = -Fc - sigma v`` (f = Fc), lag ``m v' = -Fc - Fv``, ``beta Fv' = sigma v - Fv``
    (f = Fc + Fv)."""
    dt, m, fr = cfg.observer.dt, cfg.plant.m, cfg.friction
    n = int(round(seconds / dt))
    rng = np.random.default_rng(seed)
    flips = rng.random(n) < 1.0 - math.exp(-rate * dt)     # Poisson reversals, one per sample at most
    fc = fr.Cf * np.where(np.cumsum(flips) % 2 == 0, 1.0, -1.0)
    if cfg.observer.variant == "static":
        A, B = np.array([[0.0, 1.0], [0.0, -fr.sigma / m]]), np.array([[0.0], [-1.0 / m]])
        Cm = np.array([[1.0, 0.0], [0.0, 0.0]])
    else:
        A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0 / m], [0.0, fr.sigma / fr.beta, -1.0 / fr.beta]])
        B, Cm = np.array([[0.0], [-1.0 / m], [0.0]]), np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    sysd = scipy.signal.cont2discrete((A, B, Cm, np.zeros((2, 1))), dt, "zoh")
    _, out, _ = scipy.signal.dlsim(sysd[:4] + (dt,), fc)
    y, f = out[:, 0], fc + out[:, 1]
    _, f_hat = run_offline(est, np.zeros(n), y, f0=f[0])
    keep = slice(int(1.0 / dt), None)
    return float(np.sqrt(np.mean((f - f_hat)[keep] ** 2)))


@pytest.mark.slow  # a Monte Carlo of long noisy runs, 13-15 s a case
@pytest.mark.parametrize("preset, name", [("vcm", "paper+lowpass"), ("table1", "paper+lowpass"), ("vcm", "dob")])
def test_lag_part_against_monte_carlo(preset, name):
    cfg = od.load_preset(preset)
    est = reference_estimator(cfg) if name == "paper+lowpass" else build("dob", cfg, omega_q=200.0)
    rate = 20.0                                           # 2000 reversals in 100 s: about 2 % Monte-Carlo error
    A, B, C = lag_moments(est, cfg, reversal_rate=rate)
    predicted = math.sqrt(A - 2 * B + C)
    measured = _telegraph_run(cfg, est, rate, 100.0)
    assert measured == pytest.approx(predicted, rel=0.06)


def test_prediction_parts_and_gain():
    cfg = od.load_preset("vcm")
    est = reference_estimator(cfg)
    full, half = predict_error(est, cfg), predict_error(est, cfg, gain=0.5)
    assert full.noise == pytest.approx(friction_noise_rms(est, *noise_level(cfg)), rel=1e-12)
    assert half.noise == pytest.approx(0.5 * full.noise, rel=1e-12)
    A, B, C = lag_moments(est, cfg)
    assert A == pytest.approx(cfg.friction.Cf ** 2, rel=2e-4)    # static: Fc itself (theta < 1e-8 pi left out)
    # lag^2 is quadratic in the gain: A - 2 g B + g^2 C
    assert half.lag ** 2 == pytest.approx(A - B + 0.25 * C, rel=1e-12)
    assert full.total == pytest.approx(math.hypot(full.lag, full.noise), rel=1e-12)
    with pytest.raises(ValueError, match="gain: expected a finite number > 0 and <= 1, found 1.5"):
        predict_error(est, cfg, gain=1.5)


@pytest.mark.parametrize("delay", [0, 1, 2])
def test_compensated_loop_without_compensation_is_the_sampled_loop(delay):
    cfg = od.load_preset("vcm").override(delay_samples=delay)
    pm, stable, _ = _loop(cfg, reference_estimator(cfg), 1e-12)
    assert stable and pm == pytest.approx(sampled_loop(cfg).phase_margin_deg, abs=1e-3)


def test_min_error_rule_is_a_minimum():
    cfg = od.load_preset("vcm")
    est = tune_estimator("dob", cfg, rule="min-error")
    w = est.params["omega_q"]
    best = predict_error(est, cfg).total
    for f in (0.9, 1.1):
        assert predict_error(build("dob", cfg, omega_q=w * f), cfg).total > best


def _check_tuned(res, min_pm):
    cfg = res.config
    assert certify(od.design_observer(cfg)).certified
    pm, stable, _ = _loop(cfg, reference_estimator(cfg), cfg.compensation.gain)
    assert stable and pm >= min_pm - 1e-9
    assert res.after <= res.before
    assert evaluate(cfg).objective == pytest.approx(res.after, rel=1e-9)


@pytest.mark.slow
def test_tune_vcm():
    res = tune(od.load_preset("vcm"), constraints=Constraints(min_phase_margin_deg=15.0))
    _check_tuned(res, 15.0)
    assert res.after < 0.9 * res.before


@pytest.mark.slow
@needs_emps
def test_tune_identified_emps():
    from obsdesign.data import identify, load_trace

    trace = load_trace(EMPS, position="qm", input="vir", time="t", input_gain=35.15065188)
    cfg = identify(trace).to_config()
    res = tune(cfg, constraints=Constraints(min_phase_margin_deg=35.0))
    _check_tuned(res, 35.0)


@pytest.mark.parametrize("argv, match", [
    (["--objective", "speed"], "argument --objective: invalid choice: 'speed'"),
    (["--delay-samples", "1.5"], "argument --delay-samples: expected an integer >= 0 and <= 10000, found '1.5'"),
    (["--delay-samples", "-1"], "argument --delay-samples: expected an integer >= 0 and <= 10000, found '-1'"),
    (["-o", "x.txt"], "argument -o: expected a file ending in .toml"),
])
def test_cli_bad_input(argv, match, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["tune", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert match in err and "\n" not in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_cli_infeasible_constraint(capsys, tmp_path):
    out = tmp_path / "t.toml"
    assert main(["tune", "--min-phase-margin", "170", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("obsdesign: error: infeasible constraint: min_phase_margin: expected >= 170 deg")
    assert "\n" not in err and not out.exists()


def test_sweep_integer_axis():
    from obsdesign.sweeps.plan import check_axes, make_plan

    plan = make_plan(*check_axes({"delay_samples": (0, 2, 3)}, {}, 1), samples=1, seed=0)
    assert [r.params["delay_samples"] for r in plan] == [0, 1, 2]
    assert all(type(r.params["delay_samples"]) is int for r in plan)
    with pytest.raises(ValueError, match="vary delay_samples: expected whole grid points"):
        check_axes({"delay_samples": (0, 1, 3)}, {}, 1)
    with pytest.raises(ValueError, match="uncertain delay_samples: an integer field cannot be drawn"):
        check_axes({}, {"delay_samples": (0, 2)}, 1)


@pytest.mark.slow
def test_compare_min_error_tunes_every_estimator(tmp_path):
    import json

    from obsdesign.comparison import compare, paper_design
    from obsdesign.estimators import reference_noise_rms

    cfg = od.load_preset("vcm")
    res = compare(cfg, plants=("paper",), estimators=("paper", "dob"), scenarios=("excitation",), seeds=1,
                  workers=1, rule="min-error")
    tuned = paper_design(cfg, "min-error")
    assert tuned.observer.rho != cfg.observer.rho and tuned.compensation.gain == cfg.compensation.gain
    assert tuned.observer.rho == tune(cfg, tune_gain=False).config.observer.rho
    paper, dob = res.rows
    # the paper row ran the tuned design (its noise column is that design's), the DOB the min-error knob
    assert paper["friction_noise_rms"] == pytest.approx(reference_noise_rms(tuned), rel=1e-12)
    est = tune_estimator("dob", cfg, rule="min-error")
    assert dob["friction_noise_rms"] == pytest.approx(friction_noise_rms(est, *noise_level(cfg)), rel=1e-12)
    assert predict_error(reference_estimator(tuned), tuned).total < predict_error(reference_estimator(cfg), cfg).total
    out = tmp_path / "cmp"
    assert main(["compare", "--plants", "paper", "--estimators", "paper,dob", "--scenarios", "excitation",
                 "--seeds", "1", "--workers", "1", "--rule", "min-error", "--out", str(out)]) == 0
    assert json.loads((out / "summary.json").read_text())["rule"] == "min-error"
