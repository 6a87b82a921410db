"""Numeric design against closed forms, the paper's numbers and python-control / SciPy."""

import math
import warnings

import control as ct
import numpy as np
import pytest
import scipy.signal
from hypothesis import given
from hypothesis import strategies as st

import obsdesign as od
from obsdesign.design import band_limited_rms, lowpass

TABLE1 = od.load_preset("table1")
VCM = od.load_preset("vcm")


def closed_form_gains(cfg, rho):
    m, kap, sig = cfg.plant.m, cfg.friction.kappa, cfg.friction.sigma
    if cfg.observer.variant == "lag":  # eq:3:3:3-4
        return 2 * rho * math.sqrt(kap / m), sig / cfg.friction.beta + kap * (1 - rho**2)
    return 2 * rho * math.sqrt(kap / m) - sig / m, kap * (1 - rho**2)  # DESIGN.md, static


@pytest.mark.parametrize("cfg", [TABLE1, VCM], ids=["table1", "vcm"])
def test_gains_follow_the_gain_rule(cfg):
    d = od.design_observer(cfg)
    np.testing.assert_allclose((d.L1, d.L2), closed_form_gains(cfg, cfg.observer.rho), rtol=1e-12)


def test_table1_rho_102_is_stable_with_dominant_pole_minus_2_44():
    rep = od.check_stability(TABLE1.override(rho=1.02))
    assert rep.stable and rep.eigenvalues_real and rep.observable and rep.all_hold
    root = math.sqrt(8000 / 0.538)
    assert rep.dominant_pole == pytest.approx(-root * 0.02, rel=1e-9)  # eq:3:3:2
    assert rep.dominant_pole == pytest.approx(-2.44, abs=0.005)
    assert rep.fastest_pole == pytest.approx(-root * 2.02, rel=1e-9)
    np.testing.assert_allclose(rep.eigenvalues_at_ends[8000.0].real, [-1.02 * root] * 2, rtol=1e-7)


def test_table1_rho_098_fails_with_the_condition_named():
    rep = od.check_stability(TABLE1.override(rho=0.98))
    assert not rep.stable and not rep.all_hold
    assert "Proposition 1: L_2 < sigma/beta" in rep.failed()
    assert "eigenvalues negative on [0, kappa]" in rep.failed()
    assert rep.dominant_pole == pytest.approx(math.sqrt(8000 / 0.538) * 0.02, rel=1e-9)  # +2.44 1/s


@pytest.mark.parametrize("cfg", [TABLE1, VCM], ids=["table1", "vcm"])
@pytest.mark.parametrize("stiffness", [0.0, 1234.5, 8000.0])
def test_eigenvalues_agree_with_numpy_and_python_control(cfg, stiffness):
    d = od.design_observer(cfg)
    A_obs, _, _ = d.matrices(stiffness)
    ours = np.sort_complex(d.eigenvalues(stiffness))
    np.testing.assert_allclose(ours, np.sort_complex(np.linalg.eigvals(A_obs)), rtol=1e-6)
    np.testing.assert_allclose(ours, np.sort_complex(ct.poles(d.to_statespace(stiffness).observer)), rtol=1e-6)
    # eq:3:3:7
    root = math.sqrt(cfg.friction.kappa / cfg.plant.m)
    spread = math.sqrt((cfg.friction.kappa - stiffness) / cfg.plant.m)
    np.testing.assert_allclose(ours.real, sorted([-cfg.observer.rho * root - spread, -cfg.observer.rho * root + spread]), rtol=1e-6)


