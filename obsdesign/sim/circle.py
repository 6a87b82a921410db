"""The two-axis circle (ballbar) test: X and Y each a sampled loop of its own config, one contour.

The machine-tool contour test: the tool follows a circle of radius ``R`` at feed ``F`` (path
velocity); where an axis reverses, friction holds it for a moment and the contour shows a
*quadrant glitch*, a spike of radial error. :func:`simulate_circle` runs each axis as the one
sampled loop of :func:`obsdesign.sim.prepare` (each with its own config, the same by default; no
cross-coupling between the axes) on its component of the path and reports:

* ``radial_error`` [m]: ``r - R`` over the evaluated revolution (``rms``, ``max``, ``min``);
* ``circularity`` [m]: ``max r - min r`` over it;
* ``glitches``: the four axis reversals of the revolution (X at 0 and 180 deg, Y at 90 and
  270 deg), each with its ``height`` [m], the largest ``|e_r - median(e_r)|`` in the eighth of a
  revolution after the reversal, and its ``duration`` [s], the time in that window where the
  deviation exceeds half the height; ``glitch_peak`` is the largest height;
* ``axes``: per axis the tracking error (``rms``, ``max``) and the axis's glitch (its largest
  ``|e|`` after its reversals).

The path: centre ``(-R, 0)``, so both axes start at 0 and at rest; ``theta`` runs from 0 with a
raised-cosine ramp of the angular speed over ``ramp`` seconds, a lead-in revolution, the evaluated
revolution(s) from ``theta = 2 pi``, then a quarter turn and the ramp down. ``direction`` ``ccw``:
``(x, y) = (R (cos theta - 1), R sin theta)``; ``cw``: ``y = -R sin theta``. The noise of X uses
seed ``2 seed``, of Y ``2 seed + 1``.

Examples
--------
>>> import obsdesign as od
>>> res = simulate_circle(od.load_preset("vcm"), radius=5e-3, feed=2e-2)
>>> sorted(res.metrics)[:4]
['axes', 'circularity', 'controller', 'direction']
>>> len(res.metrics["glitches"]), res.metrics["glitch_peak"] > 0
(4, True)
>>> simulate_circle(od.load_preset("vcm"), radius=5e-3, feed=5.0)
Traceback (most recent call last):
...
ValueError: feed: expected a path velocity the axis can drive (peak force m F^2/R + Cf + sigma F + |G| <= K u_max = 32.8 N: at most 0.414 m/s for radius 0.005 m), found 5.0
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import POSITIVE, check_choice, check_integer
from ..params import Config
from . import kernel
from ..loop.inputs import prepare

__all__ = ["CircleResult", "simulate_circle", "circle_modes", "circle_path", "circle_metrics", "DIRECTIONS", "MAX_RADIUS"]

DIRECTIONS = ("ccw", "cw")
#: Largest radius [m] (a path beyond 1 m is not a precision-axis test).
MAX_RADIUS = 1.0
#: Smallest radius in encoder counts.
MIN_RADIUS_COUNTS = 100


@dataclass(frozen=True, eq=False)
class CircleResult:
    """One circle run: the metrics and (``keep_trace``) the traces.

    Attributes
    ----------
    metrics : dict
        See :mod:`obsdesign.sim.circle`.
    t, theta, x_ref, y_ref, x, y : ndarray
        Time [s], path angle [rad], references and positions [m] (empty without trace).
    window : slice
        The samples of the evaluated revolution(s).
    """

    metrics: dict
    t: np.ndarray = field(repr=False)
    theta: np.ndarray = field(repr=False)
    x_ref: np.ndarray = field(repr=False)
    y_ref: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    y: np.ndarray = field(repr=False)
    window: slice = field(repr=False)


def _check_limits(cfg: Config, radius: float, feed: float, name: str) -> None:
    """The path must be within what the axis can drive and resolve."""
    pl, fr = cfg.plant, cfg.friction
    q = cfg.sensor.quantization
    if radius > MAX_RADIUS or (q > 0 and radius < MIN_RADIUS_COUNTS * q):
        low = MIN_RADIUS_COUNTS * q
        raise ValueError(f"radius: expected a radius in [{low:g}, {MAX_RADIUS:g}] m ({MIN_RADIUS_COUNTS} encoder "
                         f"counts to {MAX_RADIUS:g} m) for {name}, found {radius!r}")
    budget = pl.K * pl.u_max - abs(pl.G) - fr.Cf
    # m F^2 / R + sigma F <= budget: the largest feed
    a = pl.m / radius
    f_max = (-fr.sigma + math.sqrt(fr.sigma ** 2 + 4 * a * max(budget, 0.0))) / (2 * a)
    if feed > f_max:
        raise ValueError(f"feed: expected a path velocity the axis can drive (peak force m F^2/R + Cf + sigma F + |G| "
                         f"<= K u_max = {pl.K * pl.u_max:.4g} N: at most {f_max:.3g} m/s for radius {radius:g} m)"
                         f"{'' if name == 'the axis' else ' for ' + name}, found {feed!r}")


def circle_path(radius: float, feed: float, dt: float, *, direction: str = "ccw", revolutions: int = 1,
                ramp: float = 0.1):
    """Angle and the two references of the circle test (see :mod:`obsdesign.sim.circle`).

    Parameters
    ----------
    radius, feed : float
        Radius [m] and path velocity [m/s].
    dt : float
        Sample time [s].
    direction : str
        ``ccw`` or ``cw``.
    revolutions : int
        Evaluated revolutions (after the lead-in one).
    ramp : float
        Ramp time [s] of the angular speed at the start and the end.

    Returns
    -------
    theta, x_ref, y_ref : ndarray
    window : slice
        Samples with ``2 pi <= theta < 2 pi (1 + revolutions)``.

    Examples
    --------
    >>> theta, x, y, w = circle_path(1e-3, 1e-2, 1e-3)
    >>> float(x[0]), float(y[0]), round(float(theta[-1] / (2 * np.pi)), 3)
    (0.0, 0.0, 2.25)
    """
    omega = feed / radius
    t_a = ramp
    theta_end = 2 * np.pi * (1 + revolutions) + np.pi / 2  # ramp-down starts after a quarter turn more
    # theta(t): ramp 0..t_a (gains omega t_a / 2), constant, ramp down (loses omega t_a / 2)
    t_const = (theta_end - omega * t_a) / omega
    duration = 2 * t_a + max(t_const, 0.0)
    t = np.arange(int(math.ceil(duration / dt)) + 1) * dt
    up = omega * (t / 2 - t_a / (2 * np.pi) * np.sin(np.pi * t / t_a))
    t2 = t - t_a - t_const
    down = omega * t_a / 2 + omega * t_const + omega * (t2 / 2 + t_a / (2 * np.pi) * np.sin(np.pi * t2 / t_a))
    theta = np.where(t < t_a, up, np.where(t2 < 0, omega * (t - t_a / 2), down))
    theta = np.where(t2 >= t_a, theta_end, theta)
    sign = 1.0 if check_choice("direction", direction, DIRECTIONS) == "ccw" else -1.0
    x_ref = radius * (np.cos(theta) - 1.0)
    y_ref = sign * radius * np.sin(theta)
    inside = np.flatnonzero((theta >= 2 * np.pi) & (theta < 2 * np.pi * (1 + revolutions)))
    return theta, x_ref, y_ref, slice(int(inside[0]), int(inside[-1]) + 1)


def circle_metrics(theta, x, y, x_ref, y_ref, radius: float, dt: float, window: slice) -> dict:
    """Radial error, circularity, the four quadrant glitches and the per-axis errors of a circle run.

    Parameters
    ----------
    theta, x, y, x_ref, y_ref : ndarray
        Path angle [rad], positions and references [m].
    radius, dt : float
        Nominal radius [m], sample time [s].
    window : slice
        The evaluated revolution(s).

    Returns
    -------
    dict
        The keys of :mod:`obsdesign.sim.circle` (SI units).
    """
    th = theta[window]
    r = np.hypot(x[window] + radius, y[window])
    er = r - radius
    base = float(np.median(er))
    dev = np.abs(er - base)
    glitches = []
    n_rev = (th[-1] - th[0]) / (2 * np.pi)
    for axis, angle in (("x", 0.0), ("y", np.pi / 2), ("x", np.pi), ("y", 1.5 * np.pi)):
        a0 = 2 * np.pi + angle
        sel = (th >= a0) & (th < a0 + np.pi / 4)
        if not np.any(sel):
            continue
        h = float(np.max(dev[sel]))
        glitches.append({"axis": axis, "angle_deg": math.degrees(angle), "height": h,
                         "duration": float(np.sum(dev[sel] > h / 2) * dt)})
    axes = {}
    for name, pos, ref, reversals in (("x", x, x_ref, (0.0, np.pi)), ("y", y, y_ref, (np.pi / 2, 1.5 * np.pi))):
        e = (ref - pos)[window]
        peak = 0.0
        for angle in reversals:
            sel = (th >= 2 * np.pi + angle) & (th < 2 * np.pi + angle + np.pi / 4)
            if np.any(sel):
                peak = max(peak, float(np.max(np.abs(e[sel]))))
        axes[name] = {"rms": float(np.sqrt(np.mean(e ** 2))), "max": float(np.max(np.abs(e))), "glitch": peak}
    return {
        "radial_error": {"rms": float(np.sqrt(np.mean(er ** 2))), "max": float(np.max(er)), "min": float(np.min(er)),
                         "median": base},
        "circularity": float(np.max(r) - np.min(r)),
        "glitches": glitches,
        "glitch_peak": max((g["height"] for g in glitches), default=0.0),
        "axes": axes,
        "revolutions": float(round(n_rev, 3)),
    }


def _run_axis(cfg: Config, ref: np.ndarray, *, controller: str, seed: int, **options) -> np.ndarray:
    """One axis: the loop of :func:`prepare` on ``ref``; returns its position."""
    dt = cfg.observer.dt
    loop = prepare(cfg, "tracking", controller=controller, duration=len(ref) * dt, seed=seed, **options)
    n = min(loop.n_samples, len(ref))
    loop = dataclasses.replace(loop, x_ref=ref[:n], u_open=loop.u_open[:n], noise=loop.noise[:n])
    out = kernel.Outputs(*(np.empty(n) for _ in kernel.OUTPUT_NAMES))
    written = kernel.run_loop(*loop.kernel_args(), out)
    if written < n:
        raise ValueError(f"circle: the loop diverged after {written * dt:.4g} s of {n * dt:.4g} s")
    return out.x


def simulate_circle(cfg: Config, *, radius: float = 5e-3, feed: float = 1e-2, direction: str = "ccw",
                    cfg_y: Config | None = None, controller: str = "pid+observer", revolutions: int = 1,
                    ramp: float = 0.1, seed: int = 0, keep_trace: bool = False, **options) -> CircleResult:
    """Simulate the circle test on two axes (X: ``cfg``, Y: ``cfg_y``, default the same).

    Parameters
    ----------
    cfg : Config
        The X axis's design (its ``[compensation]`` chooses the compensation mode).
    radius : float
        Radius [m], at least 100 encoder counts, at most :data:`MAX_RADIUS`.
    feed : float
        Path velocity [m/s] (positive, within the actuator's force limit).
    direction : str
        ``ccw`` or ``cw``.
    cfg_y : Config, optional
        The Y axis's design (same sample time as X).
    controller : str
        ``pid`` or ``pid+observer`` (:data:`obsdesign.sampled.choices.CONTROLLERS`).
    revolutions : int
        Evaluated revolutions (after a lead-in one).
    ramp : float
        Ramp time [s] of the path speed at the start and the end.
    seed : int
        Noise seed (X: ``2 seed``, Y: ``2 seed + 1``).
    keep_trace : bool
        Keep the traces in the result.
    **options
        Further options of :func:`obsdesign.sim.prepare` (``stiffness``, ``plant``, ``estimator``,
        ``substeps``); ``plant`` applies to both axes.

    Returns
    -------
    CircleResult

    Raises
    ------
    ValueError
        A radius or feed outside the axis's limits, an unknown direction, configs of different
        sample times, a look-ahead longer than the axis's half period, a diverged run.
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    cfg_y = cfg if cfg_y is None else cfg_y
    if not isinstance(cfg_y, Config):
        raise TypeError(f"cfg_y: expected a Config, found {type(cfg_y).__name__}")
    radius = POSITIVE.check("radius", radius)
    feed = POSITIVE.check("feed", feed)
    ramp = POSITIVE.check("ramp", ramp)
    revolutions = check_integer("revolutions", revolutions, minimum=1, maximum=100)
    seed = check_integer("seed", seed, minimum=0)
    direction = check_choice("direction", direction, DIRECTIONS)
    dt = cfg.observer.dt
    if cfg_y.observer.dt != dt:
        raise ValueError(f"cfg_y: expected the sample time of X ({dt!r} s), found {cfg_y.observer.dt!r} s")
    _check_limits(cfg, radius, feed, "the axis" if cfg_y is cfg else "axis X")
    if cfg_y is not cfg:
        _check_limits(cfg_y, radius, feed, "axis Y")
    theta, x_ref, y_ref, window = circle_path(radius, feed, dt, direction=direction, revolutions=revolutions,
                                              ramp=ramp)
    x = _run_axis(cfg, x_ref, controller=controller, seed=2 * seed, **options)
    y = _run_axis(cfg_y, y_ref, controller=controller, seed=2 * seed + 1, **options)
    n = min(len(x), len(y))
    metrics = circle_metrics(theta[:n], x[:n], y[:n], x_ref[:n], y_ref[:n], radius, dt, window)
    metrics.update(radius=radius, feed=feed, direction=direction, controller=controller,
                   mode=cfg.compensation.mode if controller == "pid+observer" else "none")
    if not keep_trace:
        empty = np.empty(0)
        return CircleResult(metrics, empty, empty, empty, empty, empty, empty, window)
    return CircleResult(metrics, np.arange(n) * dt, theta[:n], x_ref[:n], y_ref[:n], x[:n], y[:n], window)


def circle_modes(cfg: Config, *, modes=None, feeds=(1e-2,), directions=("ccw",), seeds=(0,), radius: float = 5e-3,
                 **options) -> list[dict]:
    """The circle test for each compensation mode, feed, direction and seed: one row each.

    Parameters
    ----------
    cfg : Config
        The design of both axes (its ``[compensation]`` knobs other than ``mode`` are kept).
    modes : sequence of str, optional
        ``pid`` (no compensation) and names of
        :data:`obsdesign.compensation.COMPENSATION_MODES`; default all of them.
    feeds, directions, seeds : sequence
        Path velocities [m/s], ``ccw``/``cw``, noise seeds.
    radius : float
        Radius [m].
    **options
        Further options of :func:`simulate_circle`; with ``keep_trace=True`` each row also holds its
        run as ``result`` (a :class:`CircleResult`).

    Returns
    -------
    list of dict
        ``mode, feed, direction, seed, glitch_peak, circularity, radial_rms`` [SI].

    Examples
    --------
    >>> import obsdesign as od
    >>> rows = circle_modes(od.load_preset("vcm"), modes=("pid", "observer"), feeds=(2e-2,))
    >>> [r["mode"] for r in rows], rows[1]["glitch_peak"] < rows[0]["glitch_peak"]
    (['pid', 'observer'], True)
    """
    from ..compensation import COMPENSATION_MODES

    names = ("pid", *COMPENSATION_MODES.names())
    modes = names if modes is None else tuple(check_choice("mode", m, names) for m in modes)
    rows = []
    for mode in modes:
        if mode == "pid":
            c, controller = cfg, "pid"
        else:
            keep = {} if mode != "observer" else {"lookahead": 0, "buildup": 0.0, "ff_presliding": True}
            c, controller = cfg.override(mode=mode, **keep), "pid+observer"
        for feed in feeds:
            for direction in directions:
                for seed in seeds:
                    res = simulate_circle(c, radius=radius, feed=feed, direction=direction, controller=controller,
                                          seed=seed, **options)
                    m = res.metrics
                    rows.append({"mode": mode, "feed": feed, "direction": direction, "seed": seed,
                                 "glitch_peak": m["glitch_peak"], "circularity": m["circularity"],
                                 "radial_rms": m["radial_error"]["rms"]})
                    if options.get("keep_trace"):
                        rows[-1]["result"] = res
    return rows
