"""``simulate()``: run a scenario in closed loop and summarise it.

Examples
--------
>>> import obsdesign as od
>>> res = od.simulate(od.load_preset("vcm"), "positioning", controller="pid+observer", duration=4.0)
>>> res.metrics["diverged"], len(res.metrics["settling_time"])
(False, 2)
>>> sorted(res.columns())[:3]
['e', 'f', 'f_hat']
"""

from __future__ import annotations

import dataclasses
import functools
import io
import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from .._io import atomic_write
from ..design.observer import design_observer
from ..design.pid import pid_gains
from ..params import Config, _Range
from ..symbolic import derive
from . import kernel
from .discretize import step_matrices
from .scenarios import CHIRP_BAND_LABELS, band_limited_noise, build_scenario, chirp_frequency

__all__ = ["SimResult", "simulate", "COLUMNS", "PLANTS"]

#: Trace columns of CSV/NPZ exports, in order (SI units).
COLUMNS = ("t", "x", "x_meas", "v", "f", "v_hat", "f_hat", "f_hat_filtered", "u", "x_ref", "e")
PLANTS = ("physical", "model")

_POS = _Range(low=0.0)
_NONNEG = _Range(low=0.0, low_inclusive=True)
_FINITE = _Range()


@dataclass(frozen=True, eq=False)
class SimResult:
    """A simulated run: traces (SI units) and summary metrics.

    Attributes
    ----------
    t, x, x_meas, v, f, v_hat, f_hat, f_hat_filtered, u, x_ref, e : ndarray or None
        Per sample ``k``: the plant at ``t[k]``, the measurement, the estimates after
        processing it and the force ``u`` computed at ``k``; ``f`` is the plant's value of
        the estimated friction state; ``e = x_ref - x``. ``None`` when the trace was not kept.
    stiffness : ndarray or None
        Stiffness the observer used for the interval after each sample [N/m].
    metrics : dict
        ``rms_error``, ``max_error``, ``settling_time``, ``steady_state_error``,
        ``observer_rms_error_v``, ``observer_rms_error_f``, ``diverged``, ``sim_wall_s``
        and more (see ``docs/simulation.md``).
    scenario, controller, plant, stiffness_schedule : str
    config : Config
        The config after the overrides.
    """

    scenario: str
    controller: str
    plant: str
    stiffness_schedule: str
    config: Config
    metrics: dict
    t: np.ndarray | None = field(default=None, repr=False)
    x: np.ndarray | None = field(default=None, repr=False)
    x_meas: np.ndarray | None = field(default=None, repr=False)
    v: np.ndarray | None = field(default=None, repr=False)
    f: np.ndarray | None = field(default=None, repr=False)
    v_hat: np.ndarray | None = field(default=None, repr=False)
    f_hat: np.ndarray | None = field(default=None, repr=False)
    f_hat_filtered: np.ndarray | None = field(default=None, repr=False)
    u: np.ndarray | None = field(default=None, repr=False)
    x_ref: np.ndarray | None = field(default=None, repr=False)
    e: np.ndarray | None = field(default=None, repr=False)
    stiffness: np.ndarray | None = field(default=None, repr=False)

    def columns(self) -> dict[str, np.ndarray]:
        """The trace columns of :data:`COLUMNS` as a dict."""
        if self.t is None:
            raise ValueError("trace: this result holds metrics only (simulate(..., keep_trace=False))")
        return {name: getattr(self, name) for name in COLUMNS}

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write the trace as CSV (header: :data:`COLUMNS`), atomically."""
        data = np.column_stack(list(self.columns().values()))
        buf = io.StringIO()
        np.savetxt(buf, data, delimiter=",", header=",".join(COLUMNS), comments="", fmt="%.17g")
        atomic_write(path, buf.getvalue().encode())

    def to_npz(self, path: str | os.PathLike) -> None:
        """Write the trace as a NumPy ``.npz`` archive, atomically."""
        buf = io.BytesIO()
        np.savez(buf, **self.columns())
        atomic_write(path, buf.getvalue())

    def _metric_rows(self) -> list[tuple[str, str]]:
        from ..design.results import fmt

        rows = []
        for key, value in self.metrics.items():
            if isinstance(value, list):
                value = "[" + ", ".join(fmt(v) for v in value) + "]"
            elif isinstance(value, dict):
                value = ", ".join(f"{k}: {fmt(v)}" for k, v in value.items())
            rows.append((key, fmt(value)))
        return rows

    def _repr_latex_(self) -> str:
        from ..design.results import _tex

        body = " \\\\\n".join(f"{_tex(k)} & {_tex(v)}" for k, v in self._metric_rows())
        return (f"\\begin{{tabular}}{{ll}}\n\\multicolumn{{2}}{{l}}{{simulation: {_tex(self.scenario)}, "
                f"{_tex(self.controller)}}} \\\\ \\hline\n{body}\n\\end{{tabular}}")

    def _repr_html_(self) -> str:
        import html

        rows = "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>" for k, v in self._metric_rows())
        return (f"<table class='obsdesign-result'><caption>simulation: {html.escape(self.scenario)}, "
                f"{html.escape(self.controller)}</caption>{rows}</table>")

    def __str__(self) -> str:
        lines = [f"Simulation: {self.scenario} ({self.controller}, plant {self.plant}, "
                 f"stiffness {self.stiffness_schedule}, variant {self.config.observer.variant})"]
        lines += [f"  {key}: {value}" for key, value in self._metric_rows()]
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class LoopInputs:
    """Every input of :func:`obsdesign.sim.kernel.run_loop`, in its argument order."""

    dt: float
    n_sub: int
    mode: int
    lag_model: bool
    m: float
    K: float
    G: float
    Cf: float
    s: float
    sigma: float
    beta: float
    kappa: float
    A0: np.ndarray
    A1: np.ndarray
    b0: np.ndarray
    b1: np.ndarray
    g0: np.ndarray
    g1: np.ndarray
    L1: float
    L2: float
    schedule: int
    v_hat0: float
    f_hat0: float
    controller: int
    kp: float
    ki: float
    kd: float
    tau_d: float
    u_max: float
    lp_phi: np.ndarray
    lp_g0: np.ndarray
    lp_g1: np.ndarray
    x_ref: np.ndarray
    u_open: np.ndarray
    noise: np.ndarray
    quantization: float

    def args(self) -> tuple:
        """The positional arguments of ``run_loop`` before its output arrays."""
        return tuple(getattr(self, f.name) for f in dataclasses.fields(self))


@functools.lru_cache(maxsize=None)
def _check_affine(variant: str) -> None:
    d = derive(variant)
    k = d.symbols["k"]
    for name in ("observer_matrix", "observer_input", "observer_output_gain"):
        if getattr(d, name).diff(k, 2) != sp.zeros(*getattr(d, name).shape):
            raise NotImplementedError(f"{name} of variant {variant!r} is not affine in the stiffness")


@dataclass(frozen=True, eq=False)
class ObserverArrays:
    """A designed observer in the affine-in-stiffness form the kernel uses.

    ``A(k) = A0 + k A1`` is the observer matrix of the symbolic derivation; likewise the
    input vector ``b`` and the measurement gain ``g``.
    """

    design: Any
    A0: np.ndarray
    A1: np.ndarray
    b0: np.ndarray
    b1: np.ndarray
    g0: np.ndarray
    g1: np.ndarray


def observer_arrays(cfg: Config) -> ObserverArrays:
    """The config's observer as :class:`ObserverArrays` (affinity in k is checked symbolically)."""
    d = design_observer(cfg)
    _check_affine(d.variant)
    at0, at1 = d.matrices(0.0), d.matrices(1.0)
    A0, b0, g0 = at0
    A1, b1, g1 = (np.asarray(x1) - np.asarray(x0) for x0, x1 in zip(at0, at1))
    return ObserverArrays(d, np.ascontiguousarray(A0), np.ascontiguousarray(A1), b0, b1, g0, g1)


