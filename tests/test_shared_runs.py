"""obsdesign.sim.shared: identical runs made once and runs sharing an open-loop plant equal the runs made one
by one, bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import obsdesign as od
from obsdesign.comparison import plant_config
from obsdesign.sim import prepare, run
from obsdesign.sim.result import COLUMNS
from obsdesign.sim.shared import run_shared, same_run, shares_plant

FIELDS = (*COLUMNS, "stiffness")


def assert_same(a, b):
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=name)
    ma = {k: v for k, v in a.metrics.items() if k != "sim_wall_s"}
    mb = {k: v for k, v in b.metrics.items() if k != "sim_wall_s"}
    assert ma.keys() == mb.keys()
    for k in ma:
        np.testing.assert_equal(ma[k], mb[k], err_msg=k)
    assert (a.estimator, a.controller, a.stiffness_schedule) == (b.estimator, b.controller, b.stiffness_schedule)


@pytest.mark.parametrize("plant", ["paper", "lugre", "gms"])
@pytest.mark.parametrize("preset", ["vcm", "table1"])
def test_every_estimator_over_one_plant_equals_its_own_run(preset, plant):
    cfg = od.load_preset(preset)
    pc = plant_config(cfg, plant)
    loops = [prepare(cfg, "excitation", plant=pc, estimator=e, duration=0.8, seed=s)
             for s in (0, 1) for e in ("paper", "paper-k0", "eso", "kalman", "dob")]
    for shared, loop in zip(run_shared(loops), loops):
        assert_same(shared, run(loop))


@pytest.mark.parametrize("options", [
    {"stiffness": "constant"},
    {"stiffness": "estimated-raw"},
    {"initial_estimate": (0.01, 0.2)},
])
def test_schedules_and_initial_estimates(options):
    cfg = od.load_preset("vcm")
    loops = [prepare(cfg, "excitation", duration=0.5, seed=2, **options),
             prepare(cfg, "excitation", duration=0.5, seed=2, estimator="kalman")]
    assert shares_plant(*loops)
    for shared, loop in zip(run_shared(loops), loops):
        assert_same(shared, run(loop))


def test_delay_quantization_and_saturation_are_the_plant_s():
    # a computation delay, an encoder and a command that saturates: all on the plant's side of the run
    vcm = od.load_preset("vcm")
    u_max = vcm.plant.G / vcm.plant.K + 0.1  # 0.1 V above the load's feed-forward: the excitation hits it
    cfg = vcm.override(delay_samples=3, quantization=1e-6, u_max=u_max)
    loops = [prepare(cfg, "excitation", estimator=e, duration=0.5, seed=4) for e in ("paper", "eso", "dob")]
    res = run_shared(loops)
    saturated = np.mean(res[0].u == cfg.plant.K * u_max - cfg.plant.G)
    assert 0.01 < saturated < 0.99
    for shared, loop in zip(res, loops):
        assert_same(shared, run(loop))


def test_a_diverging_estimate_stops_its_run_where_the_loop_stops_it():
    cfg = od.load_preset("vcm")
    good = prepare(cfg, "excitation", duration=0.3)
    bad = prepare(cfg, "excitation", duration=0.3, initial_estimate=(0.0, 2e12))  # |f_hat| >= 1e12 at once
    assert shares_plant(good, bad)
    shared = run_shared([good, bad])
    alone = run(bad)
    assert alone.metrics["diverged"] and np.isnan(alone.x[1:]).all()
    assert_same(shared[1], alone)
    assert_same(shared[0], run(good))
    # the diverging run leading: the others run in the loop
    shared = run_shared([bad, good])
    assert_same(shared[0], alone)
    assert_same(shared[1], run(good))


def test_what_does_not_share_runs_alone():
    cfg = od.load_preset("vcm")
    base = prepare(cfg, "excitation", duration=0.3)
    other_seed = prepare(cfg, "excitation", duration=0.3, seed=1)
    other_plant = prepare(cfg, "excitation", duration=0.3, plant=plant_config(cfg, "dahl"))
    true_schedule = prepare(cfg, "excitation", duration=0.3, stiffness="true")
    closed = prepare(cfg, "positioning", duration=4.0)
    heavier = prepare(cfg, "excitation", duration=0.3, plant=cfg.override(m=cfg.plant.m * 2))
    assert not any(shares_plant(base, x) for x in (other_seed, other_plant, true_schedule, closed, heavier))
    # another actuator gain on the plant's side: its u is not the net force the estimator is fed
    gain = dataclasses.replace(base, K_plant=base.K_plant * 1.1)
    assert not shares_plant(base, gain)
    gain_eso = dataclasses.replace(prepare(cfg, "excitation", duration=0.3, estimator="eso"), K_plant=gain.K_plant)
    assert not shares_plant(gain, gain_eso)
    loops = [base, other_seed, other_plant, true_schedule, closed, gain, heavier, gain_eso]
    for shared, loop in zip(run_shared(loops), loops):
        assert_same(shared, run(loop))


def test_refuses_what_is_not_loop_inputs():
    with pytest.raises(TypeError, match=r"loops\[1\]: expected LoopInputs"):
        run_shared([prepare(od.load_preset("vcm"), "excitation", duration=0.1), "excitation"])


def test_identical_runs_are_made_once_and_each_result_is_its_own():
    cfg = od.load_preset("vcm")  # quantization only: the seed draws nothing in a closed-loop scenario
    loops = [prepare(cfg, scenario, estimator=e, seed=s, duration=d)
             for scenario, d in (("positioning", 4.0), ("tracking", 1.0)) for e in ("paper", "kalman") for s in (0, 1)]
    assert same_run(loops[0], loops[1]) and not same_run(loops[0], loops[2])
    calls = []
    import obsdesign.sim.shared as shared

    real = shared.run_kernel

    def counted(loop):
        calls.append(loop)
        return real(loop)

    shared.run_kernel = counted
    try:
        res = run_shared(loops)
    finally:
        shared.run_kernel = real
    assert len(calls) == 4  # one run per scenario and estimator
    for got, loop in zip(res, loops):
        assert_same(got, run(loop))
    res[1].x[:] = 0.0  # a result's arrays are its own
    assert not np.array_equal(res[0].x, res[1].x)


@pytest.mark.parametrize("change", ["noise", "negative zero", "negative zero scalar", "settle band", "scenario"])
def test_a_run_that_differs_in_one_bit_is_not_the_same_run(change):
    cfg = od.load_preset("vcm")
    a = prepare(cfg, "positioning", duration=4.0)
    if change == "noise":
        b = prepare(cfg.override(noise_rms=1e-9), "positioning", duration=4.0)
    elif change == "negative zero":  # -0.0 == 0.0 in Python, not for the kernel's sign tests
        x_ref = a.x_ref.copy()
        x_ref[0] = -0.0
        b = dataclasses.replace(a, x_ref=x_ref)
    elif change == "negative zero scalar":  # same bits or not the same run, whatever the kernel makes of it
        a = prepare(cfg.override(quantization=0.0), "positioning", duration=4.0)
        b = dataclasses.replace(a, quantization=-0.0)
    elif change == "settle band":
        b = prepare(cfg, "positioning", duration=4.0, settle_tol=3e-6)
    else:
        b = prepare(cfg, od.sim.Positioning(step_down=3.0000000001), duration=4.0)
    assert not same_run(a, b)
    for got, loop in zip(run_shared([a, b]), [a, b]):
        assert_same(got, run(loop))


def test_identical_diverging_runs_stop_alike():
    cfg = od.load_preset("vcm")
    loops = [prepare(cfg, "tracking", duration=0.5, initial_estimate=(0.0, 2e12), seed=s) for s in (0, 1)]
    assert same_run(*loops)
    for got, loop in zip(run_shared(loops), loops):
        alone = run(loop)
        assert alone.metrics["diverged"]
        assert_same(got, alone)
