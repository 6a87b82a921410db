"""Tests of obsdesign.estimators: designs against closed forms, the paper entry against the
kernel, unbiasedness on a linear plant, and the equal-noise tuning computed two ways."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
import scipy.linalg
import scipy.signal

import obsdesign as od
from obsdesign.design.discretize import step_matrices
from obsdesign.estimators import (
    ESTIMATORS,
    build,
    build_dob,
    build_eso,
    build_kalman,
    build_paper,
    dob_continuous,
    eso_gains,
    estimator_step,
    friction_noise_rms,
    noise_level,
    paper_dominant_pole,
    q_filter,
    reference_estimator,
    reference_noise_rms,
    run_offline,
    tune,
    with_lowpass,
)
from obsdesign.estimators.eso import eso_continuous
from obsdesign.estimators.kalman import kalman_model
from obsdesign.estimators.tuning import estimate_noise_rms
from obsdesign.sim import band_limited_noise

PRESETS = {"table1-static": lambda: od.load_preset("table1").override(variant="static"),
           "vcm": lambda: od.load_preset("vcm")}


@pytest.fixture(scope="module", params=list(PRESETS))
def cfg(request):
    return PRESETS[request.param]()


@pytest.fixture(scope="module")
def tuned(cfg):
    return {name: tune(name, cfg) for name in ESTIMATORS}


def test_registry_codes():
    assert {name: info.code for name, info in ESTIMATORS.items()} == {
        "paper": 0, "paper-k0": 1, "eso": 2, "kalman": 3, "dob": 4}


def test_one_catalogue_light_and_complete():
    """The command line and the simulator read the same object; it loads no NumPy, SciPy or
    python-control; every entry's builder resolves and every baseline has what the fair rule needs."""
    import subprocess
    import sys

    from obsdesign.estimators import FIRST_BASELINE_CODE, RULES, EstimatorInfo
    from obsdesign.sampled.choices import ESTIMATORS as CHOICES

    assert CHOICES is ESTIMATORS
    code = ("import sys, obsdesign.estimators.registry, obsdesign.sampled.choices, obsdesign.friction.registry; "
            "print(','.join(m for m in ('numpy', 'scipy', 'control', 'numba') if m in sys.modules))")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == ""
    for name, info in ESTIMATORS.items():
        assert isinstance(info, EstimatorInfo) and info.name == name and callable(info.build)
        assert set(info.rules) <= set(RULES) and info.doc and "\n" not in info.doc
        assert info.baseline == (info.code >= FIRST_BASELINE_CODE)
        if info.baseline:
            lo, hi = info.knob_range
            assert info.knob and info.knob_unit and 0 < lo < hi and not info.lowpass


