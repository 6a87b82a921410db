"""The shipped example log: where it is, what it holds, and that it tells the truth it was made with."""

from __future__ import annotations

import numpy as np
import pytest

import obsdesign as od
from obsdesign.data import identify, load_trace
from obsdesign.datasets import example_log
from obsdesign.datasets import make_example_log as maker

#: The axis the log was simulated with (written here, not read from the script).
TRUTH = {"m": 0.8, "sigma": 12.0, "Cf": 0.9}
#: Closed-loop identification bias allowed: measurement noise is fed back into the force (measured with the
#: rows within 1/s of each reversal left out: -0.18 %, -0.10 %, +0.06 %; with them: -1.7 %, +2.9 %, -3.3 %).
RTOL = 0.01


def test_the_accessor_returns_the_package_data_file():
    path = example_log()
    assert path.is_file() and path.parent.name == "datasets"
    assert od.datasets.example_log() == path
    assert path.stat().st_size < 300_000  # "a few hundred kB at most"


def test_the_log_is_8_s_at_1_khz_in_si_units():
    trace = load_trace(example_log(), position="x", input="u", time="t")
    assert trace.samples == 8000 and trace.sample_time == pytest.approx(1e-3, rel=1e-9)
    # an encoder of 1 um: every position is a whole number of steps
    steps = trace.position / 1e-6
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    assert 5e-3 < np.ptp(trace.position) < 2e-2  # millimetres of travel, so metres, not mm
    assert trace.reversals >= 20


def test_the_script_simulates_the_stated_truth():
    assert {k: maker.AXIS[k] for k in TRUTH} == TRUTH


def test_identification_recovers_the_known_axis():
    ident = identify(load_trace(example_log(), position="x", input="u", time="t"))
    found = {"m": ident.m, "sigma": ident.sigma, "Cf": ident.Cf}
    assert found == pytest.approx(TRUTH, rel=RTOL)
    assert abs(ident.offset) < 0.02  # no load in the simulation [N]


def test_the_intervals_hold_the_truth():
    ident = identify(load_trace(example_log(), position="x", input="u", time="t"))
    for name, value in TRUTH.items():
        lo, hi = ident.intervals[name]
        assert lo <= value <= hi, (name, lo, hi)
    # the rows within 1/s of travel past each reversal (50 um, pre-sliding) were left out
    assert ident.s is not None and ident.travel_floor == pytest.approx(1.0 / ident.s)
    assert 1e-5 < ident.travel_floor < 1e-4


def test_the_presliding_rows_are_what_biased_the_fit(monkeypatch):
    # with the rows after each reversal kept (the fit before the travel floor) the intervals miss the truth:
    # the check above can fail
    import sys
    monkeypatch.setattr(sys.modules["obsdesign.data.identify"], "PRESLIDING_TRAVEL", 0.0)
    ident = identify(load_trace(example_log(), position="x", input="u", time="t"))
    assert ident.travel_floor == 0.0
    missed = [n for n, v in TRUTH.items() if not ident.intervals[n][0] <= v <= ident.intervals[n][1]]
    assert missed, ident.intervals


def test_a_wrong_truth_would_fail():
    # the tolerance is tight enough to tell the example axis from the paper's VCM (m 0.538, sigma 21.1)
    ident = identify(load_trace(example_log(), position="x", input="u", time="t"))
    assert (ident.m, ident.sigma) != pytest.approx((0.538, 21.1), rel=RTOL)


@pytest.mark.slow
def test_the_script_writes_the_shipped_file_again(tmp_path):
    out = maker.write_csv(tmp_path / "log.csv", *maker.simulate_log())
    assert out.read_text(encoding="utf-8") == example_log().read_text(encoding="utf-8")


@pytest.mark.slow
def test_refined_presliding_scale_holds_the_truth(monkeypatch):
    # `identify --refine s` on the example log (the help's example): the held m, sigma, Cf carry their 95 %
    # intervals (widened by the timing the log does not resolve), not only their standard errors
    from obsdesign.data import oe_stats
    from obsdesign.data.output_error import refine
    trace = load_trace(example_log(), position="x", input="u", time="t")
    ident = identify(trace)
    ref = refine(trace, ident, parameters=("s",))
    assert ref["s"].low <= maker.AXIS["s"] <= ref["s"].high, (ref["s"].low, ref["s"].high)
    # with the standard errors alone (before) the interval missed it
    monkeypatch.setattr(oe_stats, "held_std", lambda ident, name: float(getattr(ident, name + "_std")))
    narrow = refine(trace, ident, parameters=("s",))
    assert not narrow["s"].low <= maker.AXIS["s"] <= narrow["s"].high
