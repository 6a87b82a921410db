"""Output-error refinement of dynamic friction (obsdesign.data.output_error, obsdesign.data.oe_plant)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import obsdesign as od
from obsdesign.data import Trace, identify, load_trace
from obsdesign.data.oe_plant import simulate_windows
from obsdesign.data.output_error import refinable, refine
from obsdesign.sim import prepare, run

EMPS = Path(__file__).resolve().parents[2] / "shared" / "data" / "emps" / "DATA_EMPS.mat"


def _open_loop(cfg, seconds=2.0, seed=1):
    loop = prepare(cfg, od.sim.Excitation(force_rms=3.0), duration=seconds, seed=seed)
    return run(loop), loop


def test_window_plant_is_the_simulators_plant():
    """One window from rest over a whole open-loop run reproduces run_loop's plant displacement."""
    cfg = od.load_preset("vcm").override(noise_rms=0.0, quantization=0.0, G=0.0)
    res, loop = _open_loop(cfg)
    n = res.x.size
    pp = np.array([0.35, 0.35, 21.1, 21.1, 0.0, 3000.0, 0.0, 8000.0])
    out = np.empty(n)
    # from rest: the window's branch starts saturated in no direction (v0 = 0), as run_loop's does
    ok = simulate_windows(0, pp, res.u, np.array([0]), np.array([n]), np.zeros(1), np.zeros(1), np.zeros(1),
                          cfg.plant.m,
                          cfg.observer.dt, loop.n_sub, 1e-3, out)
    assert ok
    np.testing.assert_allclose(out, res.x, rtol=0, atol=1e-12)


@pytest.mark.parametrize("model", ["lugre", "gms"])
def test_window_plant_of_a_friction_model_is_the_simulators(model):
    from obsdesign.loop.plant import plant_friction_arrays
    from obsdesign.plant_spec import PlantFrictionSpec

    cfg = od.load_preset("vcm").override(noise_rms=0.0, quantization=0.0, G=0.0)
    cfg = dataclasses.replace(cfg, plant_friction=PlantFrictionSpec(model=model, parameters={}))
    res, loop = _open_loop(cfg)
    code, pp = plant_friction_arrays(cfg)
    out = np.empty(res.x.size)
    assert simulate_windows(code, pp, res.u, np.array([0]), np.array([res.x.size]), np.zeros(1), np.zeros(1), np.zeros(1),
                            cfg.plant.m, cfg.observer.dt, loop.n_sub, 1e-3, out)
    np.testing.assert_allclose(out, res.x, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kw, exc, match", [
    (dict(parameters=("s", "nope")), ValueError, "parameters: expected distinct names of"),
    (dict(parameters=("s", "s")), ValueError, "parameters: expected distinct names"),
    (dict(model="dahl"), ValueError, "model: expected one of paper, lugre, gms"),
    (dict(travel=0.0), ValueError, r"travel: expected a number in \(0, 1\]"),
    (dict(substeps=0), ValueError, r"substeps: expected an integer in \[1, 1000\]"),
])
def test_bad_input(kw, exc, match):
    cfg = od.load_preset("vcm").override(G=0.0)
    res, _ = _open_loop(cfg)
    tr = Trace(t=res.t, position=res.x_meas, force=res.u, sample_time=cfg.observer.dt)
    with pytest.raises(exc, match=match):
        refine(tr, identify(tr), **kw)


def test_refinable_names_come_from_the_registry():
    from obsdesign.friction.registry import FRICTION_MODELS

    lugre = set(FRICTION_MODELS["lugre"].scalar_parameters()) - {"Cf_neg", "sigma_neg"}
    assert set(refinable("lugre", "windows")) == lugre | {"m", "delay"}
    assert set(refinable("lugre")) == lugre | {"m"}          # the segment fit: the delay as identify found it