@pytest.mark.slow
def test_a_sixth_linear_estimator_is_its_module_plus_one_entry(request, monkeypatch, capsys, tmp_path):
    """docs/estimators.md, "Adding an estimator": a module with its builder and one registry entry
    reach tune, build, the simulator's kernel, compare and the command line, with no other edit.
    The probe is the ESO under another name and knob, so its closed loop must be the ESO's."""
    import dataclasses
    import sys
    import types

    from obsdesign.cli import main
    from obsdesign.comparison import compare
    from obsdesign.estimators import EstimatorInfo

    def build_probe(cfg, *, omega_p, sigma_model=None, tuning="manual"):
        est = build_eso(cfg, omega_o=omega_p, sigma_model=sigma_model, tuning=tuning)
        return dataclasses.replace(est, name="probe", params={**est.params, "omega_p": omega_p})

    module = types.ModuleType("obsdesign.estimators.probe")   # "its module"
    module.build_probe = build_probe
    monkeypatch.setitem(sys.modules, module.__name__, module)
    ESTIMATORS.register(EstimatorInfo(                         # "plus one entry"
        name="probe", code=max(info.code for info in ESTIMATORS.values()) + 1, doc="the ESO, renamed",
        knob="omega_p", knob_unit="rad/s", knob_range=(1e-3, 1e5), knob_is_rate=True, lowpass=False,
        builder="probe:build_probe"))
    request.addfinalizer(lambda: ESTIMATORS._entries.pop("probe"))

    cfg = od.load_preset("vcm")
    eso = tune("eso", cfg)
    assert tune("probe", cfg).params["omega_p"] == eso.params["omega_o"]
    assert tune("probe", cfg, rule="rate").params["omega_p"] == tune("eso", cfg, rule="rate").params["omega_o"]
    assert build("probe", cfg, omega_p=100.0).name == "probe"
    res = od.simulate(cfg, "tracking", estimator="probe", duration=0.05)
    np.testing.assert_array_equal(res.u, od.simulate(cfg, "tracking", estimator="eso", duration=0.05).u)
    rows = compare(cfg, plants=("paper",), estimators=("eso", "probe"), scenarios=("excitation",), seeds=1,
                   workers=1).rows
    assert [r["status"] for r in rows] == ["ok", "ok"]
    assert rows[0]["friction_rms_error"] == rows[1]["friction_rms_error"]
    assert main(["simulate", "tracking", "--estimator", "nope"]) == 2   # the command line's choices
    assert "'dob', 'probe')" in capsys.readouterr().err
    assert main(["compare", "--estimators", "nope", "--out", str(tmp_path / "cmp")]) == 2
    assert "expected names from paper, paper-k0, eso, kalman, dob, probe, found 'nope'" in capsys.readouterr().err
    assert main(["simulate", "tracking", "--estimator", "probe", "--duration", "0.05"]) == 0


# --- ESO ---------------------------------------------------------------------------------

