"""Units of a logged record: each column's unit by pint, its scale to SI, the axis kind, plausibility.

A log names its units per column, in any unit expression that `pint <https://pint.readthedocs.io>`__
(the units library of scientific Python) parses and whose dimension fits the column: time (``s``,
``ms``, ``us``, ``min``), position as a length (``m``, ``mm``, ``µm``, ``inch``), an angle (``rad``,
``deg``, ``rev``: a rotary axis) or encoder ``counts`` (with a resolution per count), the input
as a current (``A``, ``mA``), a voltage (``V``), a force (``N``, ``kN``, ``lbf``), a torque (``N m``,
``mN m``; a rotary axis) or a fraction (``%``, ``permille``) of a rated current or torque given
with ``rated``. Inside, everything is SI: a linear axis in m, kg, N; a rotary one in rad,
kg m^2, N m (the same equations, with inertia for mass and torque for force); the logged input is
taken to the SI unit of its kind (A, V, N or N m), which the input gain multiplies.
:class:`Units` holds the choice, :func:`check_plausible` names the likely unit error of a record
whose numbers do not fit a servo axis.

Examples
--------
>>> u = Units(time="ms", position="mm", input="A")
>>> u.time_scale, u.position_scale, u.axis, u.force_unit
(0.001, 0.001, 'linear', 'N')
>>> Units(position="counts", resolution=2 * 3.141592653589793 / 4096, rotary=True).describe()
'time s, position counts (0.00153398 rad/count), input N m; rotary axis (inertia kg m^2, torque N m)'
>>> deg = Units(position="deg", input="mA")
>>> deg.axis, round(deg.position_scale, 12), deg.input_scale, deg.input_unit(0.2)
('rotary', 0.01745329252, 0.001, 'A')
>>> Units(input="%", rated="2.5 A").input_scale
0.025
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from functools import cache

from ..axis import INPUT_UNITS, AxisSpec, AxisWords

__all__ = ["Units", "INPUT_UNITS", "check_plausible", "PLAUSIBLE", "parse_unit", "unit_kind", "UNIT_KINDS",
           "column_unit", "DEFAULT_UNITS", "is_unit"]

# INPUT_UNITS (the SI unit of each kind of logged input; ``N`` and ``N m`` are force and torque themselves,
# gain 1 by default) is the config's one list, :data:`obsdesign.axis.INPUT_UNITS`.
#: Plausible ranges (SI) of a servo axis record; outside, :func:`check_plausible` warns.
PLAUSIBLE = {"sample_time": (1e-6, 0.02), "position_range": (1e-7, 5.0), "speed": (0.0, 10.0),
             "mass": (1e-4, 1000.0)}
#: Kind of a unit -> its SI unit (pint's spelling) and how the messages name it. ``angle``, ``count`` and
#: ``fraction`` are dimensionless to pint; they are told apart by the root unit (radian, count, none).
UNIT_KINDS = {"time": ("s", "a time"), "length": ("m", "a length"), "angle": ("rad", "an angle"),
              "count": ("count", "a count"), "fraction": ("dimensionless", "a fraction (%)"),
              "current": ("A", "a current"), "voltage": ("V", "a voltage"), "force": ("N", "a force"),
              "torque": ("N * m", "a torque")}
#: The kinds each column accepts, in the words of the messages.
_ROLE_KINDS = {"time": ("time",), "position": ("length", "angle", "count"),
               "input": ("current", "voltage", "force", "torque", "fraction"),
               "rated": ("current", "voltage", "force", "torque")}
_ROLE_WORDS = {"time": "a time (s, ms, us, min)", "position": "a length (m, mm, um, inch), an angle (rad, deg, "
               "rev) or counts", "input": "a current (A, mA), a voltage (V), a force (N) or a torque (N m), or % "
               "of a rated value", "rated": "a current (A), a voltage (V), a force (N) or a torque (N m)"}
#: SI unit (the config's [axis] input) of each input kind.
_INPUT_SI = {"current": "A", "voltage": "V", "force": "N", "torque": "N m"}
#: ``Nm``, ``mNm``, ``kNm`` (a newton metre as drives write it; pint reads ``Nm`` as a "number metre").
_NEWTON_METRE = re.compile(r"(?<![A-Za-z])([kmuµμ]?)Nm(?![A-Za-z])")


@cache
def _registry():
    """The one pint registry of the package (built on first use: pint is imported only to read a log)."""
    import pint

    reg = pint.UnitRegistry()
    reg.define("rev = turn")  # a revolution, as drives write it
    return reg


def _normalize(text: str) -> str:
    return _NEWTON_METRE.sub(r"\1N m", text.strip().replace("\u03bc", "\u00b5"))


def parse_unit(param: str, text: object, role: str | None = None) -> tuple[str, float]:
    """The kind of the unit expression ``text`` and its factor to the kind's SI unit.

    Parameters
    ----------
    param : str
        The parameter named in an error (``'position_unit'``, ``"column 'pos'"``).
    text : str
        A unit expression pint parses (``'mm'``, ``'deg'``, ``'mN m'``, ``'%'``; ``Nm`` is a newton metre).
    role : {'time', 'position', 'input', 'rated'}, optional
        The column the unit is for: a unit of another dimension is refused naming the one expected.

    Returns
    -------
    kind : str
        A key of :data:`UNIT_KINDS`.
    factor : float
        SI units per ``text`` (``count`` and ``fraction`` are per count and per 1).

    Raises
    ------
    ValueError
        A unit pint does not know, or of a dimension the column does not take.

    Examples
    --------
    >>> parse_unit("position_unit", "µm", "position")
    ('length', 1e-06)
    >>> parse_unit("input_unit", "W", "input")
    Traceback (most recent call last):
    ...
    ValueError: input_unit: expected a current (A, mA), a voltage (V), a force (N) or a torque (N m), or % of a rated value, found 'W' (dimension [length]^2 [mass] [time]^-3)
    """
    if not isinstance(text, str):
        raise TypeError(f"{param}: expected a unit (a string such as 'mm'), found {type(text).__name__} {text!r}")
    kind, factor, dims = _classify(_normalize(text))
    if kind is None:
        expected = _ROLE_WORDS[role] if role else "a unit pint knows"
        raise ValueError(f"{param}: expected {expected}, found {text!r} ({dims})")
    if role is not None and kind not in _ROLE_KINDS[role]:
        raise ValueError(f"{param}: expected {_ROLE_WORDS[role]}, found {text!r} ({UNIT_KINDS[kind][1]})")
    return kind, factor


_UNKNOWN = "not a unit pint knows"


@cache
def _classify(text: str) -> tuple[str | None, float, str]:
    reg = _registry()
    try:
        unit = reg.parse_units(text)
    except Exception:  # noqa: BLE001 (pint raises several types for text that is not a unit)
        return None, math.nan, _UNKNOWN
    dims = unit.dimensionality
    if not dims:
        root = str(reg.get_root_units(unit)[1])
        kind = {"radian": "angle", "count": "count", "dimensionless": "fraction"}.get(root)
    else:
        kind = next((k for k, (si, _) in UNIT_KINDS.items()
                     if k not in ("angle", "count", "fraction") and dims == reg.parse_units(si).dimensionality),
                    None)
    if kind is None:
        return None, math.nan, "dimensionless, but no angle, count or fraction" if not dims else _dims_text(dims)
    factor = float(reg.Quantity(1.0, unit).to(UNIT_KINDS[kind][0]).magnitude)
    return kind, factor, _dims_text(dims)


def is_unit(text: str) -> bool:
    """Whether pint parses ``text`` as a unit (of any dimension).

    Parameters
    ----------
    text : str
        A unit expression, or any text.

    Examples
    --------
    >>> is_unit("kg"), is_unit("Position")
    (True, False)
    """
    return _classify(_normalize(text))[2] != _UNKNOWN


def _dims_text(dims) -> str:
    """``[length]^2 [mass] [time]^-3``: pint's dimensionality, sorted (its own text follows dict order)."""
    return "dimension " + " ".join(k if v == 1 else f"{k}^{v:g}" for k, v in sorted(dims.items()))


