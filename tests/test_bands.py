"""Metrics scaled to the axis (issue 33 point 4): the settling band from the sensor, "did not settle",
units that follow the axis, and runs that run away from their task flagged as diverged."""

import contextlib
import dataclasses
import io
import json
import math

import numpy as np
import pytest
import scipy.optimize

import obsdesign as od
from obsdesign.axis import AxisSpec
from obsdesign.cli import main
from obsdesign.loop import bands
from obsdesign.loop.bands import settle_band
from obsdesign.loop.scenarios import Positioning, build_scenario, hold_samples
from obsdesign.sim.metrics import loop_metrics
from obsdesign.sim.step_metrics import settling_sample, step_metrics


def run_cli(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


# --- the band rule -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("q, eta, expected, word", [
    (1e-6, 0.0, 2e-6, "encoder resolution"),
    (4e-6, 0.0, 8e-6, "encoder resolution"),          # scales with the resolution
    (0.0, 1e-6, 3e-6, "noise RMS"),
    (0.0, 5e-7, 1.5e-6, "noise RMS"),                 # scales with the noise
    (1e-6, 1e-6, 3e-6, "noise RMS"),                  # the larger of the two
    (1e-6, 5e-7, 2e-6, "encoder resolution"),
    (0.0, 0.0, 1e-3 * 2.5e-3, "reference span"),     # ideal sensor: 0.1 % of the move
])
def test_band_is_the_larger_of_two_counts_and_three_noise_rms(q, eta, expected, word):
    cfg = od.load_preset("vcm").override(quantization=q, noise_rms=eta)
    b = settle_band(cfg, span=2.5e-3)
    assert b.value == pytest.approx(expected, rel=1e-15) and word in b.rule
    assert settle_band(cfg, span=2.5e-3, given=7e-7) == bands.SettleBand(7e-7, "given")


def test_band_of_a_2_20_counts_encoder_is_two_counts_in_rad():
    """The new-user trial's axis: a fixed 2 urad was a third of a count."""
    rot = dataclasses.replace(od.load_preset("vcm").override(quantization=2 * math.pi / 2**20),
                              axis=AxisSpec(kind="rotary", input="A"))
    b = settle_band(rot, span=1e-3)
    assert b.value == pytest.approx(2 * 2 * math.pi / 2**20, rel=1e-15) and b.rule.endswith(" rad")


def test_band_refuses_an_ideal_sensor_with_a_reference_that_does_not_move():
    cfg = od.load_preset("vcm").override(quantization=0.0, noise_rms=0.0)
    with pytest.raises(ValueError, match="settle_tol: no default band for an ideal sensor"):
        settle_band(cfg, span=0.0)
    code, out, err = run_cli("simulate", "positioning", "--quantization", 0, "--step-size", 0, "--duration", 4)
    assert code == 2 and "settle_tol" in err and "Traceback" not in err


def test_simulate_states_the_band_it_used():
    cfg = od.load_preset("vcm")
    for q in (1e-6, 4e-6):
        m = od.simulate(cfg.override(quantization=q), "positioning", duration=4.0, keep_trace=False).metrics
        assert m["settle_band"] == pytest.approx(2 * q, rel=1e-15)
        assert m["settle_band_rule"] == f"2 x encoder resolution {q:.4g} m"
    m = od.simulate(cfg, "positioning", duration=4.0, settle_tol=5e-6, keep_trace=False).metrics
    assert (m["settle_band"], m["settle_band_rule"]) == (5e-6, "given")
    open_loop = od.simulate(cfg, "constant", duration=0.1, keep_trace=False).metrics
    assert open_loop["settle_band"] is None and open_loop["error_bound"] is None


# --- settling against closed forms ---------------------------------------------------------------------------

def _fake_run(sc, x):
    """The kernel's outputs of a run whose plant follows ``x`` (estimates exact, nothing else moves)."""
    zeros = np.zeros_like(x)
    out = {"x": x, "x_meas": x, "v": zeros, "f": zeros, "v_hat": zeros, "f_hat": zeros, "f_hat_filtered": zeros}
    return loop_metrics(sc, out, sc.x_ref - x, len(x), 2e-6, 0.0, settle_rule="given", force_bound=1.0)


def _hold_response(sc, shape):
    """x: each hold's step answered by ``shape(t since the step)`` (0 -> 1) from the level before it."""
    x = np.zeros(len(sc.x_ref))
    for start, end in sc.holds:
        i0, i1 = hold_samples(start, end, sc.dt, len(x))
        y0 = sc.x_ref[i0 - 1] if i0 > 0 else 0.0
        t = np.arange(i1 - i0) * sc.dt
        x[i0:i1] = y0 + (sc.x_ref[i0] - y0) * shape(t)
    return x