@pytest.mark.parametrize("omega_o, sigma", [(30.0, 21.1), (400.0, 21.1), (50.0, 0.0)])
def test_eso_poles_continuous_and_discrete(omega_o, sigma):
    m, dt = 0.538, 1e-4
    A, b, c, l = eso_continuous(omega_o, m, sigma)  # noqa: E741 (the gain vector l of eso_continuous)
    err = ct.ss(A - np.outer(l, c), np.zeros((3, 1)), np.eye(3), 0.0)
    # A triple eigenvalue is perturbed by ~eps^(1/3) relative: compare the roots loosely and
    # the characteristic polynomial tightly.
    np.testing.assert_allclose(ct.poles(err), -omega_o, rtol=1e-4)
    np.testing.assert_allclose(np.poly(A - np.outer(l, c)), np.poly([-omega_o] * 3), rtol=1e-12)
    cfg = od.load_preset("vcm").override(sigma=21.1) if sigma else od.load_preset("table1")
    est = build_eso(cfg, omega_o=omega_o, sigma_model=sigma)
    np.testing.assert_allclose(est.Phi, scipy.linalg.expm((A - np.outer(l, c)) * dt), rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(np.poly(est.Phi), np.poly([math.exp(-omega_o * dt)] * 3), rtol=0, atol=1e-13)


def test_eso_gains_closed_form():
    # (s + w)^3 with a = sigma/m: l1 = 3w - a, l2 = 3w^2 - a l1, l3 = -m w^3.
    w, m, sig = 7.0, 2.0, 3.0
    a = sig / m
    np.testing.assert_allclose(eso_gains(w, m, sig), [3 * w - a, 3 * w * w - a * (3 * w - a), -m * w**3])


# --- Kalman ------------------------------------------------------------------------------

@pytest.mark.parametrize("q", [1e-8, 1e-3, 10.0])
def test_kalman_gain_matches_dual_riccati(q):
    cfg = od.load_preset("vcm")
    est = build_kalman(cfg, q=q)
    eta = noise_level(cfg)[0]
    dt, m, sig = cfg.observer.dt, cfg.plant.m, cfg.friction.sigma
    # Independent model: scipy's ZOH of the continuous (x, v, f) system.
    A = np.array([[0, 1, 0], [0, -sig / m, -1 / m], [0, 0, 0]], float)
    Ad, *_ = scipy.signal.cont2discrete((A, np.zeros((3, 1)), np.eye(3), np.zeros((3, 1))), dt, method="zoh")
    c = np.array([[1.0, 0.0, 0.0]])
    Qn = np.diag([0.0, 0.0, q * dt])
    P = scipy.linalg.solve_discrete_are(Ad.T, c.T, Qn, np.array([[eta * eta]]))
    M = P @ c.T / (c @ P @ c.T + eta * eta)
    np.testing.assert_allclose(est.g1, M.ravel(), rtol=1e-6)
    np.testing.assert_allclose(est.Phi, (np.eye(3) - M @ c) @ Ad, rtol=1e-6, atol=1e-12)
    assert np.max(np.abs(est.poles())) < 1.0
    # python-control's predictor gain is Ad M.
    Ad_k, _, c_k, G_k = kalman_model(m, sig, dt)
    L, _, _ = ct.dlqe(Ad_k, G_k, c_k / eta, np.array([[q * dt]]), np.eye(1))
    L = np.asarray(L) / eta                 # gain of the unscaled measurement
    np.testing.assert_allclose(np.asarray(L).ravel(), (Ad @ M).ravel(), rtol=1e-5)


# --- DOB ---------------------------------------------------------------------------------

def test_dob_q_unit_dc_gain_and_constant_disturbance():
    w = 80.0
    assert q_filter(w).dcgain() == pytest.approx(1.0, abs=1e-15)
    cfg = od.load_preset("vcm")
    est = build_dob(cfg, omega_q=w)
    # Discrete: y held constant, u held constant -> f_hat = u (Q(1) = 1, P_n^-1 of a constant is 0).
    G_u = est.transfer_from_input()
    G_y = est.transfer_from_measurement()
    assert np.asarray(G_u.dcgain()).ravel()[1] == pytest.approx(1.0, rel=1e-9)
    assert np.asarray(G_y.dcgain()).ravel()[1] == pytest.approx(0.0, abs=1e-6)  # vs m w^2 = 3443 feedthrough
    # The nominal plant at rest under u = d: friction estimate -> d exactly.
    n = 4000
    u, y = np.full(n, 0.7), np.full(n, 1e-3)
    v_hat, f_hat = run_offline(est, u, y)
    assert abs(f_hat[-1] - 0.7) < 1e-9 and abs(v_hat[-1]) < 1e-9


@pytest.mark.parametrize("sigma", [21.1, 0.0])
def test_dob_realization_equals_block_diagram(sigma):
    """The 2-state realization has f_hat = Q u - Q (m s^2 + sigma s) y, and poles at -omega_q."""
    w, m = 150.0, 0.538
    sys = dob_continuous(w, m, sigma)
    Q = q_filter(w)
    for f in (0.5, 30.0, 400.0, 5000.0):
        s = 1j * f
        H = sys(s)
        assert complex(H[1, 0]) == pytest.approx(complex(Q(s)), rel=1e-10)
        assert complex(H[1, 1]) == pytest.approx(complex(-Q(s) * (m * s * s + sigma * s)), rel=1e-10)
    np.testing.assert_allclose(np.poly(sys.A), np.poly([-w, -w]), rtol=1e-12)


# --- the paper entry against the kernel ---------------------------------------------------

@pytest.mark.parametrize("preset", ["vcm", "table1"])
def test_paper_matches_step_matrices(preset):
    cfg = od.load_preset(preset)
    design = od.design_observer(cfg)
    for k in (0.0, 1234.5, design.kappa):
        est = build_paper(cfg, stiffness=k)
        for mine, ref in zip((est.Phi, est.gu, est.g0, est.g1), step_matrices(*design.matrices(k), cfg.observer.dt)):
            np.testing.assert_allclose(mine, ref, rtol=1e-12, atol=0)


def test_paper_reproduces_kernel_recursion():
    """One step of estimator_step from the kernel's state equals the kernel's next output."""
    cfg = od.load_preset("vcm")
    r = od.simulate(cfg, "excitation", stiffness="constant", duration=0.3, initial_estimate=(0.2, 0.0), seed=3)
    est = build_paper(cfg, stiffness=cfg.friction.kappa)
    L = est.d
    worst = 0.0
    for n in range(len(r.u) - 1):
        z = np.array([r.v_hat[n] - L[0] * r.x_meas[n], r.f_hat[n] - L[1] * r.x_meas[n]])
        scale = np.abs(z) + np.abs(L * r.x_meas[n + 1]) + 1e-300     # the terms that cancel in the output
        out = estimator_step(est.Phi, est.gu, est.g0, est.g1, est.Cz, est.d, z, r.u[n], r.x_meas[n], r.x_meas[n + 1])
        worst = max(worst, float(np.max(np.abs(np.array(out) - (r.v_hat[n + 1], r.f_hat[n + 1])) / scale)))
    assert worst < 1e-12
    # Over the whole run the rounding differences accumulate but stay at the rounding level.
    v_hat, f_hat = run_offline(est, r.u, r.x_meas, v0=0.2, f0=0.0)
    _, f_filt = run_offline(with_lowpass(est, cfg.observer.omega_co), r.u, r.x_meas, v0=0.2, f0=0.0)
    for mine, ref in ((v_hat, r.v_hat), (f_hat, r.f_hat), (f_filt, r.f_hat_filtered)):
        np.testing.assert_allclose(mine, ref, rtol=0, atol=1e-9 * np.max(np.abs(ref)))


# --- unbiased on the linear plant ---------------------------------------------------------

def _linear_plant(m, sigma, f_const, dt, n, seed=0):
    """Exact ZOH samples of m x'' = u - sigma v - f with u = sine (held) and f constant."""
    A = np.array([[0.0, 1.0], [0.0, -sigma / m]])
    B = np.array([[0.0, 0.0], [1 / m, -1 / m]])
    Ad, Bd, *_ = scipy.signal.cont2discrete((A, B, np.eye(2), np.zeros((2, 2))), dt, method="zoh")
    t = np.arange(n) * dt
    u = 1.0 * np.sin(2 * np.pi * 2.0 * t) + f_const   # offset so x stays bounded when sigma = 0
    w = np.zeros((n, 2))
    w[0] = (1e-3, 0.0)
    for i in range(n - 1):
        w[i + 1] = Ad @ w[i] + Bd @ np.array([u[i], f_const])
    return u, w[:, 0], w[:, 1]


@pytest.mark.parametrize("name", list(ESTIMATORS))
def test_unbiased_on_linear_plant(cfg, tuned, name):
    """Constant f, u a sine: f_hat -> f and v_hat -> v.

    The plant is sampled exactly; every model is exact for it (Kalman: to ~1e-12) except that the
    FOH treats x as linear between samples. That error is O(dt^2): an equivalent slow measurement
    offset ~ dt^2/12 |x''| = 1.5e-9 m reaching f_hat through |m s^2 + sigma s| at 2 Hz, i.e. about
    1e-7 N (measured 1e-7 N for the ESO, 1.4e-6 N for the DOB, 4.3e-5 N for the vcm paper observer
    with its 1.2e5 N/m feedthrough, each falling 4x when dt halves; see
    test_foh_error_is_second_order). Tolerances: 1e-4 N and 1e-6 m/s. The start error
    (f0 = 0 instead of 0.3 N) decays with the slowest pole p: the run lasts 30/|p| + 1 s.
    """
    est = tuned[name]
    m, sig, dt = cfg.plant.m, cfg.friction.sigma, cfg.observer.dt
    slow = abs(est.params["slowest_pole"])
    n = int((30.0 / slow + 1.0) / dt)
    u, x, v = _linear_plant(m, sig, 0.3, dt, n)
    v_hat, f_hat = run_offline(est, u, x)
    tail = slice(n - int(0.5 / dt), n)
    assert np.max(np.abs(f_hat[tail] - 0.3)) < 1e-4
    assert np.max(np.abs(v_hat[tail] - v[tail])) < 1e-6


@pytest.mark.parametrize("name, knob", [("eso", {"omega_o": 40.0}), ("kalman", {"q": 1e-6}), ("dob", {"omega_q": 40.0})])
def test_unbiased_lag_variant_model(name, knob):
    """The ``lag`` variant's linear part has sigma = 0: m x'' = u - f."""
    cfg = od.load_preset("table1")
    est = build(name, cfg, **knob)
    assert est.params["sigma_model"] == 0.0
    dt = cfg.observer.dt
    n = int(2.0 / dt)
    u, x, v = _linear_plant(cfg.plant.m, 0.0, 0.3, dt, n)
    v_hat, f_hat = run_offline(est, u, x)
    assert np.max(np.abs(f_hat[-2000:] - 0.3)) < 1e-5
    assert np.max(np.abs(v_hat[-2000:] - v[-2000:])) < 1e-6


def test_foh_error_is_second_order():
    """The residual of the DOB and ESO on the sampled plant falls 4x when dt halves (FOH, O(dt^2))."""
    errors = {}
    for dt in (1e-4, 5e-5):
        cfg = od.load_preset("table1").override(dt=dt)
        n = int(3.0 / dt)
        u, x, v = _linear_plant(cfg.plant.m, 0.0, 0.3, dt, n)
        for name, knob in (("eso", {"omega_o": 40.0}), ("dob", {"omega_q": 40.0})):
            _, f_hat = run_offline(build(name, cfg, **knob), u, x)
            errors[name, dt] = np.max(np.abs(f_hat[-int(1.0 / dt):] - 0.3))
        vcm = od.load_preset("vcm").override(dt=dt)
        u, x, v = _linear_plant(vcm.plant.m, vcm.friction.sigma, 0.3, dt, int(1.5 / dt))
        _, f_hat = run_offline(build("paper", vcm), u, x)
        errors["paper", dt] = np.max(np.abs(f_hat[-int(1.0 / dt):] - 0.3))
    for name in ("eso", "dob", "paper"):
        assert errors[name, 1e-4] / errors[name, 5e-5] == pytest.approx(4.0, rel=0.05)


# --- equal-noise tuning --------------------------------------------------------------------

@pytest.mark.parametrize("name", ["eso", "kalman", "dob"])
def test_equal_noise_integral(cfg, tuned, name):
    eta, B = noise_level(cfg)
    assert friction_noise_rms(tuned[name], eta, B) == pytest.approx(reference_noise_rms(cfg), rel=1e-2)
    assert tuned[name].tuning == "noise"


def test_reference_close_to_continuous_analysis(cfg):
    """The discrete reference is near the continuous noise_analysis (dt is small here)."""
    ref = reference_noise_rms(cfg)
    assert ref == pytest.approx(od.noise_analysis(cfg).rms_filtered, rel=0.02)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["reference", "eso", "kalman", "dob"])
