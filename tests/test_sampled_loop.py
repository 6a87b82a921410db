"""The sampled loop that runs: config field ``hardware.delay_samples``, the discrete PID ``C(z)`` against the
kernel's recursion, margins against an independent python-control computation, the simulator's step."""

from __future__ import annotations

import pytest

import obsdesign as od
from obsdesign.hardware import HardwareSpec


# --------------------------------------------------------------------------------------------
# hardware.delay_samples: the config field (the drive's delay)
def test_delay_samples_defaults_to_zero_and_round_trips():
    cfg = od.load_preset("vcm")
    assert cfg.hardware.delay_samples == 0
    for d in (0, 1, 3):
        c = cfg.override(delay_samples=d)
        back = od.Config.from_toml(c.to_toml())
        assert back == c and back.hardware.delay_samples == d and type(back.hardware.delay_samples) is int
    assert "[hardware]\ndelay_samples = 0  # [samples] the drive's delay" in cfg.to_toml()


@pytest.mark.parametrize("bad", [-1, 1.5, 2.0, "1", True, None])
def test_delay_samples_rejects_what_is_not_a_nonnegative_integer(bad):
    cfg = od.load_preset("vcm")
    with pytest.raises(ValueError, match=r"^hardware\.delay_samples: expected an integer >= 0 and <= 10000, found "):
        HardwareSpec(delay_samples=bad)
    text = cfg.to_toml().replace("delay_samples = 0", f"delay_samples = {bad!r}".replace("'", '"')
                                 .replace("True", "true").replace("None", '"none"'))
    with pytest.raises(ValueError, match=r"hardware\.delay_samples: expected an integer >= 0 and <= 10000, found "):
        od.Config.from_toml(text)


def test_config_command_prints_delay_samples_with_its_comment():
    from obsdesign.cli._config import config_toml

    text = config_toml(od.load_preset("vcm").override(delay_samples=2))
    line = next(x for x in text.splitlines() if x.startswith("delay_samples"))
    assert line.startswith("delay_samples = 2  # [samples] the drive's delay")
    assert od.Config.from_toml(text).hardware.delay_samples == 2


# --------------------------------------------------------------------------------------------
# The sampled loop: C(z) against the kernel, H_zoh against its closed form
import contextlib  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import warnings  # noqa: E402

import _loop_axes as loop_axes  # noqa: E402
import numpy as np  # noqa: E402

from obsdesign.cli import main  # noqa: E402
from obsdesign.design.loop import loop_analysis  # noqa: E402
from obsdesign.design.sampled_loop import SampledLoop, discrete_pid, sampled_loop, zoh_plant  # noqa: E402


def run(*args):
    """In-process CLI run: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in args])
    return code, out.getvalue(), err.getvalue()


def config_2khz():
    """The new-user trial's identified axis (4i/4k): 2 kHz, tau = m/sigma, crossover at a tenth of Nyquist, with
    the paper's PID (the loop the reviewers analysed; ``auto`` would carry the sampled design here, whose tests
    are in tests/test_pid_design.py)."""
    return loop_axes.config_2khz(design="paper")


@pytest.mark.parametrize("make", [lambda: od.load_preset("vcm"), config_2khz], ids=["vcm", "2kHz"])
def test_discrete_pid_is_the_kernels_recursion(make):
    """The real numba kernel (controller_sample, controller 'pid') on a random error sequence against
    python-control's forced response of C(z): the command of every sample."""
    import control as ct

    from obsdesign.sampled import sampled_controller
    from obsdesign.sampled.kernel import CONTROLLER_STATE, OBSERVER_STATE, controller_sample

    cfg = make().override(G=0.0, u_max=1e12)
    sc = sampled_controller(cfg, controller="pid")
    obs, est, ctrl = sc.kernel_args()
    rng = np.random.default_rng(18)
    e = rng.standard_normal(400) * 1e-4
    e[0] = 0.0  # the kernel takes e_prev = e at n = 0; zero initial state needs e[0] = e[-1] = 0
    e[150:] = 1e-4  # and a step
    cst, ost, ez = CONTROLLER_STATE, OBSERVER_STATE, np.zeros(1)
    u = np.empty(e.size)
    for n in range(e.size):  # x_ref = 0, x_meas = -e
        cst, ost, u[n], *_ = controller_sample(cst, ost, ez, np.zeros(1), n, 0.0, 0.0, 1.0, 0.0, -e[n], 0.0, obs, est, ctrl)
    dt = cfg.observer.dt
    C = discrete_pid(kp=sc.kp, ki=sc.ki, kd=sc.kd, tau_d=sc.tau_d, dt=dt)
    y = ct.forced_response(C, np.arange(e.size) * dt, e).outputs.ravel()
    np.testing.assert_allclose(u, y, rtol=1e-9, atol=1e-12 * np.abs(u).max())
    # the impulse response in closed form, g = kd (1-a)/dt: kp + ki dt + g at n = 0, then ki dt + g (a-1) a^(n-1)
    a = sc.alpha_d
    imp = ct.impulse_response(C, np.arange(4) * dt).outputs.ravel() * dt  # python-control scales by 1/dt
    g = sc.kd * (1 - a) / dt
    np.testing.assert_allclose(imp, [sc.kp + sc.ki * dt + g, sc.ki * dt + g * (a - 1), sc.ki * dt + g * (a - 1) * a,
                                     sc.ki * dt + g * (a - 1) * a**2], rtol=1e-9)
    sl = sampled_loop(cfg)
    assert (sl.kp, sl.ki, sl.kd) == (sc.kp, sc.ki, sc.kd) and sl.tau_d == pytest.approx(sc.tau_d, rel=1e-15)