@pytest.mark.skipif(not EMPS.exists(), reason="EMPS data not present")
def test_emps_what_is_identifiable():
    """docs/measured-data.md, "On EMPS": s alone is not; with the Coulomb level and the offset (asymmetric fit) it is."""
    tr = load_trace(EMPS, position="qm", input="vir", time="t", input_gain=35.15065188)
    ident = identify(tr)
    alone = refine(tr, ident, parameters=("s",))
    assert not alone["s"].identifiable and alone["s"].high / alone["s"].low > 100
    joint = refine(tr, ident, parameters=("s", "Cf", "offset"))
    assert joint.rms < 0.25 * alone.rms          # the Coulomb level at the reversals explains the windows, not s
    # the Coulomb level at the reversals lies below the sliding fit's (19.45 against 20.40 N); with the held m and
    # sigma's 95 % intervals carried (oe_stats.held_std) its interval reaches 20.55 N, just above
    assert joint["Cf"].identifiable and joint["offset"].identifiable and joint["Cf"].value < ident.Cf
    asym = refine(tr, identify(tr, model="asymmetric"), parameters=("s", "Cf", "offset"))
    assert asym["s"].identifiable and 2e4 < asym["s"].value < 6e4


LOG = Path(od.__file__).parent / "datasets" / "example_log.csv"


@pytest.mark.parametrize("extra, flag", [
    (["--refine", "s,bogus"], "--refine"), (["--refine", "s,,m"], "--refine"), (["--refine", "s,s"], "--refine"),
    (["--refine", "s", "--refine-model", "dahl"], "--refine-model"),
])
def test_cli_refine_bad_input(extra, flag, tmp_path, capsys):
    from obsdesign.cli import main

    out = tmp_path / "axis.toml"
    args = ["identify", str(LOG), "--position", "x", "--input", "u", "--time", "t", "-o", str(out)]
    assert main(args + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"argument {flag}:" in err[0], err
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not EMPS.exists(), reason="EMPS data not present")
def test_cli_refine_json_and_config(tmp_path, capsys):
    import json

    from obsdesign.cli import main

    out = tmp_path / "emps.toml"
    args = ["identify", str(EMPS), "--position", "qm", "--input", "vir", "--time", "t", "--input-gain",
            "35.15065188", "--asymmetric", "--refine", "s,Cf,offset", "--json", "-o", str(out)]
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    s = data["refinement"]["parameters"]["s"]
    assert s["identifiable"] and s["low"] < s["value"] < s["high"]
    assert data["s"] == pytest.approx(s["value"]) and "output error" in data["s_note"]
    assert od.load_config(out).friction.s == pytest.approx(s["value"])


@pytest.mark.skipif(not EMPS.exists(), reason="EMPS data not present")
def test_emps_lugre_stiffness_with_the_coulomb_level_free():
    """A refined Cf moves the held Fs with it (Fs >= Cf); sigma0 is bounded within 1e6 to 5e6 N/m (at the edge of
    the factor-1.65 rule: identifiable with the held parameters' intervals before identify widened them by the
    change without the rows near the reversals, 1.66e6 to 4.44e6; docs/measured-data.md), sigma1 with it is not."""
    tr = load_trace(EMPS, position="qm", input="vir", time="t", input_gain=35.15065188)
    ident = identify(tr, model="asymmetric")
    ref = refine(tr, ident, parameters=("sigma0", "Cf", "offset"), model="lugre", method="windows")
    s0 = ref["sigma0"]
    assert 1e6 < s0.low < s0.value < s0.high < 5e6 and s0.high / s0.low < 1.65**2 * 1.05
    assert ref.fixed["Fs"] == pytest.approx(ident.Cf_pos)   # the start; the fit moved it with Cf
    both = refine(tr, ident, parameters=("sigma0", "sigma1", "Cf", "offset"), model="lugre", method="windows")
    assert not both["sigma0"].identifiable and not both["sigma1"].identifiable