def test_equal_noise_dlsim(name):
    """A long dlsim of band-limited noise through y -> f_hat (vcm: correlation times of a few ms).

    2^19 samples are ~8000 correlation times of the slowest tuned estimate (~100 rad/s):
    the sample RMS has a relative standard deviation near 1 %; the test allows 4 %.
    """
    cfg = PRESETS["vcm"]()
    est = reference_estimator(cfg) if name == "reference" else tune(name, cfg)
    eta, B = noise_level(cfg)
    dt = cfg.observer.dt
    noise = band_limited_noise(2**19, dt, eta, B, seed=11)
    sys = est.transfer_from_measurement()
    _, out, _ = scipy.signal.dlsim((sys.A, sys.B, sys.C, sys.D, dt), noise)
    f = out[20000:, 1]
    measured = float(np.sqrt(np.mean(f * f)))
    assert measured == pytest.approx(friction_noise_rms(est, eta, B), rel=0.04)
    assert measured == pytest.approx(reference_noise_rms(cfg), rel=0.04)


def test_rate_rule(cfg):
    pole = paper_dominant_pole(cfg)
    radius = math.exp(pole * cfg.observer.dt)
    for name, order in (("eso", 3), ("dob", 2)):   # repeated poles: compare polynomials, not roots
        est = tune(name, cfg, rule="rate")
        np.testing.assert_allclose(np.poly(est.Phi), np.poly([radius] * order), rtol=0, atol=1e-12)
    est = tune("kalman", cfg, rule="rate")
    assert np.max(np.abs(est.poles())) == pytest.approx(radius, rel=1e-9)


