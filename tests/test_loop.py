"""Loop views of the PID: against closed forms and computations independent of python-control."""

from __future__ import annotations

import math

import matplotlib
import numpy as np
import pytest
import scipy.optimize
from hypothesis import given, settings
from hypothesis import strategies as st

import obsdesign as od
from obsdesign.design.loop import LoopAnalysis, loop_analysis, loop_figure
from obsdesign.design.pid import pid_from_config

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def vcm():
    return od.load_preset("vcm")


@pytest.fixture(scope="module")
def la(vcm):
    return loop_analysis(vcm)


def _polys(pid):
    """Numerator and denominator of L = C H multiplied out by hand (numpy only)."""
    num = np.polymul([pid.k * pid.tau * pid.T_I, pid.k * (pid.tau + pid.T_I), pid.k], [pid.phi])
    den = np.polymul([pid.T_I, 0.0], [pid.tau, 1.0, 0.0])
    return num, den


def _L(pid, w):
    num, den = _polys(pid)
    s = 1j * np.asarray(w)
    return np.polyval(num, s) / np.polyval(den, s)


def test_phase_margin_is_the_designed_one(la, vcm):
    assert la.phase_margin_deg == pytest.approx(vcm.pid.phase_margin_deg, abs=1e-9)
    assert math.isinf(la.gain_margin_db) and la.to_dict()["gain_margin_db"] is None


def test_crossover_is_tan_phi_over_T_I(la, vcm):
    pid = pid_from_config(vcm)
    assert la.crossover_rad_s == pytest.approx(math.tan(math.radians(60.0)) / pid.T_I, rel=1e-9)
    assert la.crossover_rad_s == pytest.approx(pid.omega_s, rel=1e-9)
    assert abs(_L(pid, la.crossover_rad_s)) == pytest.approx(1.0, rel=1e-9)
    # phase margin from the hand-computed loop at that frequency
    assert 180.0 + math.degrees(np.angle(_L(pid, la.crossover_rad_s))) == pytest.approx(60.0, abs=1e-7)


def test_closed_loop_poles_are_roots_of_the_characteristic_polynomial(la, vcm):
    pid = pid_from_config(vcm)
    num, den = _polys(pid)
    char = np.polyadd(den, num)
    roots = sorted(np.roots(char), key=lambda p: (p.real, p.imag))
    np.testing.assert_allclose(np.array(la.closed_loop_poles), roots, rtol=1e-9)
    # the plant pole -1/tau cancelled by the controller zero stays a closed-loop pole
    assert min(abs(p + 1.0 / pid.tau) for p in la.closed_loop_poles) < 1e-9 / pid.tau
    assert all(p.real < 0 for p in la.closed_loop_poles)


def test_sensitivity_peaks_by_a_dense_grid(la, vcm):
    pid = pid_from_config(vcm)
    w = np.logspace(-2, 5, 400_001)
    L = _L(pid, w)
    S, T = np.abs(1.0 / (1.0 + L)), np.abs(L / (1.0 + L))
    assert la.max_S == pytest.approx(S.max(), rel=1e-6)
    assert la.max_T == pytest.approx(T.max(), rel=1e-6)
    assert la.max_S >= S.max() * (1 - 1e-12) and la.max_T >= T.max() * (1 - 1e-12)
    # T = a (T_I s + 1) / (T_I s^2 + a T_I s + a) with a = k phi: for Phi = 60 deg the peak is 3/sqrt(5)
    assert la.max_T == pytest.approx(3.0 / math.sqrt(5.0), rel=1e-9)
    Sd = np.abs(pid.phi / (1j * w * (pid.tau * 1j * w + 1)) / (1.0 + L))
    assert la.max_S_disturbance == pytest.approx(Sd.max(), rel=1e-6)
    assert la.max_S_disturbance <= vcm.pid.max_S


def test_bandwidth_where_T_is_one_over_sqrt2(la, vcm):
    pid = pid_from_config(vcm)

    def excess(logw):
        L = _L(pid, 10.0**logw)
        return abs(L / (1.0 + L)) - 1.0 / math.sqrt(2.0)

    # bracket: |T| > 1/sqrt(2) at the peak, < at 100x the crossover
    logw = scipy.optimize.bisect(excess, math.log10(la.omega_max_T), math.log10(100 * la.crossover_rad_s),
                                 xtol=1e-14)
    assert la.bandwidth_rad_s == pytest.approx(10.0**logw, rel=1e-9)