def test_first_order_settles_at_tau_ln_step_over_band():
    dt, tau, band, step = 1e-4, 0.05, 2e-6, 1e-3
    sc = build_scenario(Positioning(step_size=step), dt=dt)
    m = _fake_run(sc, _hold_response(sc, lambda t: 1.0 - np.exp(-t / tau)))
    closed_form = tau * math.log(step / band)  # |e| = step exp(-t / tau) = band
    for t in m["settling_time"]:
        assert closed_form <= t < closed_form + dt   # the first sample inside
    assert m["settled"] == [True, True] and m["steady_state_in_band"] == [True, True]
    assert m["diverged"] is False and m["error_bound"] == pytest.approx(10 * (step + band))


def test_second_order_settles_at_the_last_crossing_of_the_band():
    dt, zeta, wn, band, step = 1e-4, 0.3, 40.0, 2e-6, 1e-3
    wd = wn * math.sqrt(1 - zeta**2)

    def error(t):  # of the analytic step response, relative to the step
        return np.exp(-zeta * wn * t) / math.sqrt(1 - zeta**2) * np.sin(wd * t + math.acos(zeta))

    sc = build_scenario(Positioning(step_size=step), dt=dt)
    m = _fake_run(sc, _hold_response(sc, lambda t: 1.0 - error(t)))
    # the last time |e| = band on the continuous response, by root finding between the envelope's bounds
    grid = np.linspace(0.0, 2.0, 200_001)
    outside = np.abs(step * error(grid)) > band
    k = np.nonzero(outside)[0][-1]
    last = scipy.optimize.brentq(lambda s: abs(step * error(s)) - band, grid[k], grid[k + 1])
    for t in m["settling_time"]:
        assert last <= t < last + dt


def test_a_ripple_that_passes_through_the_band_at_the_end_did_not_settle():
    """A 66 x band ripple whose last samples happen to lie in the band: the old rule gave a settling time near
    the end of the hold; now it did not settle, and the step_metrics of the same samples agree."""
    dt, band, step = 1e-4, 2e-6, 1e-3
    sc = build_scenario(Positioning(step_size=step), dt=dt)
    f = 260.0
    x = _hold_response(sc, lambda t: 1.0 - 0.066 * np.sin(2 * np.pi * f * (t - t[-1])))  # zero at the last sample
    i0, i1 = hold_samples(*sc.holds[0], dt, len(x))
    assert abs(sc.x_ref[i1 - 1] - x[i1 - 1]) <= band          # the last sample of the hold is inside
    m = _fake_run(sc, x)
    assert m["settling_time"] == [None, None] and m["settled"] == [False, False]
    t = np.arange(i0, i1) * dt
    old = step_metrics(t, x[i0:i1], t_step=sc.holds[0][0], y0=0.0, y1=step, settle_band=band)
    assert old["settling_time"] is not None   # python-control's rule (dwell 0): inside at the last sample
    new = step_metrics(t, x[i0:i1], t_step=sc.holds[0][0], y0=0.0, y1=step, settle_band=band,
                       dwell=bands.SETTLE_DWELL)
    assert new["settling_time"] is None


def test_a_response_that_enters_the_band_only_in_the_last_tenth_did_not_settle():
    y = np.concatenate([np.ones(95), np.zeros(5)])   # inside for the last 5 % only
    assert settling_sample(y, 0.0, 0.5) == 95 and settling_sample(y, 0.0, 0.5, dwell=0.1) is None
    y = np.concatenate([np.ones(90), np.zeros(10)])  # exactly the last 10 %
    assert settling_sample(y, 0.0, 0.5, dwell=0.1) == 90


# --- runaway: table1's lag observer in the physical lag plant ------------------------------------------------

@pytest.fixture(scope="module")
def runaway():
    return od.simulate(od.load_preset("table1"), "positioning", controller="pid+observer", plant="physical")


