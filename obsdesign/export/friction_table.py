"""The feed-forward friction model as a drive's velocity -> force (-> current) table, CSV and C array.

Drives compensate friction from a table of the commanded velocity (Beckhoff TwinCAT TF5200: up to
20 points, a look-ahead in cycles before a reversal and a build-up distance after a start).
:func:`friction_table` tabulates the one feed-forward model of the sampled controller
(:func:`obsdesign.sampled.kernel.feedforward_model`: ``Cf``, ``sigma`` of ``[friction]`` and the
Stribeck terms of ``[compensation]``) on ``0 <= v <= v_max`` for the drive to interpolate linearly
and mirror: ``F(-v) = -F(v)``, with the constant ``ff_offset`` added apart. The first point is the
limit ``v -> 0+`` (``Cf + ff_stribeck``). The breakpoints are placed so that the largest
interpolation error is as small as ``points`` allow (a greedy placement for a tolerance, bisected
on the tolerance), measured on a grid of :data:`GRID` velocities; the table reports that error.

Examples
--------
>>> import obsdesign as od
>>> cfg = od.load_preset("vcm").override(ff_stribeck=0.15, ff_stribeck_velocity=2e-3)
>>> tab = friction_table(cfg, points=12, motor_constant=3.28)
>>> len(tab.velocity), float(tab.force[0]), tab.max_error < 2e-3
(12, 0.5, True)
>>> friction_table(cfg, velocities=[0.0, 0.01, 0.005])
Traceback (most recent call last):
...
ValueError: velocities: expected strictly increasing velocities >= 0 m/s starting at 0, found [0.0, 0.01, 0.005]
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import MOTOR_CONSTANT, V_MAX, check_integer
from ..axis import LINEAR, AxisSpec
from ..params import Config
from .literals import comment_text

__all__ = ["FrictionTable", "friction_table", "table_files", "GRID"]

#: Velocities of the grid on which the interpolation error is measured.
GRID = 20001
_TINY = 5e-324  # the limit v -> 0+: sign 1, exp(-(v/vs)^2) = 1, sigma v = 0 in floating point


@dataclass(frozen=True, eq=False)
class FrictionTable:
    """A velocity -> force table of the feed-forward model.

    Attributes
    ----------
    velocity, force : ndarray
        Breakpoints [m/s] (from 0) and the model's force there [N] (without the offset).
    current : ndarray or None
        ``force / motor_constant`` [A] (None without a motor constant).
    max_error : float
        Largest ``|F - interpolated table|`` [N] on the grid of :data:`GRID` velocities.
    offset, lookahead, buildup : float, int, float
        ``ff_offset`` [N], look-ahead [samples] and build-up distance [m] of ``[compensation]``.
    motor_constant : float or None
        [N/A].
    dt : float
        The controller's sample time [s] (the look-ahead's unit).
    name : str
        The config's name.
    units : AxisSpec
        The config's axis (``Config.units``): the files' units and column names (a rotary axis's table is
        velocity [rad/s] -> torque [N m]); the arrays are SI either way.
    """

    velocity: np.ndarray = field(repr=False)
    force: np.ndarray = field(repr=False)
    current: "np.ndarray | None" = field(repr=False)
    max_error: float
    offset: float
    lookahead: int
    buildup: float
    motor_constant: "float | None"
    dt: float
    name: str
    units: AxisSpec = LINEAR


def _model(cfg: Config):
    """The kernel's feed-forward model of the config, vectorised over ``v >= 0`` (without the offset)."""
    from ..sampled.controller import sampled_controller
    from ..sampled.kernel import feedforward_model

    c = sampled_controller(cfg).kernel_args()[2]

    def force(v):
        return np.array([feedforward_model(max(float(x), _TINY), 1.0, True, c) for x in v]) - c.ff_offset

    return force


def _max_error(grid, f_grid, bp_idx) -> float:
    return float(np.max(np.abs(f_grid - np.interp(grid, grid[bp_idx], f_grid[bp_idx]))))


def _greedy(grid, f_grid, tol) -> list[int]:
    """Breakpoint indices: each segment as long as its interpolation error stays within ``tol``."""
    idx, i, n = [0], 0, len(grid)
    while i < n - 1:
        lo, hi = i + 1, n - 1  # the largest j with error(i, j) <= tol (error grows with j)
        while lo < hi:
            j = (lo + hi + 1) // 2
            seg = slice(i, j + 1)
            line = f_grid[i] + (f_grid[j] - f_grid[i]) * (grid[seg] - grid[i]) / (grid[j] - grid[i])
            if np.max(np.abs(f_grid[seg] - line)) <= tol:
                lo = j
            else:
                hi = j - 1
        i = lo
        idx.append(i)
    return idx