def test_statespace_observer_matches_symbolic_noise_transfer():
    d = od.design_observer(TABLE1)
    sysk = d.to_statespace(3000.0)
    na = od.noise_analysis(TABLE1, stiffness=3000.0)
    w = np.logspace(-1, 4, 9)
    from_ss = ct.frequency_response(sysk.observer[1, 1], w).complex.ravel()  # x_meas -> f_hat
    from_sym = ct.frequency_response(na.G_friction, w).complex.ravel()
    np.testing.assert_allclose(from_ss, from_sym, rtol=1e-9)
    # The plant model: poles 0 and +-sqrt(-(k + sigma/beta)/m) (a lossless oscillator for k > 0).
    poles = np.sort_complex(ct.poles(sysk.plant))
    np.testing.assert_allclose(np.abs(poles.imag).max(), math.sqrt((3000.0 + 21.1 / 0.001) / 0.538), rtol=1e-9)


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), "1", True])
def test_to_statespace_rejects_bad_stiffness(bad):
    with pytest.raises(ValueError, match=r"stiffness: expected a finite number >= 0 \[N/m\], found"):
        od.design_observer(TABLE1).to_statespace(bad)


def test_discrete_pole_radii_are_exp_of_eigenvalues_times_dt():
    rep = od.check_stability(VCM)
    d = rep.design
    for k, radii in rep.discrete_pole_radii.items():
        np.testing.assert_allclose(sorted(radii), sorted(np.exp(d.eigenvalues(k).real * d.dt)), rtol=1e-9)


def test_stiff_kappa_warns_about_the_sampling_rate():
    with pytest.warns(UserWarning, match=r"times dt = 0.0001 s is 3.34 > 1"):
        rep = od.check_stability(VCM.override(kappa=2.4e7))
    assert rep.stable and rep.warnings
    assert max(max(r) for r in rep.discrete_pole_radii.values()) < 1


def test_presliding_velocity_bound_against_brute_force():
    """Condition (ii) along k(z) = -s Cf D ln z, evaluated on a dense grid of z."""
    rep = od.check_stability(TABLE1)
    d = rep.design
    m, s, Cf, kap = d.m, d.s, d.Cf, d.kappa
    for D in (2.0, 1.0):
        z = np.geomspace(math.exp(-kap / (s * Cf * D)), 1.0, 200001)  # where k <= kappa
        k = -s * Cf * D * np.log(z)
        a0 = (k + d.sigma / d.beta - d.L2) / m
        a1 = d.L1
        # (ii): -(s^2 Cf D |v| / z) / m + 2 a0 a1 > 0  =>  |v| < 2 a0 a1 m z / (s^2 Cf D)
        vmax = np.min(2 * a0 * a1 * m * z / (s * s * Cf * D))
        assert rep.presliding_velocity_bound[f"D={D:g}"] == pytest.approx(vmax, rel=1e-6)


# Random designs may be faster than the 10 kHz sampling: that warning is expected here (and
# asserted in test_stiff_kappa_warns_about_the_sampling_rate); any other warning fails.
FASTER_THAN_SAMPLING = "ignore:fastest observer pole .* the observer is faster than the sampling:UserWarning"


@pytest.mark.slow
@pytest.mark.filterwarnings(FASTER_THAN_SAMPLING)
@given(rho=st.floats(1.001, 12.0), kap=st.floats(100.0, 1e6), mass=st.floats(0.05, 10.0),
       frac=st.floats(0.0, 1.0), variant=st.sampled_from(["lag", "static"]))
def test_property_rho_above_one_is_stable_with_real_eigenvalues(rho, kap, mass, frac, variant):
    cfg = TABLE1.override(m=mass, variant=variant)
    rep = od.check_stability(cfg.override(rho=rho, kappa=kap))
    assert rep.stable and rep.eigenvalues_real
    d = rep.design
    k = frac * kap
    numeric = np.linalg.eigvals(d.matrices(k)[0])
    scale = rho * math.sqrt(kap / mass)
    assert np.all(numeric.real < 0)
    assert np.abs(numeric.imag).max() <= 1e-6 * scale + 1e-9
    np.testing.assert_allclose(np.sort(numeric.real), np.sort(d.eigenvalues(k).real), rtol=1e-6, atol=1e-7 * scale)