def test_table1_runaway_is_diverged(runaway):
    """1 mm step, the lag observer in the physical lag plant: the loop runs away to several metres at the
    actuator's limit while every state stays within the simulator's absolute bounds."""
    m = runaway.metrics
    cfg = od.load_preset("table1")
    pl = cfg.plant
    assert m["max_error"] > 1.0                                          # metres, for a 1 mm task
    assert np.all(np.isfinite(runaway.x))                                # the kernel did not stop
    assert m["diverged"] is True and m["divergence"] == "runaway"
    assert m["error_bound"] == pytest.approx(10 * (1e-3 + 3 * cfg.sensor.noise_rms), rel=1e-12)
    assert m["estimate_bound"] == pytest.approx(10 * (pl.K * pl.u_max + abs(pl.G) + cfg.friction.Cf), rel=1e-12)
    assert m["settling_time"] == [None, None] and m["settled"] == [False, False]
    # at the limit: full force, sliding at the speed where viscous + Coulomb friction take all of it
    assert np.max(np.abs(runaway.u)) == pytest.approx(pl.K * pl.u_max, rel=1e-12)
    v_limit = (pl.K * pl.u_max - cfg.friction.Cf) / cfg.friction.sigma
    assert abs(runaway.v[-1]) == pytest.approx(v_limit, rel=1e-3)
    text = runaway.text()
    assert "diverged: yes" in text and "runaway (|e| " in text and "did not settle" in text


def test_the_same_design_on_its_model_plant_or_static_does_not_run_away():
    cfg = od.load_preset("table1")
    for c, plant in ((cfg, "model"), (cfg.override(variant="static"), "physical")):
        m = od.simulate(c, "positioning", plant=plant, keep_trace=False).metrics
        assert m["diverged"] is False and m["divergence"] is None and all(m["settled"])


def test_the_cli_says_it_diverged_and_did_not_settle():
    args = ("simulate", "positioning", "--preset", "table1", "--controller", "pid+observer", "--plant", "physical")
    code, out, err = run_cli(*args)
    assert code == 0
    assert "diverged: yes" in out and "divergence: runaway" in out and "settling_time: [did not settle, did not settle]" in out
    assert "settle_band: 3e-06 m (3 x noise RMS 1e-06 m)" in out
    code, out, err = run_cli(*args, "--json")
    m = json.loads(out)
    assert m["diverged"] is True and m["divergence"] == "runaway" and m["settled"] == [False, False]
    assert m["settle_band"] == 3e-6 and m["settle_band_rule"] == "3 x noise RMS 1e-06 m"


def test_a_sweep_counts_the_runaway_as_diverged(tmp_path):
    res = od.sweep(od.load_preset("table1"), "positioning", vary={"noise_rms": (1e-6, 2e-6, 2)}, out_dir=tmp_path,
                   workers=1)
    assert [r["status"] for r in res.rows] == ["diverged", "diverged"]
    assert all(r["error"] == "divergence: runaway" for r in res.rows)
    assert [r["settle_band"] for r in res.rows] == pytest.approx([3e-6, 6e-6])
    from obsdesign.sweeps import make_summary

    summary = make_summary(res.rows, ["noise_rms"], metric="settling_time_1", resumed_runs=0, wall_s=0.0)
    assert summary["diverged"] == 2 and summary["settle_band"] == pytest.approx({"min": 3e-6, "max": 6e-6})


def test_an_estimate_beyond_every_force_is_diverged():
    """Open loop, rho = 0.98 (Proposition 2 violated): the estimate grows without a bound while the plant
    is driven by 1 N; the run is diverged once the filtered estimate passes 10 x the largest force."""
    cfg = od.load_preset("table1").override(rho=0.98, variant="static")
    res = od.simulate(cfg, "constant", stiffness="true", initial_estimate=(0.0, 0.5), duration=5.0)
    m = res.metrics
    assert np.nanmax(np.abs(res.f_hat_filtered)) > m["estimate_bound"]
    assert m["diverged"] is True and m["divergence"] == "estimate"


# --- units follow the axis -----------------------------------------------------------------------------------

def test_metric_units_follow_a_rotary_axis():
    rot = dataclasses.replace(od.load_preset("vcm").override(quantization=2 * math.pi / 2**20),
                              axis=AxisSpec(kind="rotary", input="A"), sources={})
    text = od.simulate(rot, "positioning", duration=4.0, keep_trace=False).text()
    rows = dict(line.strip().split(": ", 1) for line in text.splitlines()[1:])
    assert rows["rms_error"].endswith(" rad") and rows["settle_band"].endswith("(2 x encoder resolution 5.992e-06 rad)")
    assert rows["observer_rms_error_v"].endswith(" rad/s") and rows["observer_rms_error_f"].endswith(" N m")
    assert rows["estimate_bound"].endswith(" N m") and rows["error_bound"].endswith(" rad")
    assert " m" not in rows["rms_error"].replace(" rad", "")