def test_tuning_independent_of_noise_level(cfg):
    """Every RMS is proportional to eta, so the equal-noise knobs of ESO and DOB do not depend on it."""
    louder = cfg.override(noise_rms=5e-6)
    for name, knob in (("eso", "omega_o"), ("dob", "omega_q")):
        assert tune(name, louder).params[knob] == pytest.approx(tune(name, cfg).params[knob], rel=1e-7)


def test_initial_state_outputs(tuned):
    for est in tuned.values():
        z = est.initial_state(2e-3, 0.1, 0.25)
        assert est.Cz @ z + est.d * 2e-3 == pytest.approx([0.1, 0.25], abs=1e-9)


def _band_power_dense(est, row, top, n):
    """Trapezoid of |G|^2 over 0 and a geometric grid of n points up to ``top``, from the frequency
    response of ``transfer_from_measurement()`` solved point by point (no Lyapunov, no logm)."""
    sys = est.transfer_from_measurement()
    theta = np.concatenate([[0.0], np.geomspace(top * 1e-12, top, n)])
    z = np.exp(1j * theta)
    x = np.linalg.solve(z[:, None, None] * np.eye(sys.nstates) - sys.A,
                        np.broadcast_to(sys.B[:, 0].astype(complex), (n + 1, sys.nstates))[..., None])[..., 0]
    g = x @ sys.C[row] + sys.D[row, 0]
    return float(np.trapezoid(np.abs(g) ** 2, theta))


