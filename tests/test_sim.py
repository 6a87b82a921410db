"""Simulator: friction closed forms, integrator order, exact observer discretization, closed loop."""

import dataclasses
import math

import numpy as np
import pytest
import scipy.linalg

import obsdesign as od
from obsdesign.design.discretize import coefficient_matrices, step_matrices
from obsdesign.friction.presliding import coulomb, coulomb_normalized, presliding_shape, stiffness, track_reversal
from obsdesign.sim import COLUMNS, kernel

TABLE1 = od.load_preset("table1")
VCM = od.load_preset("vcm")
CF, S = 0.35, 3000.0


# --- friction model -------------------------------------------------------------------------

@pytest.mark.parametrize("direction", [1.0, -1.0])
@pytest.mark.parametrize("f_r", [-1.0, -0.3, 0.0, 0.6, 1.0])
def test_coulomb_is_continuous_at_the_end_of_presliding(direction, f_r):
    x_edge = direction / S  # |z| = 1
    inside = coulomb(x_edge * (1 - 1e-12), direction, 0.0, f_r, CF, S)
    outside = coulomb(x_edge * (1 + 1e-12), direction, 0.0, f_r, CF, S)
    assert inside == pytest.approx(CF * direction, abs=1e-9) and outside == CF * direction


@pytest.mark.parametrize("direction, f_r, z", [(1.0, -1.0, 0.2), (-1.0, 0.4, -0.05), (1.0, 0.9, 1e-6), (-1.0, -0.2, -0.999)])
def test_presliding_branch_closed_form(direction, f_r, z):
    x_r = 0.0
    expected = CF * (abs(direction - f_r) * z * (1 - math.log(abs(z))) + f_r)  # eq:2:3:3-4
    assert coulomb(x_r + z / S, direction, x_r, f_r, CF, S) == pytest.approx(expected, rel=1e-12)
    # eq:2:3:5 with the chain rule, against a central difference
    k = stiffness(x_r + z / S, direction, x_r, f_r, CF, S, 1e12)
    dx = min(abs(z), 1 - abs(z)) / S * 1e-3
    fd = (coulomb(x_r + z / S + dx, direction, x_r, f_r, CF, S) - coulomb(x_r + z / S - dx, direction, x_r, f_r, CF, S)) / (2 * dx)
    assert k == pytest.approx(fd, rel=1e-5)
    assert k == pytest.approx(-S * CF * abs(direction - f_r) * math.log(abs(z)), rel=1e-12)


def test_shape_has_its_exact_limit_at_zero_and_stiffness_is_bounded():
    assert presliding_shape(0.0) == 0.0
    assert abs(presliding_shape(1e-300)) < 1e-296
    assert stiffness(0.0, 1.0, 0.0, -1.0, CF, S, 8000.0) == 8000.0  # infinite at z = 0, bounded by kappa
    assert stiffness(1.0, 1.0, 0.0, -1.0, CF, S, 8000.0) == 0.0  # gross sliding


def test_reversal_memory():
    # Moving +, reverse at x = 1e-4 (z = 0.3): the memory is the friction there.
    d, xr, fr = track_reversal(1.0, 0.0, 0.0, 0.0, 0.0, S)
    assert (d, xr, fr) == (1.0, 0.0, 0.0)
    f_at = coulomb_normalized(1e-4, d, xr, fr, S)
    d, xr, fr = track_reversal(-1e-9, 1e-4, d, xr, fr, S)
    assert (d, xr) == (-1.0, 1e-4) and fr == f_at == pytest.approx(0.3 * (1 - math.log(0.3)), rel=1e-12)
    # Continuity through the reversal and the new branch bends towards -1.
    assert coulomb_normalized(1e-4, d, xr, fr, S) == f_at
    assert coulomb_normalized(1e-4 - 1 / S, d, xr, fr, S) == -1.0
    # v = 0 keeps the branch.
    assert track_reversal(0.0, 5.0, d, xr, fr, S) == (d, xr, fr)


