"""An identification experiment: a reference trajectory that makes the friction parameters identifiable.

:func:`design_experiment` builds, from the axis's stroke, speed and force limits, a rough mass and
the sample time, a position reference in two parts:

1. a **velocity staircase**: ``levels`` constant speeds, run level to level in one stroke, log-spaced from
   the largest of ``speed / 300``, ``3 travel`` in 5 s and 20 encoder steps per second, to
   ``speed``, forwards and then back (both directions, so the Coulomb level, the viscous
   slope, the offset and, below the Stribeck speed, the Stribeck drop are seen); the ramps between
   levels excite the mass in gross sliding, away from the pre-sliding transients;
2. **pre-sliding blocks**: a gross move of ``2 travel`` (the friction saturates), then small
   reversals of amplitudes from ``0.1 travel`` to ``travel`` with a dwell after each, then a gross
   move back. Each block is one window of :func:`obsdesign.data.output_error.refine`.

Every move is a raised-cosine velocity ramp whose peak acceleration is ``force_fraction * force /
mass``. The result writes itself as CSV (``t, x_ref, v_ref``) and as a C array (atomic writes; the
array's name is checked as a C identifier and the comment holds numbers only).

One mechanism for both kinds of axis: with ``rotary=True`` the same plan is in rad, rad/s, N m and
kg m^2 (stroke, speed, torque limit, inertia), and everything it prints says so. Given the range of
the Stribeck speed ``stribeck_speed = (lo, hi)`` (a guess is enough), the staircase gets levels from a
third of ``lo`` to three times ``hi`` (at least 2 below ``lo`` and 2 above ``2 hi``): the drop and its
end are both seen, and the plan says that ``Fs`` and ``vs`` are identifiable (with ``--stribeck on`` and
a min-speed below the slowest level, which it names).

Examples
--------
>>> exp = design_experiment(stroke=0.04, speed=0.1, force=5.0, mass=0.5, dt=1e-3, travel=1e-3, blocks=2)
>>> exp.reversals_dwelling, bool(abs(exp.x_ref).max() <= 0.02)
(10, True)
>>> sorted(exp.expected)
['Cf', 'm', 'offset', 's', 'sigma', 'timing']
>>> rot = design_experiment(stroke=60.0, speed=20.0, force=1.0, mass=2.5e-3, dt=2.5e-4, travel=1e-3,
...                         rotary=True, stribeck_speed=(0.2, 1.0))
>>> min(rot.levels) <= 0.2 / 3 * 1.001, max(rot.levels) >= 3.0, rot.expected["vs"]["identifiable"]
(True, True, True)
>>> str(rot).splitlines()[1][:26]
'  staircase speeds [rad/s]'
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from .._io import atomic_write
from ..axis import AxisSpec

__all__ = ["Experiment", "design_experiment", "C_NAME"]

#: What a C array name may be (an identifier, ASCII, at most 63 characters).
C_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,62}$")
_REVERSALS_PER_BLOCK = 5
#: Why the plan does not make the log's timing identifiable (measured: docs/experiment.md).
_TIMING_WHY = ("constant speeds and their ramps do not tell the input timing and the position delay apart (identify "
               "says 'not resolved' and widens the intervals to every reading it cannot reject: sigma's by +4.6 % on a "
               "simulated 4 kHz rotary axis, whose kept reading was -2 % off): give the drive's --input-timing (hold: "
               "a sampled controller's output) and --delay-samples")


@dataclass(frozen=True, kw_only=True)
class Experiment:
    """A designed reference trajectory (:func:`design_experiment`).

    Attributes
    ----------
    dt : float
        Sample time [s].
    x_ref, v_ref : ndarray
        Position [m] and velocity [m/s] reference per sample.
    staircase_end : int
        First sample after the staircase: identify the static model (:func:`~obsdesign.data.identify`)
        on the samples before it (gross sliding), refine ``s`` over the whole record.
    levels : tuple of float
        Speeds of the staircase [m/s].
    amplitudes : tuple of float
        Amplitudes of the small reversals [m].
    reversals_dwelling : int
        Small reversals followed by a dwell.
    expected : dict
        Per parameter (``m, sigma, Cf, offset, s``; ``Fs, vs`` with a Stribeck range; ``timing``, the log's
        input timing and delay, which the plan does not resolve: give the drive's):
        ``{"identifiable": bool, "why": str}``.
    limits : dict
        The inputs: stroke, speed, force, mass, acceleration, travel, dwell (and ``stribeck_speed``).
    rotary : bool
        A rotary axis: every length above in rad, speed in rad/s, force in N m, mass in kg m^2.
    """

    dt: float
    x_ref: np.ndarray = field(repr=False)
    v_ref: np.ndarray = field(repr=False)
    staircase_end: int
    levels: tuple[float, ...]
    amplitudes: tuple[float, ...]
    reversals_dwelling: int
    expected: dict
    limits: dict
    rotary: bool = False

    @property
    def units(self) -> AxisSpec:
        """The axis whose units the plan is in (:meth:`obsdesign.axis.AxisSpec.unit` words them)."""
        return AxisSpec(kind="rotary" if self.rotary else "linear")

    @property
    def duration(self) -> float:
        """Length [s]."""
        return self.x_ref.size * self.dt

    def to_dict(self) -> dict:
        """JSON-ready: ``samples, dt, duration, axis, units, levels, amplitudes, reversals_dwelling, limits,
        expected`` (``units``: the unit of each kind of value, those of the axis)."""
        u = self.units.unit
        units = {"length": u("m"), "speed": u("m/s"), "acceleration": u("m/s^2"), "force": u("N"), "mass": u("kg")}
        return {"samples": int(self.x_ref.size), "dt": self.dt, "duration": self.duration, "axis": self.units.kind,
                "units": units,
                "levels": list(self.levels), "amplitudes": list(self.amplitudes),
                "reversals_dwelling": self.reversals_dwelling, "limits": dict(self.limits),
                "expected": {k: dict(v) for k, v in self.expected.items()}}

    def to_csv(self, path) -> None:
        """Write ``t, x_ref, v_ref`` (SI units of the axis: s, m or rad, m/s or rad/s; header row) atomically.

        Parameters
        ----------
        path : str or PathLike
            The CSV file.
        """
        t = np.arange(self.x_ref.size) * self.dt
        rows = "\n".join(f"{a:.9g},{b:.12g},{c:.12g}" for a, b, c in zip(t, self.x_ref, self.v_ref))
        atomic_write(path, "t,x_ref,v_ref\n" + rows + "\n")

    def c_source(self, name: str = "obsdesign_experiment") -> str:
        """A C source defining ``const double NAME[N]`` (positions [m], or [rad] on a rotary axis) and ``NAME_dt``.

        Parameters
        ----------
        name : str
            The array's name: a C identifier that is no keyword of an export language
            (:func:`obsdesign.export.literals.check_identifier`), so no other user text reaches the file.

        Examples
        --------
        >>> exp = design_experiment(stroke=0.04, speed=0.1, force=5.0, mass=0.5, dt=1e-3, blocks=1)
        >>> exp.c_source("x;y")
        Traceback (most recent call last):
        ...
        ValueError: name: expected a C identifier (a letter or _, then letters, digits or _, at most 63), found 'x;y'
        """
        from ..export.literals import check_identifier

        check_identifier("name", name)  # no keyword of C (nor of the other export languages)
        body = ",\n".join("  " + ", ".join(f"{v:.12g}" for v in self.x_ref[i:i + 6])
                          for i in range(0, self.x_ref.size, 6))
        return (f"/* identification experiment: {self.x_ref.size} samples at dt = {self.dt:.9g} s, "
                f"position reference [{self.units.length_unit}] */\n"
                f"const double {name}_dt = {self.dt:.12g};\n"
                f"const unsigned long {name}_n = {self.x_ref.size}UL;\n"
                f"const double {name}[{self.x_ref.size}] = {{\n{body}\n}};\n")

    def to_c(self, path, name: str = "obsdesign_experiment") -> None:
        """Write :meth:`c_source` atomically.

        Parameters
        ----------
        path : str or PathLike
            The C file.
        name : str
            The array's name (:meth:`c_source`).
        """
        atomic_write(path, self.c_source(name))

    def __str__(self) -> str:
        u = self.units.unit
        lines = [f"Identification experiment ({self.units.kind} axis): {self.x_ref.size} samples, "
                 f"{self.duration:.4g} s at dt = {self.dt:g} s",
                 f"  staircase speeds [{u('m/s')}]: {', '.join(f'{v:.3g}' for v in self.levels)} (both directions)",
                 f"  small reversals [{u('m')}]: {', '.join(f'{a:.3g}' for a in self.amplitudes)}; "
                 f"{self.reversals_dwelling} with a dwell of {self.limits['dwell']:g} s",
                 f"  peak acceleration {self.limits['acceleration']:.3g} {u('m/s^2')}, stroke used "
                 f"{float(np.ptp(self.x_ref)):.4g} of {self.limits['stroke']:g} {u('m')}",
                 f"  identify the staircase (samples 0 to {self.staircase_end}: --window 0:"
                 f"{self.staircase_end * self.dt:.6g} --input-timing T --delay-samples D, the drive's) for m, sigma, "
                 "Cf, offset"
                 + (f", with --stribeck on --min-speed {0.5 * min(self.levels):.3g} for Fs, vs" if "vs" in self.expected
                    else "") + "; refine s over the whole record",
                 "  expected identifiability:"]
        for k, v in self.expected.items():
            lines.append(f"    {k:<7} {'yes' if v['identifiable'] else 'no '}  {v['why']}")
        return "\n".join(lines)


def _positive(name: str, value, high: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) or not 0 < value <= high \
            or not math.isfinite(value):
        bound = f" and <= {high:g}" if math.isfinite(high) else ""
        raise ValueError(f"{name}: expected a finite number > 0{bound}, found {value!r}")
    return float(value)


class _Builder:
    """Velocity segments appended sample by sample; the position is their running integral."""

    def __init__(self, dt: float, acceleration: float, ramp: float):
        self.dt, self.acc, self.t_ramp, self.v = dt, acceleration, ramp, [0.0]

    def hold(self, seconds: float) -> None:
        self.v.extend([0.0] * max(1, int(round(seconds / self.dt))))

    def cruise(self, seconds: float) -> None:
        self.v.extend([self.v[-1]] * max(1, int(round(seconds / self.dt))))

    def ramp(self, v1: float) -> None:
        v0 = self.v[-1]
        n = max(10, int(math.ceil(max(math.pi * abs(v1 - v0) / (2.0 * self.acc), self.t_ramp) / self.dt)))
        self.v.extend((v0 + (v1 - v0) * 0.5 * (1.0 - np.cos(np.pi * np.arange(1, n + 1) / n))).tolist())

    def move(self, distance: float, speed: float) -> None:
        """From rest to rest over ``distance`` [m] (signed): raised-cosine ramps to a peak of at most
        ``speed`` and an acceleration of at most the limit, the profile scaled to the exact distance."""
        d = abs(distance)
        peak = min(speed, math.sqrt(2.0 * self.acc * d / math.pi), d / self.t_ramp)
        n_r = max(10, int(math.ceil(max(math.pi * peak / (2.0 * self.acc), self.t_ramp) / self.dt)))
        up = 0.5 * (1.0 - np.cos(np.pi * np.arange(1, n_r + 1) / n_r))
        n_h = max(0, int(round((d - peak * n_r * self.dt) / (peak * self.dt))))
        shape = np.concatenate([up, np.ones(n_h), up[::-1][1:], [0.0]])
        prev = np.concatenate([[0.0], shape[:-1]])
        covered = float(np.sum(0.5 * (shape + prev))) * self.dt
        self.v.extend((shape * (distance / covered)).tolist())

    def position(self) -> float:
        v = np.asarray(self.v)
        return float(np.sum(0.5 * (v[1:] + v[:-1]))) * self.dt

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        v = np.asarray(self.v)
        x = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1])) * self.dt])
        return x, v


def design_experiment(*, stroke: float, speed: float, force: float, mass: float, dt: float,
                      travel: float = 1e-3, resolution: float = 0.0, levels: int = 6, blocks: int = 5,
                      dwell: float = 0.1, force_fraction: float = 0.5, ramp: float = 0.05, rotary: bool = False,
                      stribeck_speed: tuple[float, float] | None = None) -> Experiment:
    """Design the reference of an identification experiment for an axis.

    The units are those of the axis: a linear one in m, m/s, N, kg; a rotary one (``rotary=True``)
    in rad, rad/s, N m, kg m^2 (the parameters below name the linear unit).

    Parameters
    ----------
    stroke : float
        Usable travel [m]; the reference stays within ``[-stroke/2, stroke/2]`` of the start.
    speed : float
        Largest speed [m/s].
    force : float
        Actuator force limit [N] (the torque limit [N m] of a rotary axis).
    mass : float
        A rough moving mass [kg] (the inertia [kg m^2] of a rotary axis; for the acceleration limit
        ``force_fraction * force / mass``).
    dt : float
        Sample time [s] of the controller that will run the reference.
    travel : float
        Largest expected pre-sliding travel [m] (``1/s``); the gross moves are ``2 travel``, the small
        reversals ``0.1 travel`` to ``travel``. The ``travel`` of :func:`~obsdesign.data.output_error.refine`.
    resolution : float
        Encoder resolution [m] (0: unknown); the smallest reversal must span 20 of its steps.
    levels : int
        Speeds of the staircase (2 to 20).
    blocks : int
        Pre-sliding blocks (1 to 100), each with 5 dwelling reversals.
    dwell : float
        Rest [s] after each small reversal.
    force_fraction : float
        Share of the force limit used to accelerate (the rest is left to friction and the controller).
    ramp : float
        Shortest speed ramp [s]: the acceleration stays within the bandwidth of the position loop
        (which must follow it) and of the identification's low-pass filter.
    rotary : bool
        A rotary axis (rad, rad/s, N m, kg m^2).
    stribeck_speed : (float, float), optional
        The range ``(lo, hi)`` [m/s] the Stribeck speed ``vs`` is expected in, ``0 < lo <= hi < speed / 3``:
        the staircase covers a third of ``lo`` to three times ``hi`` (levels at most a factor 1.6 apart).

    Returns
    -------
    Experiment
    """
    if not isinstance(rotary, bool):
        raise TypeError(f"rotary: expected True or False, found {type(rotary).__name__} {rotary!r}")
    axis = AxisSpec(kind="rotary" if rotary else "linear")
    L, V = axis.length_unit, axis.unit("m/s")
    stroke, speed, force, mass = (_positive(n, v) for n, v in
                                  (("stroke", stroke), ("speed", speed), ("force", force), ("mass", mass)))
    dt = _positive("dt", dt, 1.0)
    travel, dwell, ramp = _positive("travel", travel), _positive("dwell", dwell), _positive("ramp", ramp)
    force_fraction = _positive("force_fraction", force_fraction, 1.0)
    if isinstance(resolution, bool) or not isinstance(resolution, (int, float)) or not 0 <= resolution < travel:
        raise ValueError(f"resolution: expected a number >= 0 and below travel = {travel:g} {L}, found {resolution!r}")
    for name, value, low, high in (("levels", levels, 2, 20), ("blocks", blocks, 1, 100)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
            raise ValueError(f"{name}: expected an integer in [{low}, {high}], found {value!r}")
    if stroke < 6.0 * travel:
        raise ValueError(f"stroke: expected at least 6 travel = {6 * travel:g} {L} (the pre-sliding blocks), "
                         f"found {stroke!r}")
    if stribeck_speed is not None:
        try:
            vs_lo, vs_hi = (float(v) for v in stribeck_speed)
        except (TypeError, ValueError):
            vs_lo = vs_hi = math.nan
        if not (0.0 < vs_lo <= vs_hi < speed / 3.0):
            raise ValueError(f"stribeck_speed: expected (lo, hi) with 0 < lo <= hi < speed / 3 = {speed / 3.0:.4g} "
                             f"{V}, found {stribeck_speed!r}")
    acc = force_fraction * force / mass
    half = 0.5 * stroke
    b = _Builder(dt, acc, ramp)
    b.move(-0.4 * stroke, speed)
    b.hold(dwell)
    floor = max(3.0 * travel / 5.0, 20.0 * resolution)  # 3 travel in 5 s, 20 encoder steps a second
    low = min(speed, max(speed / 300.0, floor))
    grid = np.geomspace(low, speed, levels)
    if stribeck_speed is not None:  # levels at most 1.6 apart from lo / 3 to 3 hi, merged with the grid
        c_lo, c_hi = max(vs_lo / 3.0, min(floor, speed)), 3.0 * vs_hi
        steps = max(3, int(math.ceil(math.log(c_hi / c_lo) / math.log(1.6))) + 1) if c_hi > c_lo else 1
        grid = np.concatenate([np.geomspace(c_lo, c_hi, steps), grid[grid > 1.6 * c_hi]])
    speeds = tuple(float(v) for v in grid)
    lo_h, hi_h = 0.0, 1.0  # each level held up to 1 s and over at least 3 travel; one direction within 0.6 stroke
    for _ in range(60):
        mid = 0.5 * (lo_h + hi_h)
        lo_h, hi_h = (mid, hi_h) if sum(max(v * mid, 3.0 * travel) for v in speeds) <= 0.6 * stroke else (lo_h, mid)
    reach = [max(v * lo_h, 3.0 * travel) for v in speeds]
    if sum(reach) > 0.6 * stroke * (1 + 1e-9):
        raise ValueError(f"stroke: expected at least {sum(reach) / 0.6:.4g} {L} for {len(speeds)} speed levels of at "
                         f"least 3 travel each (travel = {travel:g} {L}), found {stroke:g}; use fewer levels or a "
                         "smaller travel")
    for sign in (1.0, -1.0):  # the staircase: level to level while sliding (the mass accelerates in gross sliding)
        for v, d in zip(speeds, reach):
            b.ramp(sign * v)
            b.cruise(d / v)
        b.ramp(0.0)
        b.hold(dwell)
    staircase_end = len(b.v)
    b.move(-b.position() - travel, speed)  # the blocks run from -travel to +travel
    b.hold(dwell)
    amps = tuple(float(a) for a in np.geomspace(max(0.1 * travel, 20.0 * resolution), travel, _REVERSALS_PER_BLOCK))
    slow = min(speed, 10.0 * travel)  # pre-sliding moves: at most 10 travel per second
    for _ in range(blocks):
        centre = b.position()
        b.move(2.0 * travel, slow)
        b.hold(dwell)
        sign = -1.0
        for a in amps:
            b.move(sign * a, slow)
            b.hold(dwell)
            sign = -sign
        b.move(centre - b.position(), slow)
        b.hold(dwell)
    x, v = b.arrays()
    if float(np.max(np.abs(x))) > half * (1 + 1e-9):
        raise ValueError(f"stroke: the experiment needs {float(np.max(np.abs(x))) * 2:.4g} {L}, found {stroke:g}")
    acc = min(acc, float(np.max(np.abs(np.diff(v)))) / dt)
    resolved = resolution == 0 or amps[0] >= 20 * resolution
    expected = {
        "m": {"identifiable": True, "why": f"{2 * len(speeds) + 2} speed ramps in gross sliding, peak acceleration "
                                           f"{acc:.3g} {axis.unit('m/s^2')}"},
        "sigma": {"identifiable": True, "why": f"speeds {speeds[0]:.3g} to {speeds[-1]:.3g} {V} "
                                               f"(ratio {speeds[-1] / speeds[0]:.3g}) in both directions"},
        "Cf": {"identifiable": True, "why": f"{len(speeds)} constant-speed strokes per direction"},
        "offset": {"identifiable": True, "why": "the same speeds in both directions"},
        "s": {"identifiable": bool(resolved and blocks * _REVERSALS_PER_BLOCK >= 20),
              "why": f"{blocks * _REVERSALS_PER_BLOCK} dwelling reversals of {amps[0]:.3g} to {amps[-1]:.3g} {L} "
                     f"(1/s between {amps[0]:.3g} and {travel:.3g} {L} resolved; 20 needed"
                     + ("" if resolved else f"; the smallest spans fewer than 20 encoder steps of {resolution:g} {L}")
                     + ")"},
    }
    expected["timing"] = {"identifiable": False, "why": _TIMING_WHY}
    limits = {"stroke": stroke, "speed": speed, "force": force, "mass": mass, "acceleration": acc, "ramp": ramp,
              "travel": travel, "dwell": dwell, "resolution": float(resolution)}
    if stribeck_speed is not None:
        limits["stribeck_speed"] = [vs_lo, vs_hi]
        below, above = sum(v <= vs_lo for v in speeds), sum(v >= 2.0 * vs_hi for v in speeds)
        ok = below >= 2 and above >= 2
        why = (f"{below} levels at or below vs = {vs_lo:.3g} {V} (the drop), {above} at or above 2 x {vs_hi:.3g} "
               f"{V} (its end); 2 of each needed" + ("" if ok else f": the slowest level {speeds[0]:.3g} {V} is held "
                                                      f"above a third of lo by the travel or the encoder")
               + f"; identify with --stribeck on --min-speed {0.5 * speeds[0]:.3g}")
        expected["Fs"] = {"identifiable": ok, "why": why}
        expected["vs"] = {"identifiable": ok, "why": why}
    return Experiment(dt=dt, x_ref=x, v_ref=v, staircase_end=staircase_end, levels=speeds, amplitudes=amps,
                      reversals_dwelling=blocks * _REVERSALS_PER_BLOCK, expected=expected, limits=limits,
                      rotary=rotary)
