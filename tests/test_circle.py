"""The two-axis circle test: its path against the circle's closed form, its metrics against a
synthetic contour with known glitches, the feed-forward's limit on an exactly modelled plant, and
its refusals."""

from __future__ import annotations

import numpy as np
import pytest

import obsdesign as od
from obsdesign.sim.circle import circle_metrics, circle_path, simulate_circle

VCM = od.load_preset("vcm").override(noise_rms=2e-7)


@pytest.mark.parametrize("direction", ["ccw", "cw"])
def test_path_is_the_circle_at_the_feed(direction):
    R, F, dt = 5e-3, 2e-2, 1e-4
    theta, x, y, w = circle_path(R, F, dt, direction=direction)
    assert x[0] == 0.0 and y[0] == 0.0
    assert np.allclose(np.hypot(x + R, y), R, rtol=0, atol=1e-15)
    speed = np.hypot(np.diff(x), np.diff(y)) / dt
    assert np.allclose(speed[w], F, rtol=1e-6)  # constant feed over the evaluated revolution
    assert theta[w.start] >= 2 * np.pi and theta[w.stop - 1] < 4 * np.pi
    # ccw: y = R sin(theta) > 0 in the first quadrant of the revolution; cw the mirror
    quarter = w.start + 10
    assert np.sign(y[quarter]) == (1 if direction == "ccw" else -1)


def test_metrics_of_a_contour_with_known_glitches():
    """r = R + d(theta): four bumps of heights 1, 2, 3, 4 um, half-width 0.05 rad, just after the reversals."""
    R, dt = 5e-3, 1e-4
    theta = np.linspace(0, 4.5 * np.pi, 200001)
    w = slice(int(np.searchsorted(theta, 2 * np.pi)), int(np.searchsorted(theta, 4 * np.pi)))
    heights = [1e-6, 2e-6, 3e-6, 4e-6]
    d = np.zeros_like(theta)
    for h, angle in zip(heights, (0.0, np.pi / 2, np.pi, 1.5 * np.pi)):
        phase = np.mod(theta - angle - 0.1, 2 * np.pi)  # peak 0.1 rad after the reversal
        d += h * np.clip(1 - np.abs(np.where(phase > np.pi, phase - 2 * np.pi, phase)) / 0.05, 0, None)
    x, y = (R + d) * np.cos(theta) - R, (R + d) * np.sin(theta)
    m = circle_metrics(theta, x, y, x, y, R, dt, w)
    got = [g["height"] for g in m["glitches"]]
    assert got == pytest.approx(heights, rel=1e-3)
    assert m["glitch_peak"] == pytest.approx(4e-6, rel=1e-3)
    assert m["circularity"] == pytest.approx(4e-6, rel=1e-3)
    # the triangle's part above half its height is 0.05 rad wide; dtheta per sample, dt per sample
    dtheta = theta[1] - theta[0]
    assert [g["duration"] for g in m["glitches"]] == pytest.approx([0.05 / dtheta * dt] * 4, rel=0.01)
    assert m["axes"]["x"]["max"] == 0.0  # the references are the positions here


@pytest.mark.parametrize("feed", [pytest.param(2e-3, marks=pytest.mark.slow), 6.3e-3, 2e-2])  # the slowest feed: 2 s
def test_feedforward_of_the_exact_friction_model_removes_the_glitch(feed):
    """Plant friction = the feed-forward model: Coulomb + viscous with the design's Cf, sigma and no
    pre-sliding to speak of (s = 1e7 1/m: 0.1 um, a tenth of an encoder count), the feed-forward a
    velocity function (``ff_presliding`` off). Compensating sign(v_ref) Cf + sigma v_ref cancels the
    friction but for the sampling and the tracking error's own velocity, so the quadrant glitch must
    fall to at most 10 % of the PID-only one."""
    plant = VCM.override(s=1e7)
    pid = simulate_circle(VCM, radius=5e-3, feed=feed, controller="pid", plant=plant).metrics
    ff = simulate_circle(VCM.override(mode="feedforward", ff_presliding=False), radius=5e-3, feed=feed,
                         plant=plant).metrics
    assert ff["glitch_peak"] <= 0.10 * pid["glitch_peak"]


@pytest.mark.parametrize("feed", [pytest.param(2e-3, marks=pytest.mark.slow), 6.3e-3, 2e-2])  # the slowest feed: 3 s
def test_feedforward_with_the_models_presliding_curve_on_its_own_plant(feed):
    """The preset's plant (Coulomb with pre-sliding memory, s = 3000 1/m) and the default feed-forward,
    whose Coulomb term follows the same pre-sliding curve along the reference: the model is the
    plant's friction but for the plant's own tracking error (the friction turns over the travel of
    the axis, the model over that of the reference) and the viscous term, so again at most 10 % of
    the PID-only glitch; a velocity-function feed-forward on this plant over-compensates after each
    reversal and does worse than the curve."""
    pid = simulate_circle(VCM, radius=5e-3, feed=feed, controller="pid").metrics["glitch_peak"]
    curve = simulate_circle(VCM.override(mode="feedforward"), radius=5e-3, feed=feed).metrics["glitch_peak"]
    switch = simulate_circle(VCM.override(mode="feedforward", ff_presliding=False), radius=5e-3,
                             feed=feed).metrics["glitch_peak"]
    assert curve <= 0.10 * pid and curve < switch