def test_zoh_plant_against_its_closed_form():
    phi, tau, dt = 0.0407, 0.006675, 1e-4
    H = zoh_plant(phi=phi, tau=tau, dt=dt)
    p = math.exp(-dt / tau)
    b1, b0 = dt - tau * (1 - p), tau * (1 - p) - p * dt
    for z in (0.3 + 0.4j, -1.0, np.exp(1j * 0.7)):
        expected = phi * (b1 * z + b0) / ((z - 1) * (z - p))
        assert complex(H(z)) == pytest.approx(expected, rel=1e-9)


# --------------------------------------------------------------------------------------------
# Contract: loop --json against an independent python-control computation of the same sampled loop
def _independent(cfg, gains, d):
    """The loop built here from the ``pid --json`` gains: c2d ZOH of the plant, the PID as the parallel
    sum of its three discrete parts, z^-d as d unit delays; margins by python-control and by root finding
    on the unit circle; peaks on a dense grid that ends at the Nyquist frequency."""
    import control as ct
    import scipy.optimize

    dt, N = cfg.observer.dt, cfg.pid.derivative_N
    kp, ki, kd = gains["kp"], gains["ki"], gains["kd"]
    a = math.exp(-dt * kp * N / kd)
    z = ct.tf([1.0, 0.0], [1.0], dt)
    C = ct.parallel(ct.tf([kp], [1], dt), ki * dt * z / (z - 1), kd * (1 - a) / dt * (z - 1) / (z - a))
    H = ct.c2d(ct.ss(ct.tf([cfg.phi], [cfg.pid.tau, 1.0, 0.0])), dt, "zoh")
    delay = ct.tf([1], [1], dt)
    for _ in range(d):
        delay = delay * ct.tf([1], [1, 0], dt)
    L = ct.series(C, delay, H)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gm, pm, _, wpc, wgc, _ = ct.stability_margins(L)

    def Lw(w):
        zz = np.exp(1j * np.asarray(w) * dt)
        return np.asarray(L(zz)).ravel() if np.ndim(w) else complex(L(zz))

    w_nyq = math.pi / dt
    wg = scipy.optimize.brentq(lambda w: abs(Lw(w)) - 1.0, wgc / 3, min(3 * wgc, w_nyq), xtol=1e-12)
    pm_root = 180.0 + math.degrees(np.angle(Lw(wg)))
    grid = np.linspace(wg * 1.01, w_nyq * (1 - 1e-9), 20001)  # the first -180 deg crossing above wg
    im = Lw(grid).imag
    i = int(np.nonzero((np.sign(im[:-1]) != np.sign(im[1:])) & (Lw(grid[:-1]).real < 0))[0][0])
    wp = scipy.optimize.brentq(lambda w: Lw(w).imag, grid[i], grid[i + 1], xtol=1e-12)
    gm_root = 1.0 / abs(Lw(wp))
    w = np.concatenate([np.logspace(math.log10(wg) - 3, math.log10(w_nyq), 100_000), [w_nyq]])
    Lg = Lw(w)
    Cg = np.asarray(C(np.exp(1j * w * dt))).ravel()
    char = np.polyadd(*[np.squeeze(x) for x in ct.tfdata(ct.tf(L))][::-1])  # den + num
    return {"gm": gm, "pm": pm, "wgc": wgc, "wpc": wpc, "pm_root": pm_root, "gm_root": gm_root, "wg": wg,
            "dm": math.radians(pm_root) / wg, "max_S": np.abs(1 / (1 + Lg)).max(),
            "max_T": np.abs(Lg / (1 + Lg)).max(), "max_CS": np.abs(Cg / (1 + Lg)).max(),
            "rmax": np.abs(np.roots(char)).max()}