def test_overrides_match_an_overridden_config(vcm):
    a = loop_analysis(vcm, phi=0.05, tau=0.01)
    b = loop_analysis(vcm.override(phi=0.05, tau=0.01))
    assert a.to_dict() == b.to_dict()
    assert a.to_dict() != loop_analysis(vcm).to_dict()


@pytest.mark.parametrize("args, kwargs, exc, match", [
    (("vcm",), {}, TypeError, "cfg: expected a Config"),
    ((), {"tau": -1.0}, ValueError, "tau"),
    ((), {"phi": 0.0}, ValueError, "phi"),
])
def test_errors(args, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        loop_analysis(*args, **kwargs)


def test_to_dict_keys_and_json(la):
    import json

    d = la.to_dict()
    assert list(d)[:7] == ["gain_margin_db", "phase_margin_deg", "crossover_rad_s", "max_S", "max_T",
                           "bandwidth_rad_s", "closed_loop_poles"]
    assert all(len(p) == 2 for p in d["closed_loop_poles"])
    json.dumps(d, allow_nan=False)


def test_text_and_html(la):
    text = str(la)
    assert "phase margin [deg]" in text and "rad/s" in text and "infinite" in text
    h = la._repr_html_()
    assert "<table" in h and "max |H/(1+HC)|" in h and "|S| output" in h
    assert "<th>max |H/(1+HC)| input disturbance [m/V]</th>" in h


def test_figure_panels_have_labels_and_legends(la):
    fig = loop_figure(la)
    assert len(fig.axes) == 5
    for ax in fig.axes:
        assert ax.get_xlabel() and ax.get_ylabel() and "[" in ax.get_xlabel() and "[" in ax.get_ylabel()
        assert ax.get_legend() is not None
    labels = [t.get_text() for ax in fig.axes for t in ax.get_legend().get_texts()]
    assert any("phase margin 60 deg" in x for x in labels)
    assert any("gain margin" in x for x in labels)
    assert any("critical point -1" in x for x in labels) and any("unit circle" in x for x in labels)
    with pytest.raises(TypeError, match="analysis: expected a LoopAnalysis"):
        loop_figure(la.to_dict())


def test_result_is_frozen(la):
    with pytest.raises(Exception):
        la.max_S = 0.0  # type: ignore[misc]
    assert isinstance(la, LoopAnalysis)


# --------------------------------------------------------------------------------------------
# Step metrics (obsdesign.sim.step_metrics); here because this branch may add only these test files.
from obsdesign.sim.step_metrics import last_outside, step_metrics  # noqa: E402

ZETA, WN = 0.4, 10.0


@pytest.fixture(scope="module")
def second_order():
    import control as ct

    sys = ct.tf([WN**2], [1.0, 2 * ZETA * WN, WN**2])
    t = np.linspace(0.0, 3.0, 300_001)  # dt = 1e-5 s
    resp = ct.step_response(sys, t)
    return t, np.asarray(resp.outputs).ravel()


def _analytic(t):
    wd = WN * math.sqrt(1 - ZETA**2)
    return 1.0 - np.exp(-ZETA * WN * t) / math.sqrt(1 - ZETA**2) * np.sin(wd * t + math.acos(ZETA))


def test_step_metrics_against_step_info(second_order):
    import control as ct

    t, y = second_order
    band = 0.02
    info = ct.step_info(y, t, SettlingTimeThreshold=band, RiseTimeLimits=(0.1, 0.9), final_output=1.0)
    m = step_metrics(t, y, t_step=0.0, y0=0.0, y1=1.0, settle_band=band * 1.0)  # relative band x |y1|
    dt = t[1] - t[0]
    assert m["overshoot"] == pytest.approx(info["Overshoot"] / 100.0, rel=1e-12)
    assert m["peak_time"] == pytest.approx(info["PeakTime"], abs=1e-15)
    # step_info takes the first sample past each limit; ours interpolates: within one sample
    assert abs(m["rise_time"] - info["RiseTime"]) <= dt
    # step_info's band is open (>= threshold is outside), ours closed: equal unless a sample hits the edge
    assert abs(m["settling_time"] - info["SettlingTime"]) <= dt


def test_step_metrics_against_closed_forms(second_order):
    t, y = second_order
    m = step_metrics(t, y, t_step=0.0, y0=0.0, y1=1.0, settle_band=0.02)
    root = math.sqrt(1 - ZETA**2)
    assert m["overshoot"] == pytest.approx(math.exp(-math.pi * ZETA / root), rel=1e-6)
    assert m["peak_time"] == pytest.approx(math.pi / (WN * root), abs=1e-5)
    # rise time: the analytic response's 10 % and 90 % crossings, by root finding
    t10 = scipy.optimize.brentq(lambda s: _analytic(s) - 0.1, 1e-9, 0.2)
    t90 = scipy.optimize.brentq(lambda s: _analytic(s) - 0.9, 0.05, math.pi / (WN * root))
    assert m["rise_time"] == pytest.approx(t90 - t10, rel=1e-6)  # interpolation error O(dt^2)


def test_step_metrics_is_symmetric_and_shift_invariant(second_order):
    t, y = second_order
    ref = step_metrics(t, y, t_step=0.0, y0=0.0, y1=1.0, settle_band=0.02)
    # a step down from 3 to 1, starting at t = 0.5 s, preceded by a flat stretch
    pre = np.arange(1, 50_001) * -1e-5
    t2 = np.concatenate([pre[::-1], t]) + 0.5
    y2 = np.concatenate([np.full(pre.size, 3.0), 3.0 - 2.0 * y])
    m = step_metrics(t2, y2, t_step=0.5, y0=3.0, y1=1.0, settle_band=0.04)
    for key in ref:
        assert m[key] == pytest.approx(ref[key], rel=1e-9, abs=1e-12)


def test_step_metrics_edge_cases():
    t = np.arange(5) * 0.1
    assert step_metrics(t, [1, 1, 1, 1, 1], t_step=0, y0=0, y1=1, settle_band=0.1) == {
        "overshoot": 0.0, "rise_time": 0.0, "settling_time": 0.0, "peak_time": 0.0}
    never = step_metrics(t, [0, 0.2, 0.5, 0.7, 0.8], t_step=0, y0=0, y1=1, settle_band=0.1)
    assert never["rise_time"] is None and never["settling_time"] is None and never["overshoot"] == 0.0
    lost = step_metrics(t, [0, 1, 1, np.nan, 1], t_step=0, y0=0, y1=1, settle_band=0.1)
    assert lost["settling_time"] == pytest.approx(0.4)  # a NaN sample counts as outside the band


def _step_metrics_by_hand(t, y, t_step, y0, y1, band):
    """The module's definitions sample by sample, in plain Python (no NumPy)."""
    dt_min = min(b - a for a, b in zip(t, t[1:]))
    keep = [i for i in range(len(t)) if t[i] >= t_step - 0.5 * dt_min]
    ts, ys = [t[i] for i in keep], [y[i] for i in keep]
    r = [(v - y0) / (y1 - y0) for v in ys]
    peak_of = [-math.inf if math.isnan(v) else v for v in r]
    i_peak = peak_of.index(max(peak_of))  # the first of the largest

    def crossing(level):
        for i, v in enumerate(r):
            if v >= level:
                return ts[0] if i == 0 else ts[i - 1] + (level - r[i - 1]) * (ts[i] - ts[i - 1]) / (v - r[i - 1])
        return None

    outside = [i for i, v in enumerate(ys) if not abs(v - y1) <= band]
    t10, t90 = crossing(0.1), crossing(0.9)
    return {"overshoot": max(0.0, peak_of[i_peak] - 1.0),
            "rise_time": None if t10 is None or t90 is None else t90 - t10,
            "settling_time": 0.0 if not outside else None if outside[-1] == len(ys) - 1 else ts[outside[-1] + 1] - t_step,
            "peak_time": ts[i_peak] - t_step}


@settings(max_examples=200, deadline=None)
@given(steps=st.lists(st.one_of(st.floats(0.01, 1.0), st.sampled_from([0.25, 0.5, 1.0])), min_size=2, max_size=40),
       values=st.lists(st.sampled_from([-0.5, 0.0, 0.05, 0.1, 0.3, 0.9, 0.95, 1.0, 1.02, 1.3, math.nan]),
                       min_size=41, max_size=41),
       start=st.floats(0.0, 1.0), on_sample=st.integers(-1, 40), down=st.booleans(),
       band=st.sampled_from([0.01, 0.05, 0.2]))
def test_step_metrics_equals_its_definitions_by_hand(steps, values, start, on_sample, down, band):
    """Any trace (lost samples, plateaus at the limits, a step up or down; a step half a sample after
    a sample, the edge of "from t_step on"), with and without a scratch buffer: the module's definitions
    computed sample by sample give the same numbers, and t, y are untouched."""
    t = np.cumsum([0.0, *steps])
    y = np.asarray(values[:t.size])
    y0, y1 = (2.0, 1.0) if down else (0.0, 1.0)
    if down:
        y = 2.0 - y  # the same response, mirrored: a step down from 2 to 1
    t_step = float(t[0] + start * (t[-1] - t[0]))
    if 0 <= on_sample < t.size:  # the threshold t_step - dt_min / 2 falls on a sample (dyadic steps: exactly)
        t_step = float(t[on_sample] + 0.5 * np.diff(t).min())
    expected = _step_metrics_by_hand(list(t), list(y), t_step, y0, y1, band)
    t_copy, y_copy = t.copy(), y.copy()
    for scratch in (None, np.full(t.size + 3, 7.0)):
        m = step_metrics(t, y, t_step=t_step, y0=y0, y1=y1, settle_band=band, scratch=scratch)
        assert m.keys() == expected.keys()
        for key, value in expected.items():
            assert (m[key] is None) if value is None else m[key] == pytest.approx(value, rel=1e-12, abs=1e-15,
                                                                                   nan_ok=True), key
        np.testing.assert_array_equal(t, t_copy)
        np.testing.assert_array_equal(y, y_copy)


@given(values=st.lists(st.sampled_from([-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, math.nan, math.inf]), max_size=30),
       center=st.sampled_from([0.0, 0.5]))
def test_last_outside_is_the_last_index_outside_the_band(values, center):
    y = np.asarray(values, dtype=float)
    outside = [i for i, v in enumerate(values) if not abs(v - center) <= 1.0]
    expected = outside[-1] if outside else None
    assert last_outside(y, center, 1.0) == expected
    assert last_outside(y, center, 1.0, scratch=np.empty(y.size + 1)) == expected


@pytest.mark.parametrize("args, kwargs, exc, match", [
    (([0, 1], [0, 1, 2]), {}, ValueError, "t, y: expected two 1-D arrays"),
    (([0.0], [0.0]), {}, ValueError, "t: expected at least 2 samples"),
    (([0, 0], [0, 1]), {}, ValueError, "t: expected strictly increasing"),
    (([0, 1], [0, 1]), {"y1": 0.0}, ValueError, "y1: expected a value different from y0"),
    (([0, 1], [0, 1]), {"settle_band": 0.0}, ValueError, "settle_band: expected a number > 0"),
    (([0, 1], [0, 1]), {"t_step": 5.0}, ValueError, "t_step: expected a time within the trace"),
    (([0, 1], [0, 1]), {"y0": "0"}, TypeError, "y0: expected a real number"),
    (([0, 1], [0, 1]), {"y0": math.nan}, ValueError, "y0: expected a finite number"),
])
def test_step_metrics_errors(args, kwargs, exc, match):
    kw = dict(t_step=0.0, y0=0.0, y1=1.0, settle_band=0.1) | kwargs
    with pytest.raises(exc, match=match):
        step_metrics(*args, **kw)


def test_step_metrics_settling_matches_the_simulator(vcm):
    res = od.simulate(vcm, "positioning", controller="pid+observer", duration=4.0)
    holds = ((0.5, 3.0), (3.0, 4.0))  # the positioning scenario's holds (step up at 0.5 s, down at 3 s)
    dt = vcm.observer.dt
    for (start, end), expected in zip(holds, res.metrics["settling_time"]):
        sel = (res.t >= start - 0.5 * dt) & (res.t < end - 0.5 * dt)
        before = res.x_ref[np.nonzero(sel)[0][0] - 1]
        m = step_metrics(res.t[sel], res.x[sel], t_step=start, y0=before, y1=res.x_ref[sel][0], settle_band=2e-6)
        assert expected is not None and m["settling_time"] == pytest.approx(expected, rel=1e-12)
        assert m["overshoot"] >= 0.0 and 0.0 < m["rise_time"] < m["settling_time"]