def _rms_dense(est, eta, bandwidth, row):
    """Richardson-extrapolated trapezoid (error O(h^2): 25k and 50k points leave ~1e-12)."""
    top = min(2.0 * math.pi * bandwidth * est.dt, math.pi)
    coarse, fine = (_band_power_dense(est, row, top, n) for n in (25000, 50000))
    return eta * math.sqrt((fine + (fine - coarse) / 3.0) / top)


@pytest.mark.parametrize("bandwidth", ["sensor", 10.0])
@pytest.mark.parametrize("name", ["reference", "paper", "eso", "kalman", "dob"])
def test_noise_rms_against_a_dense_trapezoid(cfg, tuned, name, bandwidth):
    """The closed-form band integral (Lyapunov + matrix log) against quadrature of |G|^2.

    Measured agreement 1.4e-14 (sensor band, 1000 Hz) and 1.2e-10 (10 Hz) relative on the tuned
    estimators; the test allows 1e-8. The 10 Hz band sits below the estimators' corners for vcm.
    """
    est = reference_estimator(cfg) if name == "reference" else tuned[name]
    eta, B = noise_level(cfg)
    B = B if bandwidth == "sensor" else bandwidth
    for row in (0, 1):
        assert estimate_noise_rms(est, eta, B, row=row) == pytest.approx(_rms_dense(est, eta, B, row), rel=1e-8)