@pytest.fixture(scope="module")
def cfg_files(tmp_path_factory):
    root = tmp_path_factory.mktemp("sampled")
    path = root / "axis_2khz.toml"
    config_2khz().save(path)
    return {"vcm": ("--preset", "vcm"), "2kHz": ("--config", path)}


@pytest.mark.slow
@pytest.mark.parametrize("name", ["vcm", "2kHz"])
@pytest.mark.parametrize("d", [0, 1])
def test_loop_json_agrees_with_an_independent_sampled_loop(cfg_files, name, d):
    flags = cfg_files[name]
    code, out, _ = run("pid", *flags, "--delay", d, "--json")  # the PID the config carries for this delay
    gains = json.loads(out)
    code, out, err = run("loop", *flags, "--delay", d, "--json")
    assert code == 0 and err == ""
    doc = json.loads(out)
    s = doc["sampled"]
    cfg = od.load_preset("vcm") if name == "vcm" else config_2khz()
    ref = _independent(cfg, gains, d)
    assert s["delay_samples"] == d and f"delay {d} samples" in s["system"] and "ZOH plant" in s["system"]
    # the contract: 0.1 deg and 1 %
    for pm in (ref["pm"], ref["pm_root"]):
        assert s["phase_margin_deg"] == pytest.approx(pm, abs=0.1)
    for gm in (ref["gm"], ref["gm_root"]):
        assert s["gain_margin"] == pytest.approx(gm, rel=0.01)
    assert s["crossover_rad_s"] == pytest.approx(ref["wg"], rel=0.01)
    assert s["delay_margin_s"] == pytest.approx(ref["dm"], rel=0.01)
    assert s["delay_margin_samples"] == pytest.approx(ref["dm"] / cfg.observer.dt, rel=0.01)
    for key in ("max_S", "max_T", "max_CS"):
        assert s[key] == pytest.approx(ref[key], rel=0.01)
        assert s[key] >= ref[key] * (1 - 1e-9)  # a refined peak is never below the grid's
    assert s["max_pole_magnitude"] == pytest.approx(ref["rmax"], rel=1e-6) and s["stable"]
    # in fact much closer than the contract
    assert s["phase_margin_deg"] == pytest.approx(ref["pm_root"], abs=1e-5)
    assert s["gain_margin"] == pytest.approx(ref["gm_root"], rel=1e-5)
    # the continuous keys are unchanged, and labelled
    assert doc["phase_margin_deg"] == pytest.approx(60.0, abs=1e-9) and doc["gain_margin_db"] is None
    assert doc["system"].startswith("continuous idealisation")


