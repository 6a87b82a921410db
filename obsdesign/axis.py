"""The ``[axis]`` table of a config: linear or rotary, and the unit of the actuator command.

The package computes in SI with one set of equations for both kinds of axis: a linear axis in
m, kg, N; a rotary one in rad, kg m^2 (inertia for mass), N m (torque for force). The command
to the actuator is in the ``input`` unit (V, A, N or N m); ``plant.K`` converts it to force or
torque. Every place that prints a unit asks :meth:`AxisSpec.unit` for it, written in the
linear, voltage-driven form the package's field metadata uses (``'N s/m'``, ``'m/V'``):
a linear axis driven in V prints it unchanged, so a config without ``[axis]`` (both presets,
every config written before the table existed) reads exactly as before.

Examples
--------
>>> rot = AxisSpec(kind="rotary", input="A")
>>> rot.unit("N s/m"), rot.unit("kg"), rot.unit("m/V"), rot.unit("um")
('N m s/rad', 'kg m^2', 'rad/A', 'urad')
>>> rot.label("kappa [N/m]"), rot.label("omega_co [rad/s]")
('kappa [N m/rad]', 'omega_co [rad/s]')
>>> rot.words("actuator force constant"), rot.words("actuator voltage limit (saturation)")
('actuator torque constant', 'actuator current limit (saturation)')
>>> AxisSpec().unit("N s/m")
'N s/m'
>>> AxisSpec(kind="rotary", input="N m").unit("m/V")
'rad/(N m)'
>>> AxisSpec(kind="angular")
Traceback (most recent call last):
...
ValueError: axis.kind: expected one of 'linear', 'rotary', found 'angular'
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Mapping

from ._validate import Choice, document_fields, param_field, validate_fields

__all__ = ["AxisSpec", "AxisWords", "AXIS_KINDS", "INPUT_UNITS", "INPUT_WORDS", "LINEAR"]

#: Kinds of axis.
AXIS_KINDS = ("linear", "rotary")
#: Units of the actuator command; ``N`` and ``N m`` are force and torque themselves.
INPUT_UNITS = ("V", "A", "N", "N m")
#: What a command in each input unit is (the package's texts say ``voltage``: the linear form, driven in V).
INPUT_WORDS = {"V": "voltage", "A": "current", "N": "force", "N m": "torque"}
#: Linear words of the texts and their rotary counterparts (inertia for mass, torque for force).
_ROTARY_WORDS = {"moving mass": "inertia", "mass": "inertia", "masses": "inertias", "force": "torque",
                 "forces": "torques"}
_TEXT_WORD = re.compile(r"\b(moving mass|masses|mass|forces|force|voltage)\b", re.IGNORECASE)
#: Linear unit words and their rotary counterparts (inertia for mass, torque for force, angle for length).
_ROTARY = {"kg": "kg m^2", "N": "N m", "m": "rad", "mm": "mrad", "um": "urad", "nm": "nrad"}
#: Every word a printed unit is made of; a bracket holding another word is text, left alone.
_UNIT_WORDS = frozenset(_ROTARY) | {"V", "A", "s", "ms", "us", "rad", "Hz", "deg", "dB", "samples", "counts",
                                    "mrad", "urad", "nrad"}
_WORD = re.compile(r"[A-Za-z]+")
_BRACKET = re.compile(r"\[([^\[\]]*)\]")


class AxisWords:
    """The unit names of a linear or rotary axis, from its ``rotary`` flag (a mixin of
    :class:`AxisSpec` and of the log's :class:`obsdesign.data.units.Units`).

    Examples
    --------
    >>> AxisSpec(kind="rotary").mass_unit, AxisSpec().force_word
    ('kg m^2', 'force')
    """

    @property
    def rotary(self) -> bool:
        """Whether the axis is rotary (given by the class that mixes these in)."""
        raise NotImplementedError

    @property
    def force_unit(self) -> str:
        """``'N'`` or ``'N m'``."""
        return "N m" if self.rotary else "N"

    @property
    def length_unit(self) -> str:
        """``'m'`` or ``'rad'``."""
        return "rad" if self.rotary else "m"

    @property
    def mass_unit(self) -> str:
        """``'kg'`` or ``'kg m^2'``."""
        return "kg m^2" if self.rotary else "kg"

    @property
    def mass_word(self) -> str:
        """``'mass'`` or ``'inertia'``."""
        return "inertia" if self.rotary else "mass"

    @property
    def force_word(self) -> str:
        """``'force'`` or ``'torque'``."""
        return "torque" if self.rotary else "force"


@document_fields
@dataclass(frozen=True, kw_only=True)
class AxisSpec(AxisWords):
    """An axis's kind and the unit of its actuator command (the ``[axis]`` table).

    ``input`` ``'N'`` is for a linear axis, ``'N m'`` for a rotary one (the command is then the
    force or torque itself, ``plant.K = 1``).

    Examples
    --------
    >>> AxisSpec(kind="rotary", input="N m").force_unit
    'N m'
    >>> AxisSpec(kind="rotary", input="N")
    Traceback (most recent call last):
    ...
    ValueError: axis.input: expected 'N m' (or 'V', 'A') for a rotary axis, found 'N'
    """

    _section = "axis"
    kind: str = param_field(Choice(AXIS_KINDS), "-", "linear (m, kg, N) or rotary (rad, kg m^2, N m)", "linear")
    input: str = param_field(Choice(INPUT_UNITS), "-", "unit of the actuator command (plant.K turns it into "
                             "force or torque)", "V")

    def __post_init__(self) -> None:
        validate_fields(self)
        if self.input in ("N", "N m") and self.input != self.force_unit:
            raise ValueError(f"axis.input: expected {self.force_unit!r} (or 'V', 'A') for a {self.kind} axis, "
                             f"found {self.input!r}")

    @property
    def rotary(self) -> bool:
        """Whether the axis is rotary."""
        return self.kind == "rotary"

    def unit(self, text: str) -> str:
        """The unit ``text``, written for a linear axis driven in V, for this axis.

        Parameters
        ----------
        text : str
            A unit made of :data:`_UNIT_WORDS` (``'N s/m'``, ``'m/(V s)'``, ``'um'``).

        Returns
        -------
        str
            For a rotary axis kg -> kg m^2, N -> N m, m -> rad (mm, um, nm -> mrad, urad, nrad);
            V -> the input unit (a two-word unit after ``/`` in parentheses). ``rad``, ``s``, ``Hz``
            are unchanged, so an angular frequency stays ``rad/s``.

        Examples
        --------
        >>> AxisSpec(kind="linear", input="A").unit("V/(m s)")
        'A/(m s)'
        """
        if self.kind == "linear" and self.input == "V":
            return text
        table = dict(_ROTARY) if self.rotary else {}
        table["V"] = self.input

        def swap(match: re.Match) -> str:
            new = table.get(match.group(0), match.group(0))
            if " " in new and match.start() > 0 and text[match.start() - 1] == "/":
                new = f"({new})"
            return new

        return _WORD.sub(swap, text)

    def words(self, text: str) -> str:
        """``text``, a label or sentence written for a linear axis driven in V, in this axis's words.

        On a rotary axis mass becomes inertia and force torque; ``voltage`` becomes what the command
        is (:data:`INPUT_WORDS`: current, force, torque). The first letter keeps its case; units are
        :meth:`label`'s.

        Examples
        --------
        >>> AxisSpec(kind="rotary", input="A").words("Moving mass and known load force")
        'Inertia and known load torque'
        >>> AxisSpec(kind="linear", input="A").words("actuator voltage limit, force constant")
        'actuator current limit, force constant'
        """
        if self.kind == "linear" and self.input == "V":
            return text
        table = dict(_ROTARY_WORDS) if self.rotary else {}
        table["voltage"] = INPUT_WORDS[self.input]

        def swap(match: re.Match) -> str:
            word = match.group(0)
            new = table.get(word.lower(), word)
            return new[:1].upper() + new[1:] if word[:1].isupper() else new

        return _TEXT_WORD.sub(swap, text)

    def label(self, text: str) -> str:
        """``text`` with each bracketed unit (``'kappa [N/m]'``) and its words (:meth:`words`) written
        for this axis.

        A bracket holding a word that is no unit (``'[95 %: 1 to 2]'``) is left as it is.

        Examples
        --------
        >>> AxisSpec(kind="rotary", input="A").label("max |PS| [m/V] ([dB]) [95 %: a to b]")
        'max |PS| [rad/A] ([dB]) [95 %: a to b]'
        >>> AxisSpec(kind="rotary", input="A").label("friction force [N]")
        'friction torque [N m]'
        """
        if self.kind == "linear" and self.input == "V":
            return text
        text = self.words(text)

        def swap(match: re.Match) -> str:
            inner = match.group(1)
            if not set(_WORD.findall(inner)) <= _UNIT_WORDS:
                return match.group(0)
            return f"[{self.unit(inner)}]"

        return _BRACKET.sub(swap, text)

    def describe(self) -> str:
        """One line: the kind, its units and the input unit.

        >>> AxisSpec(kind="rotary", input="A").describe()
        'rotary axis (inertia kg m^2, torque N m, angle rad), command in A'
        """
        kind = ("rotary axis (inertia kg m^2, torque N m, angle rad)" if self.rotary
                else "linear axis (mass kg, force N, position m)")
        return f"{kind}, command in {self.input}"

    def to_dict(self) -> dict[str, str]:
        """The TOML table."""
        return {"kind": self.kind, "input": self.input}

    @classmethod
    def from_dict(cls, table: Mapping[str, Any]) -> "AxisSpec":
        """Build from the parsed ``[axis]`` table (unknown keys are an error, as in every section)."""
        from ._validate import section_from_table

        return section_from_table(cls, table)

    def toml_lines(self) -> list[str]:
        """The ``[axis]`` table as TOML lines (a blank line first), each key with its meaning in this axis's words.

        >>> AxisSpec(kind="rotary", input="A").toml_lines()[2]
        'kind = "rotary"  # rotary axis (inertia kg m^2, torque N m, angle rad)'
        """
        from ._format import toml_value

        docs = {"kind": self.describe().partition(", command")[0],  # this axis's units only
                "input": f"unit of the actuator command (plant.K turns it into {self.force_word})"}
        return ["", "[axis]  # the units of every value below (docs/measured-data.md#units-delimiters-comments)"] + [
            f"{k} = {toml_value(v)}  # {docs[k]}" for k, v in self.to_dict().items()]


#: The axis of a config without ``[axis]``: linear, driven in V (the presets).
LINEAR = AxisSpec()