@pytest.mark.parametrize("name", ["reference", "paper", "eso", "kalman", "dob"])
def test_noise_rms_up_to_nyquist_is_the_h2_norm(cfg, tuned, name):
    """Noise up to the Nyquist frequency: rms^2 = eta^2 (D^2 + C P C^T), P from SciPy's Lyapunov solver."""
    est = reference_estimator(cfg) if name == "reference" else tuned[name]
    sys = est.transfer_from_measurement()
    P = scipy.linalg.solve_discrete_lyapunov(sys.A, sys.B @ sys.B.T)
    for row in (0, 1):
        h2 = math.sqrt(sys.D[row, 0] ** 2 + sys.C[row] @ P @ sys.C[row])
        assert estimate_noise_rms(est, 1e-6, 1e9, row=row) == pytest.approx(1e-6 * h2, rel=1e-9)


@pytest.mark.parametrize("name, knob", [("dob", {"omega_q": 1e5}), ("eso", {"omega_o": 1e5}), ("kalman", {"q": 1e8})])
def test_noise_rms_of_a_narrow_band_below_a_fast_estimator(name, knob):
    """10 Hz of noise under an estimator 10^4 times faster: the closed form's terms cancel to 1e-11,
    so the integral is refined by quadrature (measured 5e-12 against the trapezoid)."""
    est = build(name, od.load_preset("table1"), **knob)
    assert estimate_noise_rms(est, 1e-6, 10.0, row=1) == pytest.approx(_rms_dense(est, 1e-6, 10.0, 1), rel=1e-8)


def test_noise_rms_of_an_unstable_estimator_is_unbounded():
    est = build_paper(od.load_preset("table1").override(rho=0.98))      # pole +2.44 1/s at k = 0
    assert np.max(np.abs(est.poles())) > 1.0
    assert estimate_noise_rms(est, 1e-6, 1000.0, row=1) == math.inf
    assert estimate_noise_rms(est, 0.0, 1000.0, row=1) == 0.0


# --- bad input ------------------------------------------------------------------------------

@pytest.mark.parametrize("call, match", [
    (lambda c: tune("luenberger", c), r"name: expected one of paper, paper-k0, eso, kalman, dob, found 'luenberger'"),
    (lambda c: build("ekf", c), r"name: expected one of .*found 'ekf'"),
    (lambda c: tune("eso", c, rule="speed"), r"rule: expected one of noise, rate, min-error, found 'speed'"),
    (lambda c: build("eso", c, omega_o=0.0), r"omega_o: expected a finite number > 0 \[rad/s\], found 0.0"),
    (lambda c: build("eso", c, omega_o=float("nan")), r"omega_o: expected a finite number > 0 \[rad/s\], found nan"),
    (lambda c: build("kalman", c, q=-1.0), r"q: expected a finite number > 0 \[N\^2/s\], found -1.0"),
    (lambda c: build("dob", c, omega_q=-5.0), r"omega_q: expected a finite number > 0 \[rad/s\], found -5.0"),
    (lambda c: build("dob", c), r"omega_q: 'dob' needs it, expected a finite number > 0 \[rad/s\], found None"),
    (lambda c: build("eso", c, omega_q=3.0), r"omega_q: 'eso' takes omega_o, found omega_q = 3.0"),
    (lambda c: build("paper", c, stiffness=-1.0), r"stiffness: expected a finite number >= 0 \[N/m\], found -1.0"),
    (lambda c: build("eso", c, omega_o=10.0, sigma_model=-2.0), r"sigma_model: expected a finite number >= 0"),
    (lambda c: tune("eso", c.override(rho=0.98)), r"rho: .*rho > 1.*found rho = 0.98"),
    (lambda c: tune("kalman", c.override(quantization=0.0)), r"measurement_rms .*> 0 \[m\], found 0.0"),
])
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call(od.load_preset("vcm"))


def test_registry_tune_entry_matches_tune():
    cfg = PRESETS["vcm"]()
    assert ESTIMATORS["dob"].tune(cfg).params["omega_q"] == tune("dob", cfg).params["omega_q"]
