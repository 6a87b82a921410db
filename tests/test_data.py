"""Tests of obsdesign.data: loading traces, identification, and the config rules."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import io as sio

import obsdesign as od
from obsdesign.data import Identification, Trace, identify, load_trace

EMPS_GAIN = 35.15065188
EMPS = Path(os.environ.get("OBSDESIGN_EMPS") or
            Path(__file__).resolve().parents[1].parent / "shared" / "data" / "emps" / "DATA_EMPS.mat")
needs_emps = pytest.mark.skipif(not EMPS.is_file(), reason=f"EMPS data not found at {EMPS} (set OBSDESIGN_EMPS)")

N, DT = 500, 1e-3


# -- loading -----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("traces")
    rng = np.random.default_rng(7)
    t = np.arange(N) * DT
    x = 1e-3 * np.sin(2 * np.pi * 3 * t)
    u = rng.standard_normal(N)
    np.savetxt(d / "ok.csv", np.column_stack([t, x, u]), delimiter=",", header="time,x,u", comments="", fmt="%.17g")

    def csv(name, tt=t, xx=x, uu=u):
        np.savetxt(d / name, np.column_stack([tt, xx, uu]), delimiter=",", header="time,x,u", comments="", fmt="%.17g")

    u_nan = u.copy()
    u_nan[17] = np.nan
    csv("nan.csv", uu=u_nan)
    t_back = t.copy()
    t_back[40], t_back[41] = t[41], t[40]
    csv("backwards.csv", tt=t_back)
    t_jit = t.copy()
    t_jit[50] += 0.02 * DT
    csv("jitter.csv", tt=t_jit)
    csv("short.csv", tt=t[:50], xx=x[:50], uu=u[:50])
    (d / "latin1.csv").write_bytes("time,x,u\n0,1,2\n".encode() + b"\xe9\xff,1,2\n")
    (d / "binary.csv").write_bytes(b"time,x,u\n\x00\x01\x02")
    (d / "text.csv").write_text("time,x,u\n0,1,2\n1,abc,3\n", encoding="utf-8")
    (d / "garbage.mat").write_bytes(b"not a matlab file at all" * 10)
    (d / "run.txt").write_text("x", encoding="utf-8")
    sio.savemat(d / "ok.mat", {"t": t[:, None], "qm": x[:, None], "vir": u[:, None], "gtau": np.array([[EMPS_GAIN]]),
                               "M": np.ones((3, N)), "short_u": u[:N - 1, None], "label": "abc"})
    return d, t, x, u


def test_csv_round_trip(files):
    d, t, x, u = files
    tr = load_trace(d / "ok.csv", position="x", input="u", time="time", input_gain=2.5)
    np.testing.assert_array_equal(tr.position, x)
    np.testing.assert_array_equal(tr.t, t)
    np.testing.assert_allclose(tr.force, 2.5 * u, rtol=1e-15)
    assert tr.sample_time == pytest.approx(DT, rel=1e-12)
    assert tr.samples == N and tr.duration == pytest.approx((N - 1) * DT)
    assert tr.names == {"position": "x", "input": "u", "time": "time"} and tr.source == "ok.csv"


def test_mat_round_trip_and_sample_time_only(files):
    d, t, x, u = files
    tr = load_trace(d / "ok.mat", position="qm", input="vir", sample_time=DT, input_gain=EMPS_GAIN)
    np.testing.assert_array_equal(tr.position, x)
    np.testing.assert_allclose(tr.force, EMPS_GAIN * u, rtol=1e-15)
    np.testing.assert_allclose(tr.t, np.arange(N) * DT)
    assert tr.names["time"] is None and tr.input_gain == EMPS_GAIN


def test_negative_gain_is_a_sign_convention(files):
    d, _, _, u = files
    tr = load_trace(d / "ok.mat", position="qm", input="vir", time="t", input_gain=-2.0)
    np.testing.assert_allclose(tr.force, -2.0 * u)


def test_time_column_wins_when_consistent(files):
    d, t, _, _ = files
    tr = load_trace(d / "ok.csv", position="x", input="u", time="time", sample_time=1.005e-3)
    np.testing.assert_array_equal(tr.t, t)
    assert tr.sample_time == pytest.approx(DT)


def test_trace_to_csv_round_trip(files, tmp_path):
    d, *_ = files
    tr = load_trace(d / "ok.mat", position="qm", input="vir", time="t", input_gain=3.0)
    tr.to_csv(tmp_path / "out.csv")
    back = load_trace(tmp_path / "out.csv", position="position", input="force", time="t")
    for name in ("t", "position", "force"):
        np.testing.assert_array_equal(getattr(back, name), getattr(tr, name))
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]  # no temporary file left


BAD = [
    ("ok.csv", dict(position="nope", input="u", time="time"), ValueError,
     r"position: expected the name of a column, found 'nope'; available: time, u, x"),
    ("ok.mat", dict(position="qm", input="volts", time="t"), ValueError, r"input: .*'volts'; available: .*qm.*vir"),
    ("ok.mat", dict(position="qm", input="vir", time="tt"), ValueError, r"time: .*'tt'; available"),
    ("nan.csv", dict(position="x", input="u", time="time"), ValueError,
     r"input: expected finite values, found nan in column 'u' at index 17"),
    ("backwards.csv", dict(position="x", input="u", time="time"), ValueError,
     r"time: expected strictly increasing values, .* at index 41"),
    ("jitter.csv", dict(position="x", input="u", time="time"), ValueError,
     r"time: expected uniform sampling \(jitter <= 1 % .*found 2 % .* at index 5[01]"),
    ("short.csv", dict(position="x", input="u", time="time"), ValueError,
     r"position: expected at least 100 samples, found 50"),
    ("ok.mat", dict(position="gtau", input="vir", time="t"), ValueError,
     r"position: expected a column of samples, found a scalar variable 'gtau' \(1 x 1\)"),
    ("ok.mat", dict(position="M", input="vir", time="t"), ValueError, r"position: expected a vector .*3 x 500"),
    ("ok.mat", dict(position="label", input="vir", time="t"), TypeError, r"position: expected a numeric column"),
    ("ok.mat", dict(position="qm", input="short_u", time="t"), ValueError, r"input: expected 500 samples .*found 499"),
    ("ok.mat", dict(position="qm", input="vir", time="t", input_gain=0.0), ValueError,
     r"input_gain: expected a finite nonzero number, found 0.0"),
    ("ok.mat", dict(position="qm", input="vir", time="t", input_gain=math.nan), ValueError,
     r"input_gain: expected a finite nonzero number, found nan"),
    ("ok.mat", dict(position="qm", input="vir", time="t", input_gain=math.inf), ValueError,
     r"input_gain: .*found inf"),
    ("ok.mat", dict(position="qm", input="vir", time="t", input_gain="35"), TypeError, r"input_gain: .*found str"),
    ("ok.mat", dict(position="qm", input="vir", time="t", input_gain=True), TypeError, r"input_gain: .*found bool"),
    ("ok.mat", dict(position="qm", input="vir"), ValueError, r"time, sample_time: .*found neither"),
    ("ok.mat", dict(position="qm", input="vir", time="t", sample_time=2e-3), ValueError,
     r"time, sample_time: expected agreement within 1 %, found a mean step of 0.001 s .*sample_time = 0.002 s"),
    ("ok.mat", dict(position="qm", input="vir", sample_time=0.0), ValueError, r"sample_time: expected a finite number > 0"),
    ("ok.mat", dict(position=3, input="vir", time="t"), TypeError, r"position: expected a column name"),
    # Latin-1 is read (what Windows tools in a European locale write): the bad row is named as decoded
    ("latin1.csv", dict(position="x", input="u", time="time"), ValueError, r"found '\xe9\xff' on line 3"),
    ("binary.csv", dict(position="x", input="u", time="time"), ValueError, r"path: expected a text CSV file, found a "
     r"NUL byte at byte 9"),
    ("text.csv", dict(position="x", input="u", time="time"), ValueError, r"path: expected numeric CSV rows"),
    ("garbage.mat", dict(position="x", input="u", time="t"), ValueError, r"path: expected a MATLAB .mat file"),
    ("run.txt", dict(position="x", input="u", time="t"), ValueError, r"path: expected a log file \(.csv, .mat, .tdms.*found extension '.txt'"),
    ("missing.csv", dict(position="x", input="u", time="t"), ValueError, r"path: expected an existing file"),
]


@pytest.mark.parametrize("name, kwargs, exc, match", BAD, ids=[f"{b[0]}-{i}" for i, b in enumerate(BAD)])
def test_load_trace_refuses(files, name, kwargs, exc, match):
    d, *_ = files
    with pytest.raises(exc, match=match):
        load_trace(d / name, **kwargs)


def test_trace_checks_lengths():
    t = np.arange(200) * DT
    with pytest.raises(ValueError, match="force: expected columns of equal length"):
        Trace(t=t, position=t, force=t[:150], sample_time=DT)


def test_reversals_of_a_sine():
    # x = sin(2 pi f t) on [0, 2) s: the velocity cos(2 pi f t) changes sign at t = (2j + 1) / (4 f)
    f, t = 2.0, np.arange(2000) * DT
    tr = Trace(t=t, position=1e-3 * np.sin(2 * np.pi * f * t), force=np.zeros_like(t), sample_time=DT)
    assert tr.reversals == int(np.sum((2 * np.arange(20) + 1) / (4 * f) < t[-1]))  # 8


# -- identification ------------------------------------------------------------------------------

def test_identify_exact_model_closed_form():
    t = np.arange(20_000) * DT
    x = 0.05 * np.sin(2 * np.pi * 0.5 * t) + 0.01 * np.sin(2 * np.pi * 2.3 * t)
    v = np.gradient(x, DT)
    u = 2.0 * np.gradient(v, DT) + 30.0 * v + 1.5 * np.sign(v) - 0.4
    ident = identify(Trace(t=t, position=x, force=u, sample_time=DT))
    np.testing.assert_allclose([ident.m, ident.sigma, ident.Cf, ident.offset], [2.0, 30.0, 1.5, -0.4], rtol=2e-3)
    assert ident.nrmse_percent < 1.0
    assert set(ident.to_dict()) == {"m", "sigma", "Cf", "offset", "m_std", "sigma_std", "Cf_std", "offset_std",
                                    "nrmse_percent", "condition_number", "samples", "s", "s_note", "model",
                                    "sample_time", "filter_hz", "filter_rule", "decimation", "stribeck", "selection",
                                    "interval_method", "at_bound", "fixed", "min_speed", "stribeck_min_speed", "travel_floor", "window",
                                    "intervals", "eiv_shift", "units", "input_timing", "delay_samples", "timing_note",
                                    "timing_evidence", "model_shift", "timing_shift", "presliding_shift"}
    assert (ident.input_timing, ident.delay_samples) == ("sample", 0)  # the force is the exact inverse model
    # the rows of the fit: decimated by 10 after cutting 50 samples at both ends, minus low-velocity rows
    assert ident.samples <= math.ceil((20_000 - 100) / 10)


TRUE = dict(m=2.0, sigma=20.0, Cf=1.0, G=3.0)


def _simulated_trace(s: float) -> Trace:
    cfg = od.load_preset("vcm").override(m=TRUE["m"], sigma=TRUE["sigma"], Cf=TRUE["Cf"], G=TRUE["G"], s=s, dt=1e-4)
    res = od.simulate(cfg.override(noise_rms=1e-7, quantization=1e-7), od.sim.Excitation(force_rms=20.0), duration=20.0,
                      seed=1)
    # the simulator's u is the net force K u_volt - G: the actuator force is u + G
    return Trace(t=res.t, position=res.x_meas, force=res.u + TRUE["G"], sample_time=1e-4, source="simulated")


@pytest.fixture(scope="module")
def synthetic():
    # s = 1e5 1/m: pre-sliding over 10 um only, so the gross-sliding model holds
    return _simulated_trace(1e5)


def test_identify_recovers_simulated_parameters(synthetic):
    ident = identify(synthetic)
    got = [ident.m, ident.sigma, ident.Cf, ident.offset]
    np.testing.assert_allclose(got, [TRUE["m"], TRUE["sigma"], TRUE["Cf"], TRUE["G"]], rtol=0.02)
    assert all(x > 0 for x in (ident.m_std, ident.sigma_std, ident.Cf_std, ident.offset_std))
    assert ident.quantization == pytest.approx(1e-7, rel=1e-6)


def test_asymmetric_on_symmetric_data(synthetic):
    ident = identify(synthetic, model="asymmetric")
    # Equal within 1 %: the simulated plant is not exactly the model (pre-sliding over 10 um, a held input), which
    # biases each direction by a few 0.1 % (Cf_pos - Cf_neg = -0.38 %); at the record's own cut-off (312 Hz, was
    # 1 kHz) the OLS standard errors (0.09 %) no longer hide that, so the test does not compare with them
    for a, b in (("Cf_pos", "Cf_neg"), ("sigma_pos", "sigma_neg")):
        diff = getattr(ident, a) - getattr(ident, b)
        assert abs(diff) < 0.01 * getattr(ident, b), (a, diff)
    assert {"sigma_pos", "sigma_neg", "Cf_pos", "Cf_neg"} <= set(ident.to_dict())
    v = np.array([-0.2, 0.0, 0.3])
    expected = [-ident.Cf_neg - 0.2 * ident.sigma_neg, 0.0, ident.Cf_pos + 0.3 * ident.sigma_pos]
    np.testing.assert_allclose(ident.friction(v), expected)


def test_presliding_s_from_simulated_reversals():
    # open-loop excitation dwells at reversals; s = 3000 1/m (the VCM's), 1/s = 0.33 mm
    ident = identify(_simulated_trace(3000.0), presliding_window=1e-3)
    assert ident.s == pytest.approx(3000.0, rel=0.1), ident.s_note
    assert ident.s_note.startswith("fitted from")


@pytest.mark.parametrize("kwargs, exc, match", [
    (dict(model="lugre"), ValueError, r"model: expected one of 'coulomb-viscous', 'asymmetric', found 'lugre'"),
    (dict(filter_hz=600.0), ValueError, r"filter_hz: expected a cut-off in \(0, 500\) Hz"),
    (dict(decimation=0), ValueError, r"decimation: expected an integer >= 1, found 0"),
    (dict(presliding_window=-1.0), ValueError, r"presliding_window: expected a finite number > 0"),
])
def test_identify_refuses(kwargs, exc, match):
    t = np.arange(2000) * DT
    tr = Trace(t=t, position=np.sin(t), force=np.cos(t), sample_time=DT)
    with pytest.raises(exc, match=match):
        identify(tr, **kwargs)


def test_identification_display_escapes_html():
    ident = Identification(model="coulomb-viscous", m=1.0, sigma=2.0, Cf=3.0, offset=0.0, m_std=0.1, sigma_std=0.1,
                           Cf_std=0.1, offset_std=0.1, nrmse_percent=1.0, condition_number=2.0, samples=10,
                           s_note="<b>x</b>", source="a&b")
    assert "&lt;b&gt;x&lt;/b&gt;" in ident._repr_html_() and "a&amp;b" in ident._repr_html_()
    assert "m                 1 ± 0.1 kg" in str(ident)


def _check_config(cfg: od.Config, tmp_path: Path) -> None:
    rep = od.check_stability(cfg)
    assert rep.all_hold, rep.failed()
    assert rep.fastest_pole * cfg.observer.dt == pytest.approx(-0.2, rel=1e-6)
    # PID rule: |L(j w_c)| = 1 at w_c = 2 pi (Nyquist / 10) for L = k phi (T_I s + 1) / (T_I s^2)
    from obsdesign.design.pid import pid_gains

    k, T_I, *_ = pid_gains(phi=cfg.phi, tau=cfg.pid.tau, max_S=cfg.pid.max_S, phase_margin_deg=60.0)
    w = 2 * math.pi * (0.5 / cfg.observer.dt) / 10
    assert abs(k * cfg.phi * (1j * w * T_I + 1) / (T_I * (1j * w) ** 2)) == pytest.approx(1.0, rel=1e-9)
    assert cfg.phi == pytest.approx(cfg.plant.K / cfg.friction.sigma)  # K tau / m with tau = m / sigma
    res = od.simulate(cfg, "positioning")
    assert not res.metrics["diverged"]
    assert abs(res.metrics["steady_state_error"][0]) < 1e-5
    cfg.save(tmp_path / "identified.toml")
    assert od.load_config(tmp_path / "identified.toml") == cfg


def test_to_config_synthetic(synthetic, tmp_path):
    cfg = identify(synthetic).to_config()
    assert cfg.plant.K == 1.0 and cfg.plant.G == pytest.approx(TRUE["G"], rel=0.02)
    _check_config(cfg, tmp_path)


# -- real data -----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def emps():
    return load_trace(EMPS, position="qm", input="vir", time="t", input_gain=EMPS_GAIN)


@needs_emps
def test_emps_trace(emps):
    assert emps.samples == 24841 and emps.sample_time == pytest.approx(1e-3, rel=1e-4)
    assert emps.reversals == 7


@needs_emps
def test_emps_reproduces_published_model(emps):
    ident = identify(emps)
    published = {"m": 95.1089, "sigma": 203.5034, "Cf": 20.3935, "offset": -3.1648}
    for key, value in published.items():
        assert getattr(ident, key) == pytest.approx(value, rel=0.02), key
    assert ident.s is None
    assert ident.s_note.startswith("not identifiable from these data") and "7 velocity reversals" in ident.s_note


@needs_emps
def test_emps_asymmetric(emps):
    ident = identify(emps, model="asymmetric")
    # README: "roughly" 167 / 240 N s/m, given to 3 digits: 2 % covers the rounding and the rough procedure
    assert ident.sigma_pos == pytest.approx(167.0, rel=0.02) and ident.sigma_neg == pytest.approx(240.0, rel=0.02)
    # The Coulomb split against the offset is not identifiable in gross sliding (only the levels
    # Cf_pos + offset and offset - Cf_neg are); compare the split-free sum with 20.1 + 20.6.
    assert ident.Cf_pos + ident.Cf_neg == pytest.approx(20.1 + 20.6, rel=0.02)
    assert ident.s is None


@needs_emps
def test_emps_to_config(emps, tmp_path):
    cfg = identify(emps).to_config(name="emps")
    assert cfg.plant.K == EMPS_GAIN and cfg.observer.dt == pytest.approx(1e-3, rel=1e-4)
    assert cfg.sensor.quantization == pytest.approx(5e-8, rel=1e-6)
    _check_config(cfg, tmp_path)


def test_settled_rows_leave_out_the_travel_after_each_reversal():
    # x = A sin(w t): after each reversal the travel is A (1 - cos(w tau)), below d for w tau < acos(1 - d/A),
    # a share acos(1 - d/A) / pi of each half period
    from obsdesign.data._ident_fit import settled_rows
    t = np.arange(200_000) * 1e-5
    A, d = 0.01, 2e-3
    x = A * np.cos(2 * np.pi * 1.0 * t)            # reversals at t = 0.5, 1.0, 1.5 s
    ok = settled_rows(x, np.gradient(x, 1e-5), d, lambda c: c)
    after = t >= 0.5
    assert 1.0 - np.mean(ok[after]) == pytest.approx(np.arccos(1.0 - d / A) / np.pi, abs=1e-3)
    assert settled_rows(x, np.gradient(x, 1e-5), 0.0, lambda c: c) is None


@pytest.mark.parametrize("s", [3000.0, 1e4])
def test_presliding_rows_do_not_bias_the_fit(s, monkeypatch):
    # 0.33 mm and 0.1 mm of pre-sliding after each reversal of a random force: with those rows left out the
    # 95 % intervals hold the truth; with them (the fit before) Coulomb is biased low by more than 1 %
    trace = _simulated_trace(s)
    ident = identify(trace, presliding_window=1e-3)
    truth = dict(m=TRUE["m"], sigma=TRUE["sigma"], Cf=TRUE["Cf"], offset=TRUE["G"])
    for name, value in truth.items():
        lo, hi = ident.intervals[name]
        assert lo <= value <= hi, (name, lo, hi)
    monkeypatch.setattr(sys.modules["obsdesign.data.identify"], "PRESLIDING_TRAVEL", 0.0)
    before = identify(trace, presliding_window=1e-3)
    assert before.Cf < 0.99 * TRUE["Cf"] and before.travel_floor == 0.0


def test_fast_reversals_resolve_s_in_the_wider_window(monkeypatch):
    # a 4 kHz axis (2^20 counts/rev, the paper's pre-sliding over 0.5 mrad) tracking a chirp up to 4 Hz: no
    # reversal dwells 5 rows within 0.1 mrad, so s needs the wider window; without the travel floor Coulomb is
    # 6.8 % low (outside its interval on 2 of 6 seeds), with it the intervals hold the truth
    q = 2 * math.pi / 2**20
    cfg = od.load_preset("vcm").override(m=2.5e-3, sigma=1e-3, Cf=0.05, s=2000.0, G=0.0, dt=2.5e-4,
                                         noise_rms=3e-6, quantization=q)
    res = od.simulate(cfg, od.sim.Chirp(f0=0.5, f1=4.0, peak_velocity=2.0), controller="pid", duration=8.0, seed=0)
    trace = Trace(t=res.t, position=res.x_meas, force=res.u, sample_time=2.5e-4)
    ident = identify(trace)
    # the floor from the reversals in 1 mrad; s itself is not reported (no reversal dwells in 0.1 mrad)
    assert ident.s is None and 1e-4 < ident.travel_floor < 1e-3 and "left out all the same" in ident.s_note
    for name, value in dict(m=2.5e-3, sigma=1e-3, Cf=0.05).items():
        lo, hi = ident.intervals[name]
        assert lo <= value <= hi, (name, lo, hi)
    assert ident.m == pytest.approx(2.5e-3, rel=0.005) and ident.Cf == pytest.approx(0.05, rel=0.03)
    module = sys.modules["obsdesign.data.identify"]
    monkeypatch.setattr(module, "WINDOW_STEPS", 1)   # the default window alone: s not resolved, no floor
    narrow = identify(trace)
    assert narrow.s is None and narrow.travel_floor == 0.0
    assert narrow.Cf < 0.95 * 0.05 and narrow.m < 0.99 * 2.5e-3
    # ... and then the rows within the window (0.1 mm in the trace's metres, a fifth of the travel) are left out of a second fit whose
    # change widens the intervals (Cf +5.6 %, m +2.1 %): they hold the truth all the same, and a notice says so
    assert narrow.presliding_shift["Cf"] > 0.03 * 0.05 and narrow.presliding_shift["m"] > 0.01 * 2.5e-3
    for name, value in dict(m=2.5e-3, sigma=1e-3, Cf=0.05).items():
        lo, hi = narrow.intervals[name]
        assert lo <= value <= hi, (name, lo, hi)
    assert any(n.startswith("s not resolved: without the rows within 0.0001 m") and "Cf +5" in n
               for n in narrow.notices), narrow.notices
    assert "without the rows near reversals" in narrow.interval_method and not ident.presliding_shift


def test_a_travel_floor_that_leaves_too_few_rows_keeps_them(monkeypatch):
    # s so small that 1/s covers every stroke: identify keeps its first fit and says why, not an error
    trace = _simulated_trace(3000.0)
    monkeypatch.setattr(sys.modules["obsdesign.data.identify"], "PRESLIDING_TRAVEL", 1e6)
    ident = identify(trace, presliding_window=1e-3)
    assert ident.travel_floor == 0.0 and ident.s is not None
    assert "the fit keeps the rows within 1/s of the reversals: without them" in ident.s_note
    assert "expected at least 20" in ident.s_note
