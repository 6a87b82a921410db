"""One home for input validation: ranges, choices, text, integers and number parsing.

Every public entry point of the package checks its arguments with these rules,
so a bad value always gets the same kind of message: the parameter's name, what
was expected and what was found (python-control's style)::

    observer.rho: expected a finite number > 0, found 0.0

``ValueError`` is raised for a bad value, ``TypeError`` for a bad type. NumPy
scalars are accepted where a Python number is; an integer too large for a float
is a ``ValueError``, not an ``OverflowError``.

Examples
--------
>>> POSITIVE.check("rho", 4)
4.0
>>> POSITIVE.check("rho", 0.0)
Traceback (most recent call last):
...
ValueError: rho: expected a finite number > 0, found 0.0
>>> check_choice("stiffness", "guess", ("estimated", "true"))
Traceback (most recent call last):
...
ValueError: stiffness: expected one of estimated, true, found 'guess'
>>> check_integer("samples", 0, minimum=1)
Traceback (most recent call last):
...
ValueError: samples: expected an integer >= 1, found 0
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from typing import Any, Mapping

__all__ = [
    "Range", "Choice", "Text", "Integer", "POSITIVE", "NONNEGATIVE", "FINITE", "SAMPLE_TIME",
    "check_choice", "check_integer", "parse_number", "as_float", "FrozenMap",
    "param_field", "validate_fields", "document_fields", "section_from_table",
]


def as_float(name: str, value: Any, expected: str) -> float:
    """``value`` as a float if it is a real number (Python or NumPy, not bool), else ``TypeError``.

    >>> import numpy as np
    >>> as_float("rho", np.int64(4), "a number")
    4.0
    >>> as_float("rho", 10**400, "a finite number")
    Traceback (most recent call last):
    ...
    ValueError: rho: expected a finite number, found an integer of 401 digits
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: expected {expected}, found {type(value).__name__} {value!r}")
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name}: expected {expected}, found an integer of {len(str(abs(int(value))))} digits") from None


@dataclass(frozen=True)
class Range:
    """Admissible range of a numeric value; ``None`` bounds are open-ended."""

    low: float | None = None
    high: float | None = None
    low_inclusive: bool = False
    high_inclusive: bool = False
    optional: bool = False

    def describe(self) -> str:
        """The expectation in words, e.g. ``'a finite number > 0'``."""
        parts = []
        if self.low is not None:
            parts.append(f"{'>=' if self.low_inclusive else '>'} {self.low:g}")
        if self.high is not None:
            parts.append(f"{'<=' if self.high_inclusive else '<'} {self.high:g}")
        text = "a finite number" + (" " + " and ".join(parts) if parts else "")
        return text + (" (or omitted)" if self.optional else "")

    def contains(self, number: float) -> bool:
        """Whether a float lies in the range (finite and within the bounds)."""
        ok = math.isfinite(number)
        if ok and self.low is not None:
            ok = number >= self.low if self.low_inclusive else number > self.low
        if ok and self.high is not None:
            ok = number <= self.high if self.high_inclusive else number < self.high
        return ok

    def check(self, name: str, value: Any) -> float | None:
        """``value`` as a float in the range, or a ``ValueError``/``TypeError`` naming ``name``."""
        if value is None and self.optional:
            return None
        number = as_float(name, value, self.describe())
        if not self.contains(number):
            raise ValueError(f"{name}: expected {self.describe()}, found {number!r}")
        return number


@dataclass(frozen=True)
class Choice:
    """One of a fixed set of strings."""

    options: tuple[str, ...]

    def describe(self) -> str:
        return "one of " + ", ".join(repr(o) for o in self.options)

    def check(self, name: str, value: Any) -> str:
        if not isinstance(value, str):
            raise TypeError(f"{name}: expected {self.describe()}, found {type(value).__name__} {value!r}")
        if value not in self.options:
            raise ValueError(f"{name}: expected {self.describe()}, found {value!r}")
        return value


@dataclass(frozen=True)
class Text:
    """Any string."""

    def describe(self) -> str:
        return "a string"

    def check(self, name: str, value: Any) -> str:
        if not isinstance(value, str):
            raise TypeError(f"{name}: expected a string, found {type(value).__name__} {value!r}")
        return value


