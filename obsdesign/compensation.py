"""The ``[compensation]`` section of a config: knobs of the friction compensation law.

The closed loop ``pid+observer`` adds ``comp / K`` to the PID's command [V] with::

    fade = min(1, |v_hat| / deadzone)  if deadzone > 0 else 1
    comp = gain * (f_hat_filtered + (sigma * v_hat if viscous else 0)) * fade

The defaults (gain 1, no viscous term, no deadzone) give the paper's law ``f_hat_filtered / K``;
the simulator and the exported controller then do exactly the floating-point operations of
that law. The section is optional in TOML. :meth:`obsdesign.Config.override` addresses its
fields as ``gain``, ``viscous`` and ``deadzone``.

Examples
--------
>>> CompensationSpec(deadzone=1e-4).viscous
False
>>> CompensationSpec(gain=1.5)
Traceback (most recent call last):
...
ValueError: compensation.gain: expected a finite number > 0 and <= 1, found 1.5
>>> CompensationSpec(viscous=1)
Traceback (most recent call last):
...
TypeError: compensation.viscous: expected true or false, found int 1
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ._validate import NONNEGATIVE, Range, param_field, validate_fields

__all__ = ["CompensationSpec", "Flag"]


@dataclass(frozen=True)
class Flag:
    """A true/false value (Python ``bool``; TOML ``true``/``false``)."""

    def describe(self) -> str:
        """The expectation in words."""
        return "true or false"

    def check(self, name: str, value: Any) -> bool:
        """``value`` if it is a bool, else a ``TypeError`` naming ``name``.

        Parameters
        ----------
        name : str
            Qualified parameter name for the message.
        value : object
            The value to check.
        """
        if not isinstance(value, bool):
            raise TypeError(f"{name}: expected {self.describe()}, found {type(value).__name__} {value!r}")
        return value


@dataclass(frozen=True, kw_only=True)
class CompensationSpec:
    """Friction compensation of the ``pid+observer`` controller (defaults: the paper's law).

    Parameters
    ----------
    gain : float
        Fraction of the estimate applied, in (0, 1].
    viscous : bool
        Add ``sigma v_hat`` to the filtered friction estimate.
    deadzone : float
        Velocity [m/s] below which the compensation fades linearly to zero
        (``|v_hat| / deadzone``); 0 disables the fade.

    Examples
    --------
    >>> CompensationSpec().is_default
    True
    >>> CompensationSpec(gain=0.8).is_default
    False
    """

    _section = "compensation"
    gain: float = param_field(Range(low=0.0, high=1.0, high_inclusive=True), "-",
                         "fraction of the friction estimate compensated", 1.0)
    viscous: bool = param_field(Flag(), "-", "add sigma * v_hat to the filtered estimate", False)
    deadzone: float = param_field(NONNEGATIVE, "m/s", "compensation fades out below this |v_hat| (0: off)", 0.0)

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def is_default(self) -> bool:
        """Whether the knobs are the paper's law (gain 1, no viscous term, no deadzone)."""
        return self.gain == 1.0 and not self.viscous and self.deadzone == 0.0