def _lowpass_arrays(omega_co: float, dt: float):
    """FOH recursion of the low-pass eq:3:4:5 with state (f_filtered, its derivative)."""
    w = omega_co
    A = np.array([[0.0, 1.0], [-w * w, -2.0 * w]])
    Phi, _, g0, g1 = step_matrices(A, np.zeros(2), np.array([0.0, w * w]), dt)
    return np.ascontiguousarray(Phi), g0, g1


def _choice(name: str, value: Any, options) -> str:
    if not isinstance(value, str) or value not in options:
        raise ValueError(f"{name}: expected one of {', '.join(options)}, found {value!r}")
    return value


def _rms(x: np.ndarray) -> float | None:
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if x.size else None


def _metrics(sc, out, e, n_written, settle_tol, wall, dt) -> dict:
    valid = slice(0, n_written)
    t = np.arange(len(e)) * dt
    m: dict[str, Any] = {
        "rms_error": _rms(e[valid]),
        "max_error": float(np.max(np.abs(e[valid]))) if n_written else None,
        "settling_time": [],
        "steady_state_error": [],
        "observer_rms_error_v": _rms(out["v_hat"][valid] - out["v"][valid]),
        "observer_rms_error_f": _rms(out["f_hat"][valid] - out["f"][valid]),
        "diverged": bool(n_written < len(e)),
        "sim_wall_s": wall,
    }
    for start, end in sc.holds:
        idx = np.nonzero((t >= start - 0.5 * dt) & (t < end - 0.5 * dt))[0]
        seg = np.abs(e[idx])
        outside = np.nonzero(~(seg <= settle_tol))[0]
        if m["diverged"] and idx[-1] >= n_written:
            m["settling_time"].append(None)
        elif outside.size == 0:
            m["settling_time"].append(0.0)
        elif outside[-1] == len(seg) - 1:
            m["settling_time"].append(None)  # never settles within the hold
        else:
            m["settling_time"].append(float((outside[-1] + 1) * dt))
        tail = idx[int(0.9 * len(idx)):]
        m["steady_state_error"].append(float(np.mean(e[tail])) if np.all(np.isfinite(e[tail])) else None)
    if sc.name == "tracking":
        freq = chirp_frequency(t, sc.duration)
        m["rms_error_per_band"] = {
            label: _rms(e[(freq >= lo) & (freq < hi)]) for label, lo, hi in CHIRP_BAND_LABELS
        }
    return m