def _open_loop(u_open, *, substeps=10, cfg=VCM):
    """Run the kernel on an arbitrary open-loop force sequence (dt 1e-4 s)."""
    n = len(u_open)
    loop = od.sim.prepare(cfg.override(quantization=0.0), "constant", duration=n * cfg.observer.dt,
                          substeps=substeps, stiffness="true")
    loop = dataclasses.replace(loop, u_open=np.asarray(u_open, float))
    out = kernel.empty_outputs(n)
    assert kernel.run_loop(*loop.kernel_args(), out) == n
    return out._asdict()


def test_free_motion_stops_in_finite_time():
    """A push, then u = 0: Coulomb friction stops the slide in the closed-form finite time
    t* = (m/sigma) ln(1 + sigma v0 / Cf); afterwards the mass stays within the pre-sliding
    distance 1/s of where it stopped, and its pre-sliding oscillation dies out."""
    dt, n, push = 1e-4, 15000, 500
    u = np.zeros(n)
    u[:push] = 1.0  # 50 ms push of 1 N reaches gross sliding
    out = _open_loop(u)
    v, x = out["v"][push:], out["x"][push:]
    m, sigma = 0.538, 21.1
    t_star = m / sigma * math.log(1 + sigma * v[0] / CF)
    i = np.argmax(v <= 0)  # first stop, linear interpolation between samples
    t_stop = (i - 1 + v[i - 1] / (v[i - 1] - v[i])) * dt
    assert t_stop == pytest.approx(t_star, abs=2e-6)
    x_stop = x[i]
    assert np.max(np.abs(x[i:] - x_stop)) < 1 / S
    reversals = np.nonzero(np.diff(np.sign(v[i:][np.abs(v[i:]) > 0])))[0]
    assert len(reversals) >= 5 and np.all(np.diff(reversals) > 0)
    assert np.max(np.abs(v[12000:])) < 1e-12  # at rest 1.2 s after the push


def test_integrator_is_second_order():
    """Heun substeps: the error of x(0.3 s) against a fine reference falls 4x per halving of h."""
    u = np.full(3000, 1.0)
    ref = _open_loop(u, substeps=512)["x"][-1]
    errs = [abs(_open_loop(u, substeps=n)["x"][-1] - ref) for n in (1, 2, 4, 8)]
    orders = [math.log2(a / b) for a, b in zip(errs[:-1], errs[1:])]
    assert all(1.8 < p < 2.3 for p in orders), (errs, orders)


# --- observer discretization ----------------------------------------------------------------

@pytest.mark.parametrize("cfg, k", [(TABLE1, 0.0), (TABLE1, 8000.0), (VCM, 8000.0), (VCM, 3000.0),
                                     (VCM.override(kappa=2.4e7), 2.4e7), (TABLE1.override(rho=0.98), 316.0)])
def test_discretization_is_exact_for_held_input_and_linear_measurement(cfg, k):
    d = od.design_observer(cfg)
    A, b, g = d.matrices(k)
    h, u, x0, c = cfg.observer.dt, 0.7, 1e-3, 0.05
    # Continuous solution by one matrix exponential of the augmented system (y, x, 1).
    M = np.zeros((4, 4))
    M[:2, :2], M[:2, 2], M[:2, 3] = A, g, b * u
    M[2, 3] = c
    y0 = np.array([0.3, -2.0])
    exact = scipy.linalg.expm(M * h) @ np.array([*y0, x0, 1.0])
    Phi, bu, gx0, gx1 = step_matrices(A, b, g, h)
    ours = Phi @ y0 + bu * u + gx0 * x0 + gx1 * (x0 + c * h)
    np.testing.assert_allclose(ours, exact[:2], rtol=1e-11, atol=1e-12 * np.abs(exact[:2]).max())


def test_confluent_pole_needs_no_special_case():
    d = od.design_observer(VCM)
    A = d.matrices(d.kappa)[0]
    lam = np.linalg.eigvals(A)
    assert abs(lam[0] - lam[1]) < 1e-6 * abs(lam[0])  # the designed double pole
    Phi, G0, G1 = coefficient_matrices(A, 1e-4)
    np.testing.assert_allclose(Phi, scipy.linalg.expm(A * 1e-4), rtol=1e-13, atol=1e-15)


def test_steady_sliding_adds_no_bias():
    res = od.simulate(VCM.override(quantization=0.0), od.sim.ConstantForce(force=1.0), stiffness="true")
    tail = slice(-1000, None)
    assert np.max(np.abs(res.f_hat[tail] - res.f[tail])) < 1e-9
    assert np.max(np.abs(res.v_hat[tail] - res.v[tail])) < 1e-12
    assert res.f[-1] == pytest.approx(0.35)  # Coulomb level in steady sliding (static variant: w3 = Fc)