@dataclass(frozen=True)
class Integer:
    """An integer within ``[minimum, maximum]`` (``None``: open-ended), checked by :func:`check_integer`.

    >>> Integer(minimum=0).check("hardware.delay_samples", -1)
    Traceback (most recent call last):
    ...
    ValueError: hardware.delay_samples: expected an integer >= 0, found -1
    """

    minimum: int | None = None
    maximum: int | None = None

    def describe(self) -> str:
        bounds = [f">= {self.minimum}"] if self.minimum is not None else []
        bounds += [f"<= {self.maximum}"] if self.maximum is not None else []
        return "an integer" + (" " + " and ".join(bounds) if bounds else "")

    def check(self, name: str, value: Any) -> int:
        return check_integer(name, value, minimum=self.minimum, maximum=self.maximum)


POSITIVE = Range(low=0.0)
NONNEGATIVE = Range(low=0.0, low_inclusive=True)
FINITE = Range()
#: Usable sample times [s], one rule for a controller's ``dt`` (simulate, check, every export) and a
#: measured record's time base: below 1 ps the derivative 1/dt of an error overflows or the record is
#: in the wrong unit; above 1 s the controller cannot hold a precision axis (and the unit is wrong).
SAMPLE_TIME = Range(low=1e-12, high=1.0, low_inclusive=True, high_inclusive=True)


# Ceilings of sizes and counts (docs/cli.md, "Limits"): far beyond any precision axis, low enough that a
# value past them is a unit or typing mistake, not a design, and that nothing allocates without bound.
#: Largest speed [m/s, or rad/s on a rotary axis] a velocity parameter or table may hold.
MAX_SPEED = 1e3
#: Largest force [N, or N m] a compensation parameter may hold.
MAX_FORCE = 1e6
#: Largest distance [m] (a build-up, a stroke).
MAX_DISTANCE = 1e3
#: Largest computation or drive delay [samples] (1 s at 10 kHz); the delay line holds this many values.
MAX_DELAY_SAMPLES = 10_000
#: Most bootstrap replicates of ``identify`` (each refits every stage on a resampled record).
MAX_BOOTSTRAP = 100_000
#: Largest CSV record read [bytes] (held in memory as text, then as floats: about 3 times this).
MAX_CSV_BYTES = 2**30
#: Longest CSV line [characters] (a thousand columns of 100 characters); a longer one is not a record.
MAX_CSV_LINE = 100_000
SPEED = Range(low=0.0, high=MAX_SPEED, low_inclusive=True, high_inclusive=True)
FORCE = Range(low=-MAX_FORCE, high=MAX_FORCE, low_inclusive=True, high_inclusive=True)
NONNEGATIVE_FORCE = Range(low=0.0, high=MAX_FORCE, low_inclusive=True, high_inclusive=True)
DISTANCE = Range(low=0.0, high=MAX_DISTANCE, low_inclusive=True, high_inclusive=True)
#: The PID's derivative filter ratio N (its time constant is (kd/kp)/N).
DERIVATIVE_N = Range(low=0.1, high=1e4, low_inclusive=True, high_inclusive=True)
#: A friction table's largest velocity [m/s or rad/s].
V_MAX = Range(low=0.0, high=MAX_SPEED, high_inclusive=True)
#: A drive's force per current [N/A or N m/A]: beyond 1e-6 to 1e6 the current column is a unit mistake.
MOTOR_CONSTANT = Range(low=1e-6, high=1e6, low_inclusive=True, high_inclusive=True)


def check_choice(name: str, value: Any, options) -> str:
    """``value`` if it is one of ``options`` (strings), else a ``ValueError`` listing them."""
    options = tuple(options)
    if not isinstance(value, str) or value not in options:
        raise ValueError(f"{name}: expected one of {', '.join(options)}, found {value!r}")
    return value


def check_integer(name: str, value: Any, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """``value`` as an int (Python or NumPy integer, not bool) within ``[minimum, maximum]``.

    >>> check_integer("chunk", 8, minimum=1, maximum=100)
    8
    >>> check_integer("chunk", 2.5, minimum=1)
    Traceback (most recent call last):
    ...
    ValueError: chunk: expected an integer >= 1, found 2.5
    """
    bounds = []
    if minimum is not None:
        bounds.append(f">= {minimum}")
    if maximum is not None:
        bounds.append(f"<= {maximum}")
    expected = "an integer" + (" " + " and ".join(bounds) if bounds else "")
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name}: expected {expected}, found {value!r}")
    value = int(value)
    if (minimum is not None and value < minimum) or (maximum is not None and value > maximum):
        raise ValueError(f"{name}: expected {expected}, found {value!r}")
    return value