def unit_kind(text: str, role: str) -> str | None:
    """The kind of ``text`` if it is a unit of the column ``role`` (else ``None``; no error).

    Parameters
    ----------
    text : str
        A unit expression.
    role : {'time', 'position', 'input', 'rated'}
        The column.

    Examples
    --------
    >>> unit_kind("ms", "time"), unit_kind("ms", "position"), unit_kind("ref", "input")
    ('time', None, None)
    """
    kind = _classify(_normalize(text))[0]
    return kind if kind in _ROLE_KINDS[role] else None


#: The unit parameter of each column (``load_trace``'s keyword; the CLI flag is the same with dashes).
_UNIT_PARAMS = {"time": "time_unit", "position": "position_unit", "input": "input_unit"}
#: The unit of a column whose unit is neither given nor written in the file.
DEFAULT_UNITS = {"time": "s", "position": "m", "input": None}
_ROLE_EXPECTED = {"time": "a time unit", "position": "a length, an angle or counts",
                  "input": "a current, a voltage, a force, a torque or a fraction (%)"}


def column_unit(role: str, given: str | None, written: str | None, where: str,
                label: str) -> tuple[str | None, str | None]:
    """The unit of a column: the one given, else the one the file writes, else :data:`DEFAULT_UNITS`.

    Parameters
    ----------
    role : {'time', 'position', 'input'}
        The column.
    given : str or None
        The unit given (``load_trace``'s ``time_unit``, ...).
    written, where : str or None, str
        The unit the file writes for the column and where (:attr:`obsdesign.data.logfile.Channel.unit_from`);
        a name's suffix (``where='name'``) that is no unit of this column is no unit (``x_ref``).
    label : str
        The column as messages name it (``"column 'pos'"``).

    Returns
    -------
    unit : str or None
    warning : str or None
        Where a unit given overrides a different one the file writes.

    Examples
    --------
    >>> column_unit("position", None, "deg", "header", "column 'pos'")
    ('deg', None)
    >>> column_unit("input", None, "max", "name", "column 'u_max'")
    (None, None)
    >>> column_unit("time", None, "kg", "units row", "column 't'")
    Traceback (most recent call last):
    ...
    ValueError: time: expected a time unit for column 't', found the unit 'kg' (dimension [mass]) in the file's units row; give time_unit (--time-unit)
    """
    param = _UNIT_PARAMS[role]
    if written is not None and where == "name" and unit_kind(written, role) is None:
        written = None
    if given is not None:
        if written is None:
            return given, None
        try:
            same = parse_unit(param, written, role) == parse_unit(param, given, role)
        except ValueError:
            same = False
        note = None if same else (f"{param}: {given!r} given overrides the unit {written!r} that the file writes "
                                  f"for {label} (from its {where})")
        return given, note
    if written is None:
        return DEFAULT_UNITS[role], None
    try:
        parse_unit(param, written, role)
    except ValueError as e:
        found = str(e).split(", found ", 1)[-1]
        raise ValueError(f"{role}: expected {_ROLE_EXPECTED[role]} for {label}, found the unit {found} in the "
                         f"file's {where}; give {param} (--{param.replace('_', '-')})") from None
    return written, None