def test_the_reviewers_numbers_come_from_a_tustin_pid():
    """New-user trial 4k: 44.0 deg / 6.04 and 25.1 deg / 2.22 with a Tustin PID; the kernel's PID (backward
    rectangle integral with the current sample, exact-pole derivative filter) has less phase at crossover."""
    import control as ct

    cfg = config_2khz()
    sl0, sl1 = sampled_loop(cfg), sampled_loop(cfg, delay_samples=1)
    s = ct.tf("s")
    Ct = ct.c2d(sl0.kp + sl0.ki / s + sl0.kd * s / (sl0.tau_d * s + 1), cfg.observer.dt, "tustin")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for d, (pm, gm) in ((0, (44.0, 6.04)), (1, (25.1, 2.22))):
            L = Ct * sl0.H * ct.tf([1], [1] + [0] * d, cfg.observer.dt)
            g, p, *_ = ct.stability_margins(L)
            assert p == pytest.approx(pm, abs=0.05) and g == pytest.approx(gm, abs=0.005)
    assert sl0.phase_margin_deg == pytest.approx(41.84, abs=0.01) and sl0.gain_margin == pytest.approx(5.739, abs=1e-3)
    assert sl1.phase_margin_deg == pytest.approx(22.76, abs=0.01) and sl1.gain_margin == pytest.approx(2.060, abs=1e-3)
    # one sample of delay removes omega_c dt rad of phase at the same crossover
    assert sl1.crossover_rad_s == pytest.approx(sl0.crossover_rad_s, rel=1e-9)
    assert sl0.phase_margin_deg - sl1.phase_margin_deg == pytest.approx(
        math.degrees(sl0.crossover_rad_s * cfg.observer.dt), abs=1e-6)
    assert sl0.delay_margin_samples - sl1.delay_margin_samples == pytest.approx(1.0, abs=1e-6)


# --------------------------------------------------------------------------------------------
# The linear sampled loop's step against the simulator's positioning step while the plant is linear
@pytest.mark.parametrize("delay", [0, 1, 2])
def test_simulated_step_is_the_sampled_loops_step_response(delay):
    """vcm with friction effectively off, no saturation, no quantization, the PID's plant equal to the
    simulated one (tau = m / sigma): x at the samples against step_response(T) of the sampled loop, and
    the step metrics against step_info, with the simulator's computation delay of 0, 1 and 2 samples."""
    import control as ct

    base = od.load_preset("vcm")
    m, sigma = base.plant.m, base.friction.sigma
    cfg = base.override(Cf=1e-12, tau=m / sigma, u_max=1e3, quantization=0.0, G=0.0, delay_samples=delay)
    size = 1e-3
    res = od.simulate(cfg, od.sim.Positioning(step_size=size, step_up=0.5, step_down=1.5), controller="pid",
                      duration=2.0)
    n0, n1 = int(np.argmax(res.x_ref > 0)), int(np.argmax(res.x_ref[5001:] == 0)) + 5001
    assert res.t[n0] == pytest.approx(0.5, abs=1e-9) and res.t[n1] == pytest.approx(1.5, abs=1e-9)
    sl = sampled_loop(cfg)
    dt = cfg.observer.dt
    y = size * ct.step_response(sl.T, np.arange(n1 - n0) * dt).outputs.ravel()
    x = res.x[n0:n1]
    assert np.max(np.abs(x - y)) <= 1e-6 * size
    assert np.max(np.abs(x - y)) > 0  # two computations, not one
    # the step down mirrors it
    y_down = size - size * ct.step_response(sl.T, np.arange(res.t.size - n1) * dt).outputs.ravel()
    assert np.max(np.abs(res.x[n1:] - y_down)) <= 1e-6 * size
    # the linear loop's step metrics are the simulator's (its settling band is 2e-6 m, here 2 % of 1 mm is 2e-5)
    info = ct.step_info(sl.T, T=np.arange(20000) * dt, SettlingTimeThreshold=0.02)
    assert sl.overshoot_pct == pytest.approx(info["Overshoot"], rel=1e-9)
    assert res.metrics["overshoot"][0] == pytest.approx(sl.overshoot_pct / 100, rel=1e-4)
    assert res.metrics["rise_time"][0] == pytest.approx(sl.rise_time_s, abs=dt)


# --------------------------------------------------------------------------------------------
# Surface: labels, the --delay flag, errors, the figure
def test_loop_text_labels_both_systems_and_delay_comes_from_the_config(tmp_path):
    code, out, err = run("loop")
    assert code == 0 and err == ""
    assert "Continuous idealisation" in out and "no sampling" in out
    assert "sampled loop: ZOH plant, discrete PID with derivative filter N=10, delay 0 samples" in out
    assert "max |CS| noise to command [V/m]" in out and "delay margin" in out
    path = tmp_path / "d2.toml"
    od.load_preset("vcm").override(delay_samples=2).save(path)
    doc = json.loads(run("loop", "--config", path, "--json")[1])
    assert doc["sampled"]["delay_samples"] == 2
    assert json.loads(run("loop", "--config", path, "--delay", 0, "--json")[1])["sampled"]["delay_samples"] == 0