@pytest.mark.parametrize("rho, sign", [(1.02, -1.0), (0.98, 1.0)])
def test_error_in_steady_sliding_decays_or_grows_at_the_designed_eigenvalue(rho, sign):
    cfg = TABLE1.override(variant="static", noise_rms=0.0)
    res = od.simulate(cfg.override(rho=rho), od.sim.ConstantForce(force=1.0), stiffness="true",
                      initial_estimate=(0.0, 0.5))
    t = res.t
    window = (t > 1.0) & (t < 3.0)
    err = np.abs(res.f_hat - res.f)[window]
    slope = np.polyfit(t[window], np.log(err), 1)[0]
    expected = sign * math.sqrt(8000 / 0.538) * abs(rho - 1)  # eq:3:3:2, +-2.44 1/s
    assert slope == pytest.approx(expected, rel=0.05)


def test_stiff_kappa_stays_stable_at_10_khz():
    cfg = VCM.override(kappa=2.4e7, quantization=0.0)
    with pytest.warns(UserWarning, match="faster than the sampling"):
        assert abs(od.check_stability(cfg).fastest_pole) * cfg.observer.dt > 3  # poles far beyond the sampling rate
    res = od.simulate(cfg.override(rho=4.0), od.sim.ConstantForce(force=1.0))
    assert not res.metrics["diverged"]
    assert abs(res.f_hat[-1] - res.f[-1]) < 1e-6


def test_divergence_is_reported_not_raised():
    res = od.simulate(TABLE1.override(variant="static", rho=0.5), od.sim.ConstantForce(force=1.0), duration=3.0)
    assert res.metrics["diverged"] is True
    assert np.isnan(res.x[-1]) and np.isfinite(res.x[0])


# --- closed loop ----------------------------------------------------------------------------

def test_observer_compensation_settles_faster_on_positioning():
    pid = od.simulate(VCM, "positioning", controller="pid").metrics
    obs = od.simulate(VCM, "positioning", controller="pid+observer").metrics
    for a, b in zip(obs["settling_time"], pid["settling_time"]):
        assert a is not None and (b is None or a < b)


def test_observer_compensation_tracks_with_lower_rms():
    pid = od.simulate(VCM, "tracking", controller="pid", keep_trace=False).metrics
    obs = od.simulate(VCM, "tracking", controller="pid+observer", keep_trace=False).metrics
    assert obs["rms_error"] < pid["rms_error"]
    assert all(obs["rms_error_per_band"][b] < pid["rms_error_per_band"][b] for b in pid["rms_error_per_band"])


def test_noise_rms_matches_the_design_prediction():
    """Issue 3's RMS prediction against the simulator, in steady sliding (k = 0)."""
    eta, B = 1e-6, 1000.0
    res = od.simulate(VCM.override(noise_rms=eta, noise_bandwidth=B, quantization=0.0), od.sim.ConstantForce(force=1.0),
                      seed=3)
    pred = od.noise_analysis(VCM, noise_rms=eta, noise_bandwidth=B)
    keep = res.t > 0.5
    assert np.all(res.stiffness[keep] == 0.0)  # no spurious reversals
    raw = np.sqrt(np.mean((res.f_hat - res.f)[keep] ** 2))
    filt = np.sqrt(np.mean((res.f_hat_filtered - res.f)[keep] ** 2))
    assert raw == pytest.approx(pred.rms_raw, rel=0.05)
    assert filt == pytest.approx(pred.rms_filtered, rel=0.15)


def test_trace_export(tmp_path):
    res = od.simulate(VCM, od.sim.Positioning(step_down=0.8), duration=1.0)
    res.to_csv(tmp_path / "trace.csv")
    res.to_npz(tmp_path / "trace.npz")
    data = np.genfromtxt(tmp_path / "trace.csv", delimiter=",", names=True)
    assert data.dtype.names == COLUMNS and len(data) == 10000
    np.testing.assert_array_equal(data["f_hat"], res.f_hat)
    with np.load(tmp_path / "trace.npz") as z:
        assert tuple(z.files) == COLUMNS
        np.testing.assert_array_equal(z["e"], res.x_ref - res.x)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["trace.csv", "trace.npz"]
    # Row semantics: the measurement of sample k is the encoder reading of x at t[k].
    np.testing.assert_array_equal(res.x_meas, 1e-6 * np.floor(res.x / 1e-6 + 0.5))