@pytest.mark.filterwarnings(FASTER_THAN_SAMPLING)
@given(rho=st.floats(0.01, 0.999), kap=st.floats(100.0, 1e6), variant=st.sampled_from(["lag", "static"]))
def test_property_rho_below_one_is_not_stable(rho, kap, variant):
    rep = od.check_stability(TABLE1.override(variant=variant, rho=rho, kappa=kap))
    assert not rep.stable
    assert rep.dominant_pole > 0
    np.testing.assert_allclose(rep.dominant_pole, math.sqrt(kap / 0.538) * (1 - rho), rtol=1e-6)


# --- PID ------------------------------------------------------------------------------------

def test_vcm_pid_reproduces_the_published_gains():
    pid = od.pid_from_config(VCM)
    for ours, paper in [(pid.kp, 429.0), (pid.ki, 4348.0), (pid.kd, 2.67)]:  # eq:PIDparams
        assert ours == pytest.approx(paper, rel=5e-3)
    assert pid.k == 400.0
    assert pid.max_S_achieved <= 1 / pid.k
    assert pid.closed_loop_stable
    assert pid.phase_margin_achieved_deg == pytest.approx(60.0, abs=1e-6)
    assert pid.omega_crossover == pytest.approx(pid.omega_s, rel=1e-6)


def test_pid_peak_of_S_against_closed_form():
    pid = od.pid_from_config(VCM)
    k, T, tau, phi = pid.k, pid.T_I, pid.tau, pid.phi
    w = np.logspace(-2, 4, 400001)
    lam = 1j * w
    S = phi * T * lam / ((tau * lam + 1) * (T * lam**2 + k * phi * T * lam + k * phi))  # eq:Syd with eq:Cpid
    assert pid.max_S_achieved == pytest.approx(np.abs(S).max(), rel=1e-6)