def simulate(
    cfg: Config,
    scenario: str,
    *,
    controller: str | None = None,
    variant: str | None = None,
    rho: float | None = None,
    kappa: float | None = None,
    stiffness: str = "estimated",
    plant: str = "physical",
    noise_rms: float | None = None,
    noise_bandwidth: float | None = None,
    quantization: float | None = None,
    input_force: float | None = None,
    duration: float | None = None,
    dt: float | None = None,
    seed: int = 0,
    step_size: float | None = None,
    step_up: float | None = None,
    step_down: float | None = None,
    excitation_bandwidth: float | None = None,
    settle_tol: float = 2e-6,
    initial_estimate: tuple[float, float] = (0.0, 0.0),
    substeps: int = 10,
    keep_trace: bool = True,
    _return_inputs: bool = False,
) -> SimResult:
    """Simulate plant, sensor, observer, filter and controller at the sampling rate.

    Parameters
    ----------
    cfg : Config
    scenario : {'excitation', 'constant', 'positioning', 'tracking'}
        See :mod:`obsdesign.sim.scenarios`.
    controller : {'open-loop', 'pid', 'pid+observer'}, optional
        Default ``open-loop`` for ``excitation``/``constant``, ``pid+observer`` otherwise.
    variant, rho, kappa : optional
        Observer overrides of the config.
    stiffness : {'estimated', 'true', 'constant'}
        Stiffness schedule of the observer.
    plant : {'physical', 'model'}
        ``physical``: Coulomb with pre-sliding memory and viscous friction (with lag when
        ``friction.beta`` is set). ``model``: the 3-state LTV model eq:3:1 of the variant.
    noise_rms, noise_bandwidth, quantization : float, optional
        Sensor overrides [m, Hz, m].
    input_force : float, optional
        Open-loop force [N]: the constant, or the RMS of the excitation (default 1 N).
    duration, dt : float, optional
        Length [s] (scenario default) and sample time [s] (config default).
    seed : int
        Seed of the measurement noise and the excitation (``numpy.random.SeedSequence``).
    step_size, step_up, step_down : float, optional
        Positioning steps [m, s, s].
    excitation_bandwidth : float, optional
        Bandwidth [Hz] of the ``excitation`` force (default 5 Hz).
    settle_tol : float
        Band [m] for the settling time (default 2 um).
    initial_estimate : (float, float)
        Observer's initial ``(v_hat, f_hat)``; the plant starts at rest.
    substeps : int
        RK4 substeps of the plant per sample (default 10).
    keep_trace : bool
        False returns metrics only.

    Returns
    -------
    SimResult
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    cfg = cfg.override(noise_rms=noise_rms, noise_bandwidth=noise_bandwidth, quantization=quantization, dt=dt,
                       rho=rho, kappa=kappa, variant=variant)
    stiffness = _choice("stiffness", stiffness, tuple(kernel.SCHEDULES))
    plant = _choice("plant", plant, PLANTS)
    dt = cfg.observer.dt
    noise_seed, signal_seed = np.random.SeedSequence(seed).spawn(2)
    sc = build_scenario(scenario, dt=dt, duration=duration, input_force=input_force, step_size=step_size,
                        step_up=step_up, step_down=step_down, excitation_bandwidth=excitation_bandwidth,
                        seed=signal_seed)
    if controller is None:
        controller = "open-loop" if sc.open_loop else "pid+observer"
    controller = _choice("controller", controller, tuple(kernel.CONTROLLERS))
    if sc.open_loop != (controller == "open-loop"):
        expected = "'open-loop'" if sc.open_loop else "'pid' or 'pid+observer'"
        raise ValueError(f"controller: scenario {sc.name!r} needs {expected}, found {controller!r}")
    settle_tol = _POS.check("settle_tol", settle_tol)
    if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
        raise ValueError(f"substeps: expected an integer >= 1, found {substeps!r}")
    v_hat0, f_hat0 = (_FINITE.check("initial_estimate", x) for x in initial_estimate)
    if plant == "model" and cfg.observer.variant == "lag" and cfg.friction.beta is None:
        raise ValueError("plant: the 'model' plant of variant 'lag' needs friction.beta")

    obs = observer_arrays(cfg)
    lp_phi, lp_g0, lp_g1 = _lowpass_arrays(cfg.observer.omega_co, dt)
    n = len(sc.x_ref)
    sensor = cfg.sensor
    noise = band_limited_noise(n, dt, sensor.noise_rms, sensor.noise_bandwidth, noise_seed)
    if controller == "open-loop":
        kp = ki = kd = tau_d = 0.0
    else:
        _, _, kp, ki, kd = pid_gains(phi=cfg.phi, tau=cfg.pid.tau, max_S=cfg.pid.max_S,
                                     phase_margin_deg=cfg.pid.phase_margin_deg)
        tau_d = kd / kp / cfg.pid.derivative_N
    fr, pl = cfg.friction, cfg.plant
    loop = LoopInputs(
        dt=dt, n_sub=substeps, mode=kernel.PLANT_MODEL if plant == "model" else kernel.PLANT_PHYSICAL,
        lag_model=cfg.observer.variant == "lag", m=pl.m, K=pl.K, G=pl.G, Cf=fr.Cf, s=fr.s, sigma=fr.sigma,
        beta=fr.beta if fr.beta is not None else 0.0, kappa=fr.kappa, A0=obs.A0, A1=obs.A1, b0=obs.b0, b1=obs.b1,
        g0=obs.g0, g1=obs.g1, L1=obs.design.L1, L2=obs.design.L2, schedule=kernel.SCHEDULES[stiffness], v_hat0=v_hat0, f_hat0=f_hat0,
        controller=kernel.CONTROLLERS[controller], kp=kp, ki=ki, kd=kd, tau_d=tau_d, u_max=pl.u_max,
        lp_phi=lp_phi, lp_g0=lp_g0, lp_g1=lp_g1, x_ref=sc.x_ref, u_open=sc.u_open, noise=noise,
        quantization=sensor.quantization,
    )
    if _return_inputs:
        return loop
    out = kernel.empty_outputs(n)
    t0 = time.perf_counter()
    n_written = kernel.run_loop(*loop.args(), *out.values())
    wall = time.perf_counter() - t0
    e = sc.x_ref - out["x"]
    metrics = _metrics(sc, out, e, n_written, settle_tol, wall, dt)
    traces = {}
    if keep_trace:
        traces = dict(out, t=np.arange(n) * dt, x_ref=sc.x_ref, e=e)
    return SimResult(scenario=sc.name, controller=controller, plant=plant, stiffness_schedule=stiffness,
                     config=cfg, metrics=metrics, **traces)