@pytest.mark.parametrize("value", ["-1", "1.5", "x", ""])
def test_bad_delay_is_one_line_exit_2(value):
    code, out, err = run("loop", "--delay", value)
    assert code == 2 and out == ""
    assert err.strip().count("\n") == 0
    assert err.startswith(f"obsdesign loop: argument --delay: expected an integer >= 0 and <= 10000, found {value!r}")


@pytest.mark.parametrize("bad", [-1, 0.5, "1"])
def test_api_errors_name_the_parameter(bad):
    with pytest.raises(ValueError, match=r"delay_samples: expected an integer >= 0 and <= 10000, found "):
        sampled_loop(od.load_preset("vcm"), delay_samples=bad)
    with pytest.raises(ValueError, match=r"delay_samples: expected an integer >= 0 and <= 10000, found "):
        loop_analysis(od.load_preset("vcm"), delay_samples=bad)
    with pytest.raises(TypeError, match="cfg: expected a Config"):
        sampled_loop("vcm")


def test_more_delay_less_margin_and_an_unstable_loop_says_so():
    cfg = config_2khz()
    loops = [sampled_loop(cfg, delay_samples=d) for d in range(4)]
    pms = [x.phase_margin_deg for x in loops]
    assert all(a > b for a, b in zip(pms, pms[1:]))
    # the delay margin of 2.19 samples (delay 0): two more samples keep it stable, three do not
    assert 2 < loops[0].delay_margin_samples < 3
    assert loops[2].stable and not loops[3].stable
    assert loops[3].overshoot_pct is None and "UNSTABLE" in str(loops[3])
    json.dumps(loops[3].to_dict(), allow_nan=False)
    assert isinstance(loops[0], SampledLoop)


def test_figure_shows_the_sampled_loop_beside_the_continuous_one():
    import matplotlib

    matplotlib.use("Agg")
    from obsdesign.design.loop import loop_figure

    fig = loop_figure(loop_analysis(config_2khz(), delay_samples=1))
    labels = [t.get_text() for ax in fig.axes for t in ax.get_legend().get_texts()]
    assert any("continuous idealisation" in x for x in labels)
    assert any("sampled (ZOH, discrete PID N=10, delay 1)" in x and "PM 22.8 deg" in x for x in labels)
    assert any(x.startswith("L(exp(jw dt)) sampled") for x in labels)
    assert any("poles at s = ln(z)/dt" in x for x in labels)


@pytest.mark.parametrize("factor", [40.0, 45.0, 50.0])
def test_a_crossover_python_control_misses_is_found_on_the_loop_itself(factor):
    # vcm at 1 kHz with one sample of delay and kp (and its derivative filter) raised: python-control's
    # stability_margins reported no gain crossover here (an 'infinite' phase margin, also for the unstable
    # loops); the margin must be that of L itself, and its sign must agree with the closed-loop poles
    import control as ct

    from obsdesign.design import sampled_loop as sl
    from obsdesign.design.pid import pid_gains

    cfg = od.load_preset("vcm").override(dt=1e-3, delay_samples=1)
    _, _, kp, ki, kd = pid_gains(phi=cfg.phi, tau=cfg.pid.tau, max_S=cfg.pid.max_S,
                                 phase_margin_deg=cfg.pid.phase_margin_deg)
    args = (kp * factor, ki, kd, kd / (kp * factor) / 10.0, 1e-3, cfg.phi, cfg.pid.tau, 1)
    gm, pm, wgc, wpc, dm, *_ = numbers = sl._numbers(*args)
    rmax = numbers[13]
    assert math.isfinite(pm) and 0.0 < wgc < math.pi / 1e-3
    L = sl._systems(*args)["L"]
    resp = ct.frequency_response(L, [wgc])  # python-control's own evaluation of L at the crossover found
    mag, phase = float(np.squeeze(resp.magnitude)), float(np.squeeze(resp.phase))
    assert abs(mag - 1.0) < 1e-9
    assert abs(((180.0 + math.degrees(phase) + 180.0) % 360.0 - 180.0) - pm) < 1e-6
    assert (pm < 0.0) == (rmax > 1.0) == (gm < 1.0)
    assert sl._verify(args, numbers) is None