def test_seeded_noise_is_reproducible():
    a = od.simulate(TABLE1, "excitation", duration=1.0, seed=5)
    b = od.simulate(TABLE1, "excitation", duration=1.0, seed=5)
    c = od.simulate(TABLE1, "excitation", duration=1.0, seed=6)
    np.testing.assert_array_equal(a.x_meas, b.x_meas)
    assert not np.array_equal(a.x_meas, c.x_meas)


def test_band_limited_noise_has_no_power_above_its_band():
    x = od.sim.band_limited_noise(100_000, 1e-4, 1e-6, 500.0, seed=1)
    spec = np.abs(np.fft.rfft(x)) ** 2
    f = np.fft.rfftfreq(x.size, 1e-4)
    assert spec[f > 500.0].sum() < 1e-20 * spec.sum()
    # 5000 kept frequency bins: the sample RMS scatters by about 0.7 % around its expectation.
    assert np.sqrt(np.mean(x * x)) == pytest.approx(1e-6, rel=0.03)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(scenario="walk"), ValueError, r"scenario: expected one of excitation, constant, positioning, tracking, found 'walk'"),
        (dict(scenario="constant", controller="pid"), ValueError, r"controller: scenario 'constant' needs 'open-loop', found 'pid'"),
        (dict(scenario="tracking", controller="lqr"), ValueError, r"controller: expected one of open-loop, pid, pid\+observer, found 'lqr'"),
        (dict(scenario="constant", stiffness="guess"), ValueError, r"stiffness: expected one of estimated, true, constant, estimated-raw, found 'guess'"),
        (dict(scenario="constant", plant="real"), ValueError, r"plant: expected one of physical, model, found 'real'"),
        (dict(scenario="constant", duration=-1.0), ValueError, r"duration: expected a finite number > 0, found -1\.0"),
        (dict(scenario=od.sim.Positioning(step_up=4.0)), ValueError, r"step_down: expected step_up < step_down < duration"),
        (dict(scenario="constant", substeps=0), ValueError, r"substeps: expected an integer >= 1 and <= 1000, found 0"),
    ],
)
def test_simulate_rejects_bad_input(kwargs, exc, match):
    scenario = kwargs.pop("scenario")
    with pytest.raises(exc, match=match):
        od.simulate(VCM, scenario, **kwargs)


def test_overrides_go_through_the_config():
    with pytest.raises(ValueError, match=r"observer\.rho: .*found nan"):
        od.simulate(VCM.override(rho=float("nan")), "constant")


def test_simulate_is_run_of_prepare():
    loop = od.sim.prepare(TABLE1, "excitation", duration=0.5, seed=4)
    a, b = od.sim.run(loop), od.simulate(TABLE1, "excitation", duration=0.5, seed=4)
    for name in COLUMNS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert {k: v for k, v in a.metrics.items() if k != "sim_wall_s"} == \
        {k: v for k, v in b.metrics.items() if k != "sim_wall_s"}


@pytest.mark.parametrize("kw, name, found", [({"duration": 3.00002}, "duration", 0), ({"duration": 3.00015}, "duration", 1),
                                             ({"step_down": 0.50005}, "step_down", 0)])
def test_a_hold_shorter_than_two_samples_is_refused_naming_its_end(kw, name, found):
    """dt = 1e-4 s: a hold from 3 s to 3.00002 s has no sample, to 3.00015 s one (3.0001 s); before, the
    first ended in an IndexError of the metrics, the second in step_metrics' 't: expected at least 2 samples'."""
    from obsdesign.loop.scenarios import Positioning

    spec = Positioning(step_size=1e-3, step_up=0.5, step_down=kw.get("step_down", 3.0))
    with pytest.raises(ValueError, match=rf"^{name}: expected a hold of at least 2 samples .* found {found} "):
        od.simulate(od.load_preset("vcm"), spec, duration=kw.get("duration", 4.0))