def parse_number(text: str, what: str, rule: Range = FINITE, unit: str = "") -> float:
    """Parse a number typed by a user; the message names ``what`` and quotes the text.

    >>> parse_number("2.5", "--vary rho")
    2.5
    >>> parse_number("abc", "--rho", POSITIVE)
    Traceback (most recent call last):
    ...
    ValueError: --rho: expected a finite number > 0, found 'abc'
    """
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected {rule.describe()}{unit}, found {text!r}") from None
    if not rule.contains(value):
        raise ValueError(f"{what}: expected {rule.describe()}{unit}, found {text!r}")
    return value


class FrozenMap(Mapping):
    """A read-only mapping for frozen config objects (picklable, unlike ``types.MappingProxyType``).

    >>> m = FrozenMap({"plant.m": "paper"})
    >>> m["plant.m"], len(m), dict(m)
    ('paper', 1, {'plant.m': 'paper'})
    """

    def __init__(self, data) -> None:
        self._data = dict(data)

    def __getitem__(self, key):
        return self._data[key]

    def __iter__(self):
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        return repr(self._data)


def param_field(check, unit: str, doc: str, default: Any = dataclasses.MISSING):
    """A dataclass field carrying its validation rule, unit and description (its one definition).

    Parameters
    ----------
    check : Range, Choice, Text or another rule with ``check(name, value)``
        Applied by :func:`validate_fields`.
    unit : str
        Unit for messages, TOML comments and the generated docstring.
    doc : str
        One-line description.
    default : object, optional
        The field's default (required when left out).
    """
    return dataclasses.field(default=default, metadata={"check": check, "unit": unit, "doc": doc})


def validate_fields(obj: Any) -> None:
    """Check (and normalise) every :func:`param_field` of ``obj`` in place; ``obj._section`` names it.

    Parameters
    ----------
    obj : dataclass instance
        A frozen section dataclass, from its ``__post_init__``.
    """
    for f in dataclasses.fields(obj):
        rule = f.metadata.get("check")
        if rule is not None:
            object.__setattr__(obj, f.name, rule.check(f"{obj._section}.{f.name}", getattr(obj, f.name)))


def section_from_table(cls: type, table: Any) -> Any:
    """Build the :func:`param_field` dataclass ``cls`` (its ``_section`` names it) from a parsed TOML table.

    Unknown keys and missing required keys are a ``ValueError`` naming ``section.key``; the values are
    checked by the class's own validation.

    >>> from obsdesign.axis import AxisSpec
    >>> section_from_table(AxisSpec, {"kind": "rotary", "unit": "A"})
    Traceback (most recent call last):
    ...
    ValueError: axis.unit: unknown key; expected one of input, kind
    """
    key = cls._section
    if not isinstance(table, Mapping):
        raise TypeError(f"{key}: expected a table, found {type(table).__name__} {table!r}")
    names = {f.name for f in dataclasses.fields(cls)}
    bad = sorted(set(table) - names)
    if bad:
        raise ValueError(f"{key}.{bad[0]}: unknown key; expected one of {', '.join(sorted(names))}")
    for f in dataclasses.fields(cls):
        required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        if required and f.name not in table:
            raise ValueError(f"{key}.{f.name}: required key is missing ({f.metadata['doc']})")
    return cls(**table)


def document_fields(cls: type) -> type:
    """Insert a numpydoc ``Attributes`` section built from the :func:`param_field` metadata of ``cls``.

    Parameters
    ----------
    cls : type
        A dataclass; its docstring gets the section before ``Examples`` (or at the end).

    Examples
    --------
    >>> @document_fields
    ... @dataclass(frozen=True)
    ... class Axis:
    ...     'An axis.'
    ...     m: float = param_field(POSITIVE, "kg", "moving mass", 1.0)
    >>> print(Axis.__doc__.rstrip())
    An axis.
    <BLANKLINE>
        Attributes
        ----------
        m : float
            Moving mass [kg].
    """
    rows = [f"    {f.name} : {f.type}\n        {f.metadata['doc'][:1].upper()}{f.metadata['doc'][1:]} [{f.metadata['unit']}]."
            for f in dataclasses.fields(cls) if "doc" in f.metadata]
    section = "    Attributes\n    ----------\n" + "\n".join(rows) + "\n\n"
    doc = cls.__doc__ or ""
    at = doc.find("    Examples\n")
    cls.__doc__ = doc[:at] + section + doc[at:] if at >= 0 else doc.rstrip() + "\n\n" + section
    return cls