def _synthetic(model, truth, seed=3):
    """The identification experiment (travel 1 mm, 4 blocks) in closed loop with the package's PID on the VCM axis,
    the plant's friction ``model`` with the parameters ``truth`` (no Stribeck drop: ``Fs = Cf``), 0.2 um noise,
    0.1 um encoder steps; the static fit on the staircase, the whole record for the refinement."""
    from obsdesign.data.experiment import design_experiment
    from obsdesign.plant_spec import PlantFrictionSpec

    cfg = od.load_preset("vcm").override(noise_rms=2e-7, quantization=1e-7)
    plant = dataclasses.replace(cfg, plant_friction=PlantFrictionSpec(model=model, parameters=truth))
    exp = design_experiment(stroke=0.04, speed=0.05, force=32.8, mass=0.538, dt=1e-4, travel=1e-3, resolution=1e-7,
                            blocks=4)
    n = exp.x_ref.size
    loop = prepare(cfg, "tracking", controller="pid", duration=n * exp.dt, seed=seed, plant=plant)
    res = run(dataclasses.replace(loop, x_ref=exp.x_ref, u_open=np.zeros(n)))
    force = res.u + cfg.plant.G  # the actuator force (run_loop's u is net of the load)
    ne = exp.staircase_end
    # the static start read as logged, no delay (as written): the refinement holds m at the static fit's, and the
    # timing identify finds here (held: m -0.49 % instead of -0.27 % on this closed loop with its noise fed back)
    # moves the refined delay to 0.83 samples, which absorbs that mass error (issue 32, reported)
    static = identify(Trace(t=res.t[:ne], position=res.x_meas[:ne], force=force[:ne], sample_time=exp.dt),
                      input_timing="sample", delay_samples=0)
    return Trace(t=res.t, position=res.x_meas, force=force, sample_time=exp.dt), static


def _recovered(ref, truth, rel):
    for name, value in truth.items():
        p = ref[name]
        assert p.identifiable, (name, p.note)
        assert p.value == pytest.approx(value, rel=rel[name]), name
        assert p.low <= value <= p.high, (name, p.low, p.high)


@pytest.mark.slow
def test_synthetic_lugre_sigma0_sigma1_and_zero_delay_recovered():
    """docs/measured-data.md, "Synthetic truth": LuGre sigma0 = 2e5 N/m, sigma1 = 400 N s/m; a delay of 0 found as 0."""
    truth = dict(sigma0=2e5, sigma1=400.0, Fs=0.35)
    tr, static = _synthetic("lugre", truth)
    # the Coulomb level and the offset free with them: held at the static fit (0.06 % low) they bias sigma0
    both = refine(tr, static, parameters=("sigma0", "sigma1", "Cf", "offset"), model="lugre", method="windows")
    _recovered(both, dict(sigma0=2e5, sigma1=400.0, Cf=0.35, offset=5.27),
               dict(sigma0=0.05, sigma1=0.25, Cf=0.005, offset=0.001))
    delay = refine(tr, static, parameters=("sigma0", "Cf", "offset", "delay"), model="lugre",
                   initial={"sigma1": 400.0}, method="windows")
    _recovered(delay, dict(sigma0=2e5, Cf=0.35), dict(sigma0=0.05, Cf=0.005))
    d = delay["delay"]
    # the interval is about 5 samples wide since the held m and sigma carry their 95 % intervals (oe_stats.held_std;
    # 2.0 with their standard errors alone, 3 before identify widened m's by the change without the rows near the
    # staircase's reversals, +9 %), and says so: "wider than one sample"
    assert d.low <= 0.0 <= d.high and d.high - d.low < 6.0 * tr.sample_time and abs(d.value) < tr.sample_time
    assert d.identifiable == (d.high - d.value <= tr.sample_time)


@pytest.mark.slow
def test_synthetic_gms_stiffness_recovered_and_c_flagged():
    """GMS K = 2e5 N/m recovered with the Coulomb level first; C (the slip relaxation rate) does not enter a plant
    without a Stribeck drop (the slip target alpha_i Cf is constant), so it must be flagged not identifiable."""
    truth = dict(K=2e5, C=20.0, Fs=0.35)
    tr, static = _synthetic("gms", truth)
    ref = refine(tr, static, parameters=("Cf", "offset", "K"), model="gms")
    _recovered(ref, dict(K=2e5, Cf=0.35, offset=5.27), dict(K=0.05, Cf=0.005, offset=0.001))
    null = refine(tr, static, parameters=("K", "C"), model="gms", initial={"C": 50.0})
    assert not null["C"].identifiable and "near-null" in null["C"].note and null.condition_number > 1e4