def test_pid_inverse_recovers_the_design():
    pid = od.pid_from_config(VCM)
    back = od.pid_from_gains(kp=pid.kp, ki=pid.ki, kd=pid.kd, phi=pid.phi)
    for name in ("k", "T_I", "tau", "phase_margin_deg"):
        assert getattr(back, name) == pytest.approx(getattr(pid, name), rel=1e-9)
    paper = od.pid_from_gains(kp=429, ki=4348, kd=2.67, phi=VCM.phi)
    assert paper.k == pytest.approx(400, rel=5e-3) and paper.tau == pytest.approx(0.006675, rel=5e-3)
    assert paper.phase_margin_deg == pytest.approx(60, abs=0.5)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(phi=0.04, tau=0.006, max_S=0.0025, phase_margin_deg=90.0), ValueError, r"phase_margin_deg: expected a finite number > 0 and < 90, found 90\.0"),
        (dict(phi=0.04, tau=-1.0, max_S=0.0025, phase_margin_deg=60.0), ValueError, r"tau: .*> 0, found -1\.0"),
        (dict(phi="a", tau=0.006, max_S=0.0025, phase_margin_deg=60.0), TypeError, r"phi: .*found str 'a'"),
    ],
)
def test_pid_bad_input(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        od.design_pid(**kwargs)


def test_pid_inverse_without_real_solution():
    with pytest.raises(ValueError, match=r"kp\^2 >= 4 kd ki"):
        od.pid_from_gains(kp=1.0, ki=100.0, kd=1.0, phi=0.04)


# --- noise ----------------------------------------------------------------------------------

def test_lowpass_is_eq_3_4_5():
    F = lowpass(2 * math.pi * 40)
    w = 2 * math.pi * 40
    np.testing.assert_allclose(F.num[0][0], [w * w])
    np.testing.assert_allclose(F.den[0][0], [1, 2 * w, w * w])


def test_band_limited_rms_of_a_gain_and_of_zero_noise():
    assert band_limited_rms(ct.tf([3.0], [1.0]), 2e-6, 500.0) == pytest.approx(6e-6, rel=1e-12)
    assert band_limited_rms(ct.tf([3.0], [1.0]), 0.0, 500.0) == 0.0


def test_noise_direct_gain_is_l2():
    na = od.noise_analysis(VCM)
    assert na.direct_gain == pytest.approx(8000 * (1 - 16))  # eq:3:4:3: -kappa (rho^2 - 1)
    assert na.noise_rms == pytest.approx(1e-6 / math.sqrt(12))  # encoder quantization


def _band_limited_noise(n, dt, rms, bandwidth, seed):
    rng = np.random.default_rng(seed)
    spec = np.fft.rfft(rng.standard_normal(n))
    spec[np.fft.rfftfreq(n, dt) > bandwidth] = 0.0
    x = np.fft.irfft(spec, n)
    return x * rms / np.sqrt(np.mean(x * x))


@pytest.mark.slow
@pytest.mark.parametrize("cfg", [TABLE1, VCM], ids=["table1", "vcm"])
def test_noise_rms_against_a_time_domain_run(cfg):
    eta, B = 1e-6, 1000.0
    na = od.noise_analysis(cfg, noise_rms=eta, noise_bandwidth=B)
    dt, n = 2e-5, 500_000
    t = np.arange(n) * dt
    eta_t = _band_limited_noise(n, dt, eta, B, seed=7)
    keep = t > 2.0
    for G, predicted in [(na.G_friction, na.rms_raw), (na.lowpass * na.G_friction, na.rms_filtered)]:
        num, den = G.num[0][0], G.den[0][0]
        _, y, _ = scipy.signal.lsim((num, den), eta_t, t)
        measured = np.sqrt(np.mean(y[keep] ** 2))
        assert measured == pytest.approx(predicted, rel=0.05)


def test_band_limited_rms_stays_accurate_far_beyond_the_corners():
    """Review n5: a noise band of 1e12 Hz (12 decades beyond the filter) was 19 % low with a SciPy
    IntegrationWarning; against a dense log-grid trapezoid of |G|^2, independent of quad."""
    import math

    cfg = od.load_preset("vcm")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no IntegrationWarning
        na = od.noise_analysis(cfg, noise_rms=1e-6, noise_bandwidth=1e12)
    G = na.lowpass * na.G_friction
    num, den = np.asarray(G.num[0][0], float), np.asarray(G.den[0][0], float)
    W = 2 * math.pi * 1e12
    w = np.logspace(-6, math.log10(W), 800_001)
    power = np.abs(np.polyval(num, 1j * w) / np.polyval(den, 1j * w)) ** 2
    reference = 1e-6 * math.sqrt(np.trapezoid(power, w) / W)
    assert na.rms_filtered == pytest.approx(reference, rel=1e-6)


@pytest.mark.parametrize("omega_co, dt", [(2 * math.pi * 40, 1e-4), (2 * math.pi * 5, 1e-3), (3e3, 2.5e-4)])
def test_the_bilinear_low_pass_is_scipy_s_bit_for_bit(omega_co, dt, tmp_path, monkeypatch):
    """obsdesign.design.bilinear: SciPy's coefficients (kept) and lfilter's floats, without scipy.signal."""
    from obsdesign.design.bilinear import bilinear_lowpass, iir_filter

    monkeypatch.setenv("OBSDESIGN_CACHE_DIR", str(tmp_path))
    b_ref, a_ref = scipy.signal.cont2discrete(([omega_co**2], [1, 2 * omega_co, omega_co**2]), dt, method="bilinear")[:2]
    for _ in range(2):  # computed, then read back
        b, a = bilinear_lowpass(omega_co, dt)
        assert np.array_equal(b, np.ravel(b_ref)) and np.array_equal(a, a_ref)
    rng = np.random.default_rng(5)
    for x in (rng.standard_normal(50000) * 1e-3, np.cumsum(rng.standard_normal(50000)), np.r_[np.zeros(10), np.ones(100)]):
        assert np.array_equal(iir_filter(b, a, x), scipy.signal.lfilter(b, a, x))
    scaled = iir_filter(2.0 * b, 2.0 * a, x)  # normalized by a[0], as lfilter does
    assert np.allclose(scaled, scipy.signal.lfilter(b, a, x), rtol=1e-12, atol=1e-15)
