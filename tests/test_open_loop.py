"""obsdesign.sim.open_loop: runs sharing an open-loop plant equal the runs made one by one, bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import obsdesign as od
from obsdesign.comparison import plant_config
from obsdesign.sim import prepare, run
from obsdesign.sim.open_loop import run_shared, shares_plant
from obsdesign.sim.result import COLUMNS

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
