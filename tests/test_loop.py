"""Loop views of the PID: against closed forms and computations independent of python-control."""

from __future__ import annotations

import math

import matplotlib
import numpy as np
import pytest
import scipy.optimize

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
