"""The Stribeck term end to end (issue 32 point 4): ``auto`` looks at the rows below the min speed, Fs and vs get
intervals, and the ``-o`` config's feed-forward reads them.

The logs are simulated (tests/_axis_logs.py: LuGre friction with a Stribeck drop in a closed loop), so the truth
is known.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from _axis_logs import AXES, axis_trace, noisy_log, simulate_axis

import obsdesign as od
from obsdesign.data import identify
from obsdesign.sampled.controller import sampled_controller

#: The Stribeck axis of the recovery benchmark with vs = 0.1 rad/s: below the default min speed (1 % of the peak
#: speed 20 rad/s), the case where the default rows hold no Stribeck drop.
LOW_VS = dict(AXES["rotary-4k-hold-d1-stribeck"], vs=0.1)


@pytest.fixture(scope="module")
def low_vs_log():
    return noisy_log(LOW_VS, simulate_axis(LOW_VS), seed=2)


@pytest.mark.slow
def test_auto_keeps_a_drop_below_the_min_speed(low_vs_log):
    trace = axis_trace(LOW_VS, low_vs_log)
    old_rows = identify(trace, n_boot=0, stribeck_min_speed=0.2)  # the rows of the min speed only: vs below them
    assert not old_rows.stribeck and "vs at its lower bound" in old_rows.selection
    ident = identify(trace, n_boot=100)
    assert ident.stribeck and "kept" in ident.selection and "\n" not in ident.selection
    # the rule: at least 2 encoder counts per period of the cut-off (closed form), below the default min speed
    q = LOW_VS["step"]
    assert 2 * q * ident.filter_hz <= ident.stribeck_min_speed * (1 + 1e-9) and ident.stribeck_min_speed < 0.1
    assert f"rows above {ident.stribeck_min_speed:.3g} rad/s" in ident.selection
    for key in ("m", "sigma", "Cf", "offset", "Fs", "vs"):
        lo, hi = ident.intervals[key]
        assert lo <= LOW_VS[key] <= hi and lo <= getattr(ident, key) <= hi, (key, lo, hi, getattr(ident, key))


@pytest.mark.slow
def test_auto_drops_the_term_on_an_axis_without_a_drop():
    spec = AXES["rotary-4k-hold-d2"]
    ident = identify(axis_trace(spec, noisy_log(spec, simulate_axis(spec), seed=0)), n_boot=0)
    assert not ident.stribeck and ident.selection.startswith("Stribeck term dropped") and "\n" not in ident.selection
    assert ident.stribeck_min_speed < ident.min_speed  # it looked at the slow rows


@pytest.mark.slow
def test_cli_stribeck_min_speed_is_the_api_keyword(low_vs_log, tmp_path):
    """``--stribeck-min-speed 0.2`` (above the drop's vs = 0.1) gives the API's ``stribeck_min_speed=0.2``: the rows
    of the min speed only, where the drop is not seen (the same decision and its reason)."""
    path = tmp_path / "rotary.csv"
    np.savetxt(path, np.column_stack([low_vs_log["t"], low_vs_log["x"], low_vs_log["i"]]), delimiter=",",
               header="t,x,i", comments="", fmt="%.17g")
    base = [sys.executable, "-m", "obsdesign", "identify", str(path), "--time", "t", "--position", "x", "--input", "i",
            "--position-unit", "rad", "--input-unit", "A", "--input-gain", str(LOW_VS["gain"]), "--bootstrap", "0"]
    out = subprocess.run(base + ["--stribeck-min-speed", "0.2", "--json"], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    api = identify(axis_trace(LOW_VS, low_vs_log), n_boot=0, stribeck_min_speed=0.2)
    assert data["stribeck"] is api.stribeck is False
    assert math.isclose(data["stribeck_min_speed"], min(0.2, data["min_speed"]), rel_tol=1e-12)
    assert math.isclose(data["stribeck_min_speed"], api.stribeck_min_speed, rel_tol=1e-9)
    bad = subprocess.run(base + ["--stribeck-min-speed", "-1"], capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2 and "--stribeck-min-speed" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_cli_config_carries_fs_vs_to_the_feedforward(low_vs_log, tmp_path):
    path = tmp_path / "rotary.csv"
    np.savetxt(path, np.column_stack([low_vs_log["t"], low_vs_log["x"], low_vs_log["i"]]), delimiter=",",
               header="t,x,i", comments="", fmt="%.17g")
    out = subprocess.run([sys.executable, "-m", "obsdesign", "identify", str(path), "--time", "t", "--position", "x",
                          "--input", "i", "--position-unit", "rad", "--input-unit", "A", "--input-gain",
                          str(LOW_VS["gain"]), "--bootstrap", "50", "--json", "-o", str(tmp_path / "axis.toml")],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["stribeck"] and data["stribeck_min_speed"] < data["min_speed"] * (1 + 1e-12)
    for key in ("Fs", "vs"):
        lo, hi = data["intervals"][key]
        assert lo <= LOW_VS[key] <= hi, (key, lo, hi)
    assert "95 % interval of Fs" in (tmp_path / "axis.toml").read_text()
    cfg = od.load_config(tmp_path / "axis.toml")
    assert math.isclose(cfg.compensation.ff_stribeck, data["Fs"] - data["Cf"], rel_tol=1e-9)
    assert math.isclose(cfg.compensation.ff_stribeck_velocity, data["vs"], rel_tol=1e-9)
    # the feed-forward of the controller built from that config reads them (the one SampledController)
    _, _, args = sampled_controller(cfg.override(mode="feedforward")).kernel_args()
    assert (args.ff_cf, args.ff_stribeck, args.ff_vs) == (cfg.friction.Cf, cfg.compensation.ff_stribeck,
                                                         cfg.compensation.ff_stribeck_velocity)


@pytest.mark.slow
def test_report_data_section_lists_fs_and_vs(low_vs_log):
    from obsdesign.report.data_section import data_section

    rows = data_section(axis_trace(LOW_VS, low_vs_log))["parameters"]
    assert [r[0] for r in rows][-2:] == ["Fs", "vs"] and [r[3] for r in rows][-2:] == ["N m", "rad/s"]
    assert rows[-1][1] == pytest.approx(LOW_VS["vs"], rel=0.3)
