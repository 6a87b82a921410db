"""Units of a logged record: the scale of each column to SI, the axis kind, plausibility checks.

A log names its units per column: time in ``s``, ``ms`` or ``us``; position in ``m``, ``mm``,
``um``, encoder ``counts`` (with a resolution per count) or ``rad`` (a rotary axis); the input
in ``V``, ``A``, ``N`` or ``N m`` with a gain to force (or torque). Inside, everything is SI:
a linear axis in m, kg, N; a rotary one in rad, kg m^2, N m (the same equations, with inertia
for mass and torque for force). :class:`Units` holds the choice, :func:`check_plausible`
names the likely unit error of a record whose numbers do not fit a servo axis.

Examples
--------
>>> u = Units(time="ms", position="mm", input="A")
>>> u.time_scale, u.position_scale, u.axis, u.force_unit
(0.001, 0.001, 'linear', 'N')
>>> Units(position="counts", resolution=2 * 3.141592653589793 / 4096, rotary=True).describe()
'time s, position counts (0.00153398 rad/count), input N m; rotary axis (inertia kg m^2, torque N m)'
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..axis import INPUT_UNITS, AxisSpec, AxisWords

__all__ = ["Units", "TIME_UNITS", "POSITION_UNITS", "INPUT_UNITS", "check_plausible", "PLAUSIBLE"]

#: Time units and their factor to seconds.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
#: Position units and their factor to m (rad for ``rad``); ``counts`` takes the resolution.
POSITION_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "rad": 1.0, "counts": None}
# INPUT_UNITS (the logged input's units; ``N`` and ``N m`` are force and torque themselves, gain 1 by
# default) is the config's one list, :data:`obsdesign.axis.INPUT_UNITS`.
#: Plausible ranges (SI) of a servo axis record; outside, :func:`check_plausible` warns.
PLAUSIBLE = {"sample_time": (1e-6, 0.02), "position_range": (1e-7, 5.0), "speed": (0.0, 10.0),
             "mass": (1e-4, 1000.0)}


def _choice(param: str, value: object, choices) -> str:
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{param}: expected one of {', '.join(repr(c) for c in choices)}, found {value!r}")
    return value


@dataclass(frozen=True, kw_only=True)
class Units(AxisWords):
    """The units of a log's columns.

    Attributes
    ----------
    time : {'s', 'ms', 'us'}
    position : {'m', 'mm', 'um', 'counts', 'rad'}
        ``rad`` makes the axis rotary; ``counts`` needs ``resolution``.
    input : {'V', 'A', 'N', 'N m'} or None
        The logged input's unit; ``None``: ``N`` (``N m`` rotary) when the gain is 1, else ``V``
        (the package's former convention, reported as assumed).
    resolution : float or None
        Size of one encoder count [m, or rad with ``rotary``]; only with ``position='counts'``.
    rotary : bool
        A rotary axis (position in rad, inertia in kg m^2, torque in N m). Implied by ``rad``.
    """

    time: str = "s"
    position: str = "m"
    input: str | None = None
    resolution: float | None = None
    rotary: bool = False

    def __post_init__(self) -> None:
        _choice("time_unit", self.time, TIME_UNITS)
        _choice("position_unit", self.position, POSITION_UNITS)
        if self.input is not None:
            _choice("input_unit", self.input, INPUT_UNITS)
        if not isinstance(self.rotary, bool):
            raise TypeError(f"rotary: expected True or False, found {type(self.rotary).__name__} {self.rotary!r}")
        if self.position == "rad":
            object.__setattr__(self, "rotary", True)
        if self.position in ("m", "mm", "um") and self.rotary:
            raise ValueError(f"rotary: expected a rotary position unit ('rad' or 'counts'), found position_unit "
                             f"{self.position!r} with rotary=True")
        if self.position == "counts":
            res = self.resolution
            if isinstance(res, bool) or not isinstance(res, (int, float)) or not (math.isfinite(res) and res > 0):
                raise ValueError(f"resolution: expected the size of one count > 0 [{self.length_unit}] with "
                                 f"position_unit 'counts', found {res!r}")
            object.__setattr__(self, "resolution", float(res))
        elif self.resolution is not None:
            raise ValueError(f"resolution: expected None unless position_unit is 'counts', found {self.resolution!r} "
                             f"with position_unit {self.position!r}")
        if self.input is not None and self.input in ("N", "N m") and self.input != self.force_unit:
            raise ValueError(f"input_unit: expected {self.force_unit!r} (or V, A) for a {self.axis} axis, found "
                             f"{self.input!r}")

    @property
    def axis(self) -> str:
        """``'rotary'`` or ``'linear'``."""
        return "rotary" if self.rotary else "linear"

    @property
    def time_scale(self) -> float:
        """Seconds per logged time unit."""
        return TIME_UNITS[self.time]

    @property
    def position_scale(self) -> float:
        """SI length (m or rad) per logged position unit."""
        return self.resolution if self.position == "counts" else POSITION_UNITS[self.position]

    def input_unit(self, gain: float) -> str:
        """The logged input's unit, with the default of :attr:`input` for ``gain``."""
        if self.input is not None:
            return self.input
        return self.force_unit if gain == 1.0 else "V"

    def axis_spec(self, gain: float) -> AxisSpec:
        """The config's ``[axis]`` table of this log: the axis kind and the input unit for ``gain``.

        >>> Units(position="rad", input="A").axis_spec(0.3)
        AxisSpec(kind='rotary', input='A')
        """
        return AxisSpec(kind=self.axis, input=self.input_unit(gain))

    def describe(self, gain: float = 1.0) -> str:
        """One line: the unit of each column and the axis kind."""
        pos = self.position
        if pos == "counts":
            pos += f" ({self.resolution:.6g} {self.length_unit}/count)"
        kind = ("rotary axis (inertia kg m^2, torque N m)" if self.rotary else "linear axis (mass kg, force N)")
        return f"time {self.time}, position {pos}, input {self.input_unit(gain)}; {kind}"

    def si(self, name: str) -> str:
        """SI unit of an identified quantity ``m, sigma, Cf, offset, Fs, vs, speed, length``."""
        L, F = self.length_unit, self.force_unit
        return {"m": self.mass_unit, "sigma": f"{F} s/{L}", "Cf": F, "offset": F, "Fs": F, "vs": f"{L}/s",
                "speed": f"{L}/s", "length": L, "force": F}[name]


def check_plausible(units: Units, *, sample_time: float | None = None, position_range: float | None = None,
                    speed: float | None = None, mass: float | None = None) -> tuple[str, ...]:
    """One sentence per value outside :data:`PLAUSIBLE`, naming the likely unit error.

    The ranges are those of a servo axis (linear; for a rotary axis the position range is
    taken up to 1e4 rad and the speed up to 1e3 rad/s): a sample time in [1 us, 20 ms], a
    position range in [0.1 um, 5 m], a peak speed up to 10 m/s, a mass in [0.1 g, 1 t].

    Parameters
    ----------
    units : Units
        The log's units (the guesses depend on them).
    sample_time, position_range, speed, mass : float, optional
        SI values to check [s, m or rad, m/s or rad/s, kg or kg m^2].

    Examples
    --------
    >>> check_plausible(Units(), sample_time=0.5, mass=1733.0 * 1000)[0]
    'sample time 0.5 s is long for a servo log (expected 1e-06 to 0.02 s): is the time column in ms (--time-unit ms)?'
    """
    out = []
    rot = units.rotary
    if sample_time is not None and not PLAUSIBLE["sample_time"][0] <= sample_time <= PLAUSIBLE["sample_time"][1]:
        low, high = PLAUSIBLE["sample_time"]
        guess = ("is the time column in ms (--time-unit ms)?" if sample_time > high and units.time == "s"
                 else "is the time column in us (--time-unit us)?" if sample_time > high
                 else "is the time column in s read with a smaller unit (--time-unit)?")
        out.append(f"sample time {sample_time:.6g} s is {'long' if sample_time > high else 'short'} for a servo log "
                   f"(expected {low:g} to {high:g} s): {guess}")
    if position_range is not None:
        low, high = PLAUSIBLE["position_range"]
        high = 1e4 if rot else high
        if position_range > high:
            out.append(f"position range {position_range:.6g} {units.length_unit} is larger than an axis's stroke "
                       f"(expected up to {high:g}): is the position in mm, um or counts (--position-unit)?")
        elif position_range < low:
            out.append(f"position range {position_range:.3g} {units.length_unit} is below 0.1 um: is the position "
                       f"in m read with a smaller unit (--position-unit), or does the axis not move?")
    if speed is not None and speed > (1e3 if rot else PLAUSIBLE["speed"][1]):
        out.append(f"peak speed {speed:.6g} {units.length_unit}/s is implausible for a servo axis: check the "
                   f"position unit (--position-unit) and the time unit (--time-unit)")
    if mass is not None and mass > 0 and not PLAUSIBLE["mass"][0] <= mass <= PLAUSIBLE["mass"][1]:
        low, high = PLAUSIBLE["mass"]
        why = ("a time in ms read as s makes it 1e6 x too large, a position in mm read as m 1000 x too small, "
               "both together 1000 x too large"
               if mass > high else "a position in mm read as m makes it 1000 x too small, a time in s read as ms "
               "1e6 x too small")
        out.append(f"identified {'inertia' if rot else 'mass'} {mass:.6g} {units.mass_unit} is outside "
                   f"{low:g} to {high:g}: check the units ({why}; --time-unit, --position-unit, --input-gain)")
    return tuple(out)
