"""Tests of obsdesign.data.observe and the measured-data commands (identify, observe, report --data)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

import obsdesign as od
from obsdesign.cli import main
from obsdesign.data import Trace, identify, load_trace, model_friction_state, observe
from obsdesign.data.observe import presliding_stiffness_along
from obsdesign.data.trace import zero_phase_velocity
from obsdesign.design import design_observer

EMPS_GAIN = 35.15065188
EMPS = Path(os.environ.get("OBSDESIGN_EMPS") or
            Path(__file__).resolve().parents[1].parent / "shared" / "data" / "emps" / "DATA_EMPS.mat")
needs_emps = pytest.mark.skipif(not EMPS.is_file(), reason=f"EMPS data not found at {EMPS} (set OBSDESIGN_EMPS)")
EMPS_FLAGS = ["--position", "qm", "--input", "vir", "--time", "t", "--input-gain", str(EMPS_GAIN)]


# -- the observer over a simulator's own record: one implementation ------------------------------

def _trace_of(res, G):
    """The record a logger would write: the measured position and the actuator force u + G."""
    return Trace(t=res.t, position=res.x_meas, force=res.u + G, sample_time=res.config.observer.dt, source="sim")


@pytest.mark.parametrize("schedule", ["estimated", "constant"])
def test_observe_reproduces_the_simulator_bit_for_bit(schedule):
    # G = 0: u + G - G is u exactly, so any difference would be a second implementation
    cfg = od.load_preset("vcm").override(G=0.0)
    res = od.simulate(cfg, od.sim.Positioning(step_down=0.8), controller="pid+observer", duration=1.0, stiffness=schedule)
    obs = observe(cfg, _trace_of(res, 0.0), stiffness=schedule)
    for name in ("v_hat", "f_hat", "f_hat_filtered", "stiffness"):
        np.testing.assert_array_equal(getattr(obs, name), getattr(res, name), err_msg=name)
    assert np.ptp(res.f_hat) > 0.1  # the comparison is not between constants


def test_observe_feeds_the_net_force_u_minus_G():
    cfg = od.load_preset("vcm")  # G = 5.27 N
    res = od.simulate(cfg, od.sim.Positioning(step_down=0.8), controller="pid+observer", duration=1.0)
    obs = observe(cfg, _trace_of(res, cfg.plant.G))
    # (u + G) - G differs from u by rounding only
    np.testing.assert_allclose(obs.f_hat, res.f_hat, rtol=0, atol=1e-9 * np.max(np.abs(res.f_hat)))
    np.testing.assert_allclose(obs.v_hat, res.v_hat, rtol=0, atol=1e-9 * np.max(np.abs(res.v_hat)))
    wrong = observe(cfg.override(G=0.0), _trace_of(res, cfg.plant.G))
    # without the feed-forward the observer sees G more force, which it assigns to friction
    assert np.mean(wrong.f_hat[5000:] - obs.f_hat[5000:]) == pytest.approx(cfg.plant.G, rel=0.05)


def test_observer_against_scipy_lsim():
    """Constant stiffness: the observer is LTI; with u = 0 and a piecewise-linear x, lsim is exact."""
    cfg = od.load_preset("table1").override(dt=1e-3)
    n, dt = 400, 1e-3
    t = np.arange(n) * dt
    x = 1e-4 * np.sin(2 * np.pi * 3 * t) + 2e-5 * np.cos(2 * np.pi * 11 * t)
    obs = observe(cfg, Trace(t=t, position=x, force=np.zeros(n), sample_time=dt), stiffness="constant")
    aff = design_observer(cfg).affine()
    k = cfg.friction.kappa
    A, g = aff.A0 + k * aff.A1, aff.g0 + k * aff.g1
    L1, L2 = aff.design.L1, aff.design.L2
    y0 = np.array([-L1 * x[0], -L2 * x[0]])  # v_hat(0) = f_hat(0) = 0
    _, _, y = signal.lsim((A, g[:, None], np.eye(2), np.zeros((2, 1))), x, t, X0=y0, interp=True)
    np.testing.assert_allclose(obs.v_hat, y[:, 0] + L1 * x, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(obs.f_hat, y[:, 1] + L2 * x, rtol=1e-7, atol=1e-6 * np.max(np.abs(obs.f_hat)))


def test_true_schedule_is_the_presliding_stiffness_closed_form():
    Cf, s, kappa = 2.0, 1e3, 1e5
    x = np.array([0.0, 0.0, 1e-4, 5e-4, 2e-3, 2e-3, 1.9e-3, 1.5e-3])  # reversal at sample 6: x_r = 1.9 mm
    v = np.array([0.0, 1.0, 1.0, 1.0, 1.0, 0.0, -1.0, -1.0])
    k = presliding_stiffness_along(x, v, Cf, s, kappa)
    # from rest |dir - f_r| = 1: k = s Cf ln(1/z); after gross sliding |dir - f_r| = 2: k = 2 s Cf ln(1/z)
    expected = [kappa, kappa, s * Cf * np.log(1 / 0.1), s * Cf * np.log(1 / 0.5), 0.0, 0.0,
                kappa, 2 * s * Cf * np.log(1 / 0.4)]
    np.testing.assert_allclose(k, expected, rtol=1e-12)


def test_observation_exports_round_trip(tmp_path):
    cfg = od.load_preset("table1")
    t = np.arange(300) * 1e-4
    tr = Trace(t=t, position=1e-5 * np.sin(40 * t), force=0.1 * np.cos(40 * t), sample_time=1e-4)
    obs = observe(cfg, tr)
    obs.to_csv(tmp_path / "o.csv")
    obs.to_npz(tmp_path / "o.npz")
    back = np.genfromtxt(tmp_path / "o.csv", delimiter=",", names=True)
    assert back.dtype.names == ("t", "x_meas", "u", "v_hat", "f_hat", "f_hat_filtered", "stiffness")
    np.testing.assert_array_equal(back["f_hat"], obs.f_hat)
    with np.load(tmp_path / "o.npz") as z:
        np.testing.assert_array_equal(z["v_hat"], obs.v_hat)
        np.testing.assert_array_equal(z["u"], tr.force)
    assert obs.summary()["rms_f_hat"] == pytest.approx(np.sqrt(np.mean(back["f_hat"] ** 2)), rel=1e-12)
    assert "<script>" not in Observation_html(tr)


def Observation_html(tr):
    evil = Trace(t=tr.t, position=tr.position, force=tr.force, sample_time=tr.sample_time, source="<script>x</script>")
    html = observe(od.load_preset("table1"), evil)._repr_html_()
    assert "&lt;script&gt;" in html
    return html


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"cfg": "vcm"}, TypeError, "cfg: expected a Config"),
    ({"trace": np.zeros(3)}, TypeError, "trace: expected a Trace"),
    ({"stiffness": "guess"}, ValueError, "stiffness: expected one of estimated, true, constant"),
    ({"cfg": od.load_preset("table1").override(dt=1e-3)}, ValueError, "the trace's sample time wins"),
])
def test_observe_refuses(kwargs, exc, match):
    t = np.arange(200) * 1e-4
    args = {"cfg": od.load_preset("table1"), "trace": Trace(t=t, position=t, force=t, sample_time=1e-4)}
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        observe(args.pop("cfg"), args.pop("trace"), **args)


# -- EMPS ----------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def emps():
    trace = load_trace(EMPS, position="qm", input="vir", time="t", input_gain=EMPS_GAIN)
    ident = identify(trace)
    return trace, ident, ident.to_config(name="emps")


@needs_emps
def test_emps_friction_estimate_against_the_identified_model(emps):
    trace, ident, cfg = emps
    obs = observe(cfg, trace)
    w3 = model_friction_state(ident, trace, cfg)
    v = zero_phase_velocity(trace.position, trace.sample_time)
    np.testing.assert_allclose(w3, ident.Cf * np.sign(v), atol=1e-9)  # G = offset: w3 is Cf sign(v)
    err = float(np.sqrt(np.mean((obs.f_hat - w3) ** 2)))
    # The estimate is u - G - m dv/dt - sigma v seen through the observer's unity-gain dynamics,
    # so it differs from Cf sign(v) by the inverse model's own residual (independent: numpy/scipy
    # below) plus the start-up transient and the reversals, where sign(v) jumps: bound 1.25x.
    a = np.gradient(v, trace.sample_time)
    residual = trace.force - (ident.m * a + ident.sigma * v + ident.Cf * np.sign(v) + ident.offset)
    res_rms = float(np.sqrt(np.mean(residual[50:-50] ** 2)))
    assert 0.8 * res_rms < err < 1.25 * res_rms, (err, res_rms)
    assert err < 0.15 * ident.Cf
    # velocity: within 1 % RMS of the zero-phase derivative
    assert np.sqrt(np.mean((obs.v_hat - v) ** 2)) < 0.01 * np.sqrt(np.mean(v**2))
    # the constant schedule integrates kappa v in gross sliding: far off (why 'estimated' is the default)
    const = observe(cfg, trace, stiffness="constant")
    assert np.sqrt(np.mean((const.f_hat - w3) ** 2)) > 10 * err


# -- command line --------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def record(tmp_path_factory):
    """A synthetic record in volts (gain 4 N/V) with m 2 kg, sigma 30 N s/m, Cf 1.5 N, offset -0.4 N."""
    d = tmp_path_factory.mktemp("record")
    dt = 1e-3
    t = np.arange(20_000) * dt
    x = 0.05 * np.sin(2 * np.pi * 0.5 * t) + 0.01 * np.sin(2 * np.pi * 2.3 * t)
    v = np.gradient(x, dt)
    u_volt = (2.0 * np.gradient(v, dt) + 30.0 * v + 1.5 * np.sign(v) - 0.4) / 4.0
    np.savetxt(d / "axis.csv", np.column_stack([t, x, u_volt]), delimiter=",", header="t,x,u_volt", comments="")
    return d / "axis.csv"


FLAGS = ["--position", "x", "--input", "u_volt", "--time", "t", "--input-gain", "4"]


def _json(capsys):
    return json.loads(capsys.readouterr().out)


def test_cli_identify_json_and_config_accepted_by_check_simulate_observe_report(record, tmp_path, capsys):
    toml = tmp_path / "axis.toml"
    assert main(["identify", str(record), *FLAGS, "--json", "-o", str(toml)]) == 0
    out = _json(capsys)
    assert {"m", "sigma", "Cf", "offset", "m_std", "sigma_std", "Cf_std", "offset_std", "nrmse_percent",
            "condition_number", "samples"} <= set(out)
    assert [round(out[k], 2) for k in ("m", "sigma", "Cf", "offset")] == [2.0, 30.0, 1.5, -0.4]
    cfg = od.load_config(toml)
    assert cfg.plant.G == pytest.approx(-0.4, abs=1e-3) and cfg.observer.dt == pytest.approx(1e-3)
    assert main(["check", "--config", str(toml), "--json"]) == 0
    assert _json(capsys)["stable"] is True
    assert main(["simulate", "positioning", "--config", str(toml), "--duration", "4", "--json"]) == 0
    assert _json(capsys)["diverged"] is False
    assert main(["observe", str(record), "--config", str(toml), *FLAGS, "--json", "--out", str(tmp_path / "o.npz"),
                 "--plot", str(tmp_path / "o.svg")]) == 0
    summary = _json(capsys)
    assert set(summary) == {"samples", "sample_time", "duration", "reversals", "rms_v_hat", "rms_f_hat",
                            "rms_f_hat_filtered"}
    with np.load(tmp_path / "o.npz") as z:
        assert summary["rms_f_hat"] == pytest.approx(np.sqrt(np.mean(z["f_hat"] ** 2)), rel=1e-12)
        # the record is the exact inverse model: after the start-up, f_hat is Cf sign(v) = +-1.5 N
        v = np.gradient(z["x_meas"], 1e-3)
        moving = (np.abs(v) > 0.05 * np.max(np.abs(v)))
        moving[:2000] = False
        assert np.median(np.abs(z["f_hat"][moving] - 1.5 * np.sign(v[moving]))) < 0.05
    svg = (tmp_path / "o.svg").read_text()
    assert "friction [N]" in svg and "time [s]" in svg
    t = np.arange(20_000) * 1e-3  # analytic velocity; the rule ignores |v| <= 1 % of the peak
    v = 0.05 * np.pi * np.cos(np.pi * t) + 0.01 * 2 * np.pi * 2.3 * np.cos(2 * np.pi * 2.3 * t)
    signs = np.sign(v[np.abs(v) > 0.01 * np.max(np.abs(v))])
    assert summary["samples"] == 20_000 and summary["reversals"] == np.count_nonzero(signs[1:] != signs[:-1])


def test_cli_identify_asymmetric_keys(record, capsys):
    assert main(["identify", str(record), *FLAGS, "--asymmetric", "--json"]) == 0
    out = _json(capsys)
    assert {"sigma_pos", "sigma_neg", "Cf_pos", "Cf_neg"} <= set(out)
    assert out["sigma_pos"] == pytest.approx(30.0, rel=1e-3) and out["Cf_neg"] == pytest.approx(1.5, rel=1e-2)


@pytest.mark.slow
def test_cli_report_with_data_escapes_names(record, tmp_path, capsys):
    evil = tmp_path / "<b>axis&.csv"
    evil.write_bytes(record.read_bytes().replace(b"u_volt", b"u<i>v</i>", 1))
    toml = tmp_path / "axis.toml"
    assert main(["identify", str(record), *FLAGS, "-o", str(toml)]) == 0
    out = tmp_path / "r.html"
    flags = ["--position", "x", "--input", "u<i>v</i>", "--time", "t", "--input-gain", "4"]
    assert main(["report", "--config", str(toml), "--data", str(evil), *flags, "-o", str(out), "--quiet"]) == 0
    html = out.read_text()
    assert "Validation on measured data" in html
    assert "&lt;b&gt;axis&amp;.csv" in html and "u&lt;i&gt;v&lt;/i&gt;" in html
    assert "<b>axis&" not in html and "u<i>v" not in html


def _bad_cases(record, tmp_path):
    r = str(record)
    cfg = ["--preset", "table1"]
    toml = tmp_path / "ok.toml"
    od.load_preset("table1").override(dt=1e-3).save(toml)
    good = ["--config", str(toml)]
    return [
        (["observe", str(tmp_path / "none.csv"), *good, *FLAGS], "path"),
        (["observe", str(tmp_path / "x.txt"), *good, *FLAGS], "expected a log file (.csv, .mat, .tdms"),
        (["observe", r, *good, "--position", "x", "--input", "u", "--time", "t"], "available: t, u_volt, x"),
        (["observe", r, *good, "--position", "x", "--input", "u_volt"], "--time NAME or --sample-time"),
        (["observe", r, *good, *FLAGS[:-1], "0"], "input_gain: expected a finite nonzero number, found 0.0"),
        (["observe", r, *good, *FLAGS[:-1], "nan"], "--input-gain: expected a finite number"),
        (["observe", r, *cfg, *FLAGS], "the trace's sample time wins"),
        (["observe", r, *good, *FLAGS, "--out", str(tmp_path / "o.txt")], ".csv or .npz"),
        (["observe", r, *good, *FLAGS, "--out", str(tmp_path / "no" / "o.csv")], "does not exist"),
        (["observe", r, *good, *FLAGS, "--out", str(tmp_path / "dir.csv")], "found the folder"),
        (["observe", r, *good, *FLAGS, "--plot", str(tmp_path / "o.pdf")], ".svg or .png"),
        (["observe", r, *FLAGS], "one of the arguments --preset --config is required"),
        (["identify", r, *FLAGS, "-o", str(tmp_path / "c.json")], ".toml"),
        (["identify", r, *FLAGS, "--sample-time", "0.002"], "agree"),
        (["report", "--data", r, "-o", str(tmp_path / "r.html")], "--position NAME and --input NAME"),
        (["report", "--position", "x", "-o", str(tmp_path / "r.html")], "need --data FILE"),
    ]


def test_cli_bad_input_one_line_exit_2_nothing_written(record, tmp_path, capsys):
    (tmp_path / "dir.csv").mkdir()
    for argv, match in _bad_cases(record, tmp_path):
        before = sorted(p.name for p in tmp_path.iterdir())
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Traceback" not in err, err
        assert match in err, (argv, err)
        assert sorted(p.name for p in tmp_path.iterdir()) == before, argv


def test_cli_subprocess_sample_time_mismatch(record, tmp_path):
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    proc = subprocess.run([sys.executable, "-m", "obsdesign", "observe", str(record), "--preset", "vcm", *FLAGS,
                           "--out", str(tmp_path / "o.csv")], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "trace's sample time wins" in proc.stderr
    assert "set dt = 0.001" in proc.stderr
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.slow
@needs_emps
def test_analysis_emps_script(tmp_path):
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root))
    proc = subprocess.run([sys.executable, str(root / "analysis" / "emps.py"), str(EMPS), "--out", str(tmp_path)],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "every stability condition holds" in proc.stdout
    for name in ("emps.toml", "emps_fit.png", "emps_observer.png", "emps_observer.csv"):
        assert (tmp_path / name).is_file(), name
    assert od.load_config(tmp_path / "emps.toml").plant.K == EMPS_GAIN