@dataclass(frozen=True, kw_only=True)
class Units(AxisWords):
    """The units of a log's columns.

    Attributes
    ----------
    time : str
        A time unit (``'s'``, ``'ms'``, ``'us'``, ``'min'``, ...).
    position : str
        A length (``'m'``, ``'mm'``, ``'µm'``, ``'inch'``), an angle (``'rad'``, ``'deg'``, ``'rev'``: the
        axis is rotary) or ``'counts'`` (needs ``resolution``).
    input : str or None
        The logged input's unit: a current, voltage, force or torque (``'mA'``, ``'V'``, ``'N'``,
        ``'mN m'``), or a fraction (``'%'``) of ``rated``. ``None``: ``N`` (``N m`` rotary) when the
        gain is 1, else ``V`` (the package's former convention, reported as assumed).
    resolution : float or None
        Size of one encoder count [m, or rad with ``rotary``]; only with a position in counts.
    rotary : bool
        A rotary axis (position in rad, inertia in kg m^2, torque in N m). Implied by an angle or a
        torque.
    rated : str or None
        The rated value that a fractional input (``%``) is a fraction of: a current or torque
        (``'2.5 A'``, ``'1.2 N m'``); only with such an input.
    time_scale, position_scale, input_scale : float
        Seconds per time unit, m (rad) per position unit, SI input units (A, V, N, N m) per
        logged input unit (derived).
    """

    time: str = "s"
    position: str = "m"
    input: str | None = None
    resolution: float | None = None
    rotary: bool = False
    rated: str | None = None
    time_scale: float = field(init=False, repr=False)
    position_scale: float = field(init=False, repr=False)
    input_scale: float = field(init=False, repr=False)
    _input_si: str | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.rotary, bool):
            raise TypeError(f"rotary: expected True or False, found {type(self.rotary).__name__} {self.rotary!r}")
        _, time_scale = parse_unit("time_unit", self.time, "time")
        pos_kind, pos_scale = parse_unit("position_unit", self.position, "position")
        in_kind, in_scale = (None, 1.0) if self.input is None else parse_unit("input_unit", self.input, "input")
        rated_kind = None
        if self.rated is not None:
            rated_kind, rated_scale = self._rated()
            if in_kind != "fraction":
                raise ValueError(f"rated: expected only with an input in % (or another fraction) of it, found "
                                 f"rated {self.rated!r} with input_unit {self.input!r}")
            in_kind, in_scale = rated_kind, in_scale * rated_scale
        elif in_kind == "fraction":
            raise ValueError(f"rated: expected the rated value that the input in {self.input!r} is a fraction of "
                             f"(rated='2.5 A', --rated 2.5 A), found none")
        rotary = self.rotary or pos_kind == "angle" or in_kind == "torque"
        object.__setattr__(self, "rotary", rotary)
        if pos_kind == "length" and rotary:
            why = "rotary=True" if self.rotary else f"a torque input ({self.input!r})"
            raise ValueError(f"rotary: expected a rotary position unit (an angle or counts), found position_unit "
                             f"{self.position!r} (a length) with {why}")
        if pos_kind == "count":
            res = self.resolution
            if isinstance(res, bool) or not isinstance(res, (int, float)) or not (math.isfinite(res) and res > 0):
                raise ValueError(f"resolution: expected the size of one count > 0 [{self.length_unit}] with "
                                 f"position_unit {self.position!r}, found {res!r}")
            object.__setattr__(self, "resolution", float(res))
            pos_scale *= float(res)
        elif self.resolution is not None:
            raise ValueError(f"resolution: expected None unless the position is in counts, found {self.resolution!r} "
                             f"with position_unit {self.position!r}")
        si = None if in_kind is None else _INPUT_SI[in_kind]
        if si in ("N", "N m") and si != self.force_unit:
            raise ValueError(f"input_unit: expected {self.force_unit!r} (or V, A) for a {self.axis} axis, found "
                             f"{self.input!r} ({UNIT_KINDS[in_kind][1]})")
        for name, value in (("time_scale", time_scale), ("position_scale", pos_scale), ("input_scale", in_scale),
                            ("_input_si", si)):
            object.__setattr__(self, name, value)

    def _rated(self) -> tuple[str, float]:
        text = self.rated
        if not isinstance(text, str):
            raise TypeError(f"rated: expected a value and its unit ('2.5 A'), found {type(text).__name__} {text!r}")
        number, _, unit = text.strip().partition(" ")
        try:
            value = float(number)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0) or not unit.strip():
            raise ValueError(f"rated: expected a value > 0 and its unit ('2.5 A', '1.2 N m'), found {text!r}")
        kind, factor = parse_unit("rated", unit, "rated")
        return kind, value * factor

    @property
    def axis(self) -> str:
        """``'rotary'`` or ``'linear'``."""
        return "rotary" if self.rotary else "linear"

    def input_unit(self, gain: float) -> str:
        """The SI unit of the logged input's kind (A, V, N, N m), with the default of :attr:`input` for ``gain``."""
        if self._input_si is not None:
            return self._input_si
        return self.force_unit if gain == 1.0 else "V"

    def axis_spec(self, gain: float) -> AxisSpec:
        """The config's ``[axis]`` table of this log: the axis kind and the input unit for ``gain``.

        >>> Units(position="rad", input="A").axis_spec(0.3)
        AxisSpec(kind='rotary', input='A')
        """
        return AxisSpec(kind=self.axis, input=self.input_unit(gain))

    def describe(self, gain: float = 1.0) -> str:
        """One line: the unit of each column (and its conversion where it is not SI) and the axis kind.

        >>> Units(time="ms", position="deg", input="%", rated="2.5 A").describe(0.3)
        'time ms, position deg, input % of 2.5 A (0.025 A per %); rotary axis (inertia kg m^2, torque N m)'
        """
        pos = self.position
        if self.resolution is not None:
            pos += f" ({self.resolution:.6g} {self.length_unit}/count)"
        unit_in = self.input_unit(gain)
        text_in = unit_in if self.input is None else self.input
        if self.rated is not None:
            text_in += f" of {self.rated} ({self.input_scale:.6g} {unit_in} per {self.input})"
        kind = ("rotary axis (inertia kg m^2, torque N m)" if self.rotary else "linear axis (mass kg, force N)")
        return f"time {self.time}, position {pos}, input {text_in}; {kind}"

    def gain_unknown(self, gain: float) -> bool:
        """Whether the input is a current or voltage taken at the default gain 1 (no torque or force constant
        given): the identified values are then per that unknown constant (``m/K``, ``Cf/K``)."""
        return gain == 1.0 and self.input_unit(gain) in ("A", "V")

    def gain_note(self, gain: float) -> tuple[str, ...]:
        """One sentence when :meth:`gain_unknown`: what the identified numbers then are, and what to give.

        >>> Units(position="rad", input="A").gain_note(1.0)[0][:96]
        'input gain 1 N m/A (the default; --input-gain not given?): every torque is in A times an unknown'
        >>> Units(position="rad", input="A").gain_note(0.1)
        ()
        """
        if not self.gain_unknown(gain):
            return ()
        unit_in, F, M = self.input_unit(gain), self.force_unit, self.mass_unit
        word = AxisSpec(kind=self.axis, input=unit_in).words("force")
        return (f"input gain 1 {F}/{unit_in} (the default; --input-gain not given?): every {word} is in "
                f"{unit_in} times an unknown {word} constant K, so m, sigma, Cf and offset are m/K, sigma/K, Cf/K and "
                f"offset/K ({M} and {F} per {F}/{unit_in}; Cf/K is the {unit_in} that overcomes the Coulomb level): "
                f"right for the loop and the compensation in {unit_in}, not physical; give the {word} constant "
                f"with --input-gain K [{F}/{unit_in}]",)

    def si(self, name: str) -> str:
        """SI unit of an identified quantity ``m, sigma, Cf, offset, Fs, vs, speed, length``."""
        L, F = self.length_unit, self.force_unit
        return {"m": self.mass_unit, "sigma": f"{F} s/{L}", "Cf": F, "offset": F, "Fs": F, "vs": f"{L}/s",
                "speed": f"{L}/s", "length": L, "force": F}[name]