def test_presliding_weight_is_the_plant_models_friction_along_the_reference():
    """``w_ff`` with the curve = sign(v_ref) Fc/Cf of the plant's own friction routine driven by the
    reference (an independent loop over eq:2:3:1-4), times the look-ahead ramp."""
    from obsdesign.friction.presliding import coulomb_normalized, track_reversal
    from obsdesign.sampled.reference import reference_feedforward

    t = np.arange(3000) * 1e-4
    x = 2e-3 * np.sin(2 * np.pi * 5 * t)
    s = 3000.0
    v, w = reference_feedforward(x, 1e-4, presliding=s)
    _, ramp = reference_feedforward(x, 1e-4, lookahead=40)
    _, both = reference_feedforward(x, 1e-4, lookahead=40, presliding=s)
    d, xr, fr, expect = 0.0, x[0], 0.0, np.empty_like(x)
    for i in range(len(x)):
        d, xr, fr = track_reversal(v[i], x[i], d, xr, fr, s)
        expect[i] = coulomb_normalized(x[i], d, xr, fr, s) * np.sign(v[i]) if v[i] != 0 else 1.0
    assert np.array_equal(w, expect)
    assert w.min() == -1.0 and w.max() == 1.0
    assert np.allclose(both, w * ramp, rtol=0, atol=1e-15)


def test_refusals():
    with pytest.raises(ValueError, match="feed: expected a path velocity the axis can drive"):
        simulate_circle(VCM, radius=5e-3, feed=2.0)
    with pytest.raises(ValueError, match=r"radius: expected a radius in \[0.0001, 1\] m"):
        simulate_circle(VCM, radius=5e-5, feed=1e-3)
    with pytest.raises(ValueError, match="compensation.lookahead: expected at most"):
        simulate_circle(VCM.override(mode="feedforward", lookahead=20000), radius=5e-3, feed=2e-2)
    with pytest.raises(ValueError, match="direction: expected one of"):
        simulate_circle(VCM, direction="up")


@pytest.mark.parametrize("argv, message", [
    (["--feed", "5"], "feed: expected a path velocity the axis can drive"),
    (["--radius", "1e-5"], "radius: expected a radius in"),
    (["--feed", "2e-2", "--modes", "feedforward", "--lookahead", "20000"], "compensation.lookahead: expected at most"),
    (["--modes", "pid,sideways"], "mode: expected one of"),
    (["--ff-presliding", "maybe"], "argument --ff-presliding: invalid choice: 'maybe'"),
])
def test_cli_bad_input_is_one_line_and_exit_2(argv, message, capsys):
    from obsdesign.cli import main

    assert main(["simulate", "circle", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_cli_circle_rows_are_the_api_rows(capsys):
    import json

    from obsdesign.cli import main
    from obsdesign.sim.circle import circle_modes

    peaks = {}
    for flag, presliding in (("on", True), ("off", False)):
        assert main(["simulate", "circle", "--feed", "2e-2", "--modes", "pid,feedforward", "--buildup", "3e-4",
                     "--ff-presliding", flag, "--json"]) == 0
        rows = json.loads(capsys.readouterr().out)["rows"]
        api = circle_modes(od.load_preset("vcm").override(buildup=3e-4, ff_presliding=presliding),
                           modes=("pid", "feedforward"), feeds=(2e-2,))
        assert [r["glitch_peak"] for r in rows] == [r["glitch_peak"] for r in api]
        peaks[flag] = rows[1]["glitch_peak"]
    assert peaks["on"] != peaks["off"]  # the flag reaches the run


def test_cli_plot_writes_the_ballbar_figure(tmp_path, capsys):
    from obsdesign.cli import main

    out = tmp_path / "ballbar.svg"
    assert main(["simulate", "circle", "--feed", "2e-2", "--modes", "pid,observer", "--plot", str(out)]) == 0
    assert out.read_text().startswith("<?xml")
    from obsdesign.report.circle_section import ballbar_figure

    res = simulate_circle(VCM, feed=2e-2, keep_trace=True)
    fig = ballbar_figure({"a": res, "b": res})
    assert [ax.name for ax in fig.axes] == ["polar", "polar"]
    labels = sorted(float(t.get_text()) for t in fig.axes[0].texts)  # the four glitches, marked with their heights
    assert labels == pytest.approx(sorted(round(g["height"] * 1e6, 1) for g in res.metrics["glitches"]))
    # without a trace the figure is refused, naming the run
    with pytest.raises(ValueError, match="results: run 'x' has no trace"):
        ballbar_figure({"x": simulate_circle(VCM, feed=2e-2)})