def friction_table(cfg: Config, *, points: int = 20, v_max: float | None = None, velocities=None,
                   motor_constant: float | None = None) -> FrictionTable:
    """Tabulate the feed-forward friction model of a config.

    Parameters
    ----------
    cfg : Config
        The design (``[friction]`` Cf, sigma; ``[compensation]`` Stribeck, offset, look-ahead, build-up).
    points : int
        Number of breakpoints, 2 to 1000 (default 20, the drives' table size).
    v_max : float, optional
        Largest velocity [m/s], at most 1e3 (:data:`obsdesign._validate.V_MAX`); default the axis's: ``(K u_max - |G| - Cf) / sigma``.
    velocities : sequence of float, optional
        Breakpoints given instead (strictly increasing from 0, within ``v_max``).
    motor_constant : float, optional
        Force per current [N/A], 1e-6 to 1e6 (:data:`obsdesign._validate.MOTOR_CONSTANT`): adds the current column.

    Returns
    -------
    FrictionTable

    Raises
    ------
    ValueError
        A table that is not increasing in velocity, a bad count, velocity or motor constant.
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    pl, fr = cfg.plant, cfg.friction
    top = (pl.K * pl.u_max - abs(pl.G) - fr.Cf) / fr.sigma
    v_max = top if v_max is None else V_MAX.check("v_max", v_max)
    if motor_constant is not None:
        motor_constant = MOTOR_CONSTANT.check("motor_constant", motor_constant)
    grid = np.linspace(0.0, v_max, GRID)
    force = _model(cfg)
    f_grid = force(grid)
    if velocities is not None:
        v = np.asarray(velocities, dtype=float)
        if v.ndim != 1 or len(v) < 2 or v[0] != 0.0 or not np.all(np.diff(v) > 0) or not np.all(np.isfinite(v)):
            raise ValueError(f"velocities: expected strictly increasing velocities >= 0 m/s starting at 0, found "
                             f"{[float(x) for x in np.ravel(v)][:8]}")
        if v[-1] > v_max:
            raise ValueError(f"velocities: expected at most v_max = {v_max:.6g} m/s, found {v[-1]!r}")
        grid = np.union1d(np.linspace(0.0, v[-1], GRID), v)
        f_grid = force(grid)
        bp = np.searchsorted(grid, v)
    else:
        points = check_integer("points", points, minimum=2, maximum=1000)
        lo, hi = 0.0, _max_error(grid, f_grid, [0, GRID - 1])
        best = [0, GRID - 1]
        for _ in range(60):  # bisection on the tolerance: the smallest one the points allow
            if hi - lo <= 1e-12 * max(hi, 1e-300):
                break
            mid = 0.5 * (lo + hi)
            idx = _greedy(grid, f_grid, mid)
            if len(idx) <= points:
                hi, best = mid, idx
            else:
                lo = mid
        bp = np.array(best)
    err = _max_error(grid, f_grid, bp)
    comp = cfg.compensation
    vel, frc = grid[bp], f_grid[bp]
    return FrictionTable(velocity=vel, force=frc, current=None if motor_constant is None else frc / motor_constant,
                         max_error=err, offset=comp.ff_offset, lookahead=comp.lookahead, buildup=comp.buildup,
                         motor_constant=motor_constant, dt=cfg.observer.dt, name=cfg.name, units=cfg.units)


def table_files(tab: FrictionTable) -> dict[str, str]:
    """``friction_table.csv`` and ``friction_table.h`` (C99 arrays) of a table.

    Parameters
    ----------
    tab : FrictionTable

    Returns
    -------
    dict of str to str
    """
    name = comment_text(tab.name)
    ax = tab.units
    u, word = ax.unit, ax.force_word
    head = [f"friction table of config {name}: {word} = table(|v|) sign(v) + offset, linear interpolation",
            f"max interpolation error {tab.max_error!r} {u('N')} on {GRID} velocities",
            f"offset {tab.offset!r} {u('N')}; lookahead {tab.lookahead} samples of dt {tab.dt!r} s; buildup "
            f"{tab.buildup!r} {u('m')}",
            f"motor constant {tab.motor_constant!r} {u('N')}/A" if tab.motor_constant else "no motor constant: no current"]
    if ax.rotary:
        head.insert(1, f"{ax.describe()}: velocity in rad/s, torque in N m")
    cols = [f"velocity_{u('m')}_s", f"{word}_{u('N').replace(' ', '_')}"] + (["current_A"] if tab.current is not None
                                                                               else [])
    data = [tab.velocity, tab.force] + ([tab.current] if tab.current is not None else [])
    csv = "".join(f"# {h}\n" for h in head) + ",".join(cols) + "\n"
    csv += "".join(",".join(repr(float(c[i])) for c in data) + "\n" for i in range(len(tab.velocity)))
    n = len(tab.velocity)

    def arr(cname, values):
        return f"static const double {cname}[{n}] = {{{', '.join(repr(float(x)) for x in values)}}};\n"

    h = "/* friction_table.h: generated by obsdesign.\n" + "".join(f" * {x}\n" for x in head) + " */\n"
    h += "#ifndef OBSDESIGN_FRICTION_TABLE_H\n#define OBSDESIGN_FRICTION_TABLE_H\n\n"
    h += f"#define OD_FT_POINTS {n}\n#define OD_FT_OFFSET {tab.offset!r}\n#define OD_FT_LOOKAHEAD {tab.lookahead}\n"
    h += f"#define OD_FT_BUILDUP {tab.buildup!r}\n#define OD_FT_MAX_ERROR {tab.max_error!r}\n\n"
    h += arr("OD_FT_VELOCITY", tab.velocity) + arr("OD_FT_FORCE", tab.force)
    if tab.current is not None:
        h += arr("OD_FT_CURRENT", tab.current)
    h += "\n#endif\n"
    assert math.isfinite(tab.max_error)
    return {"friction_table.csv": csv, "friction_table.h": h}