def check_plausible(units: Units, *, sample_time: float | None = None, position_range: float | None = None,
                    speed: float | None = None, mass: float | None = None,
                    gain: float | None = None) -> tuple[str, ...]:
    """One sentence per value outside :data:`PLAUSIBLE`, naming the likely unit error (and, with the input
    ``gain``, :meth:`Units.gain_note`: a current or voltage at the default gain 1).

    The ranges are those of a servo axis (linear; for a rotary axis the position range is
    taken up to 1e4 rad and the speed up to 1e3 rad/s): a sample time in [1 us, 20 ms], a
    position range in [0.1 um, 5 m], a peak speed up to 10 m/s, a mass in [0.1 g, 1 t].

    Parameters
    ----------
    units : Units
        The log's units (the guesses depend on them).
    sample_time, position_range, speed, mass : float, optional
        SI values to check [s, m or rad, m/s or rad/s, kg or kg m^2].
    gain : float, optional
        The input gain [N/A, N m/A, ...] of the log.

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
            L = units.length_unit
            out.append(f"position range {position_range:.3g} {L} is below {low:g} {L}: is the position "
                       f"in {L} read with a smaller unit (--position-unit), or does the axis not move?")
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
    return tuple(out) + (units.gain_note(gain) if gain is not None else ())
