"""The ``[compensation]`` section of a config: knobs of the friction compensation law.

The closed loop ``pid+observer`` adds ``comp / K`` to the PID's command [V] with::

    fade = min(1, |v_hat| / deadzone)  if deadzone > 0 else 1
    comp = gain * (f_hat_filtered + (sigma * v_hat if viscous else 0)) * fade

The defaults (gain 1, no viscous term, no deadzone) give the paper's law ``f_hat_filtered / K``;
the simulator and the exported controller then do exactly the floating-point operations of
that law. The section is optional in TOML. :meth:`obsdesign.Config.override` addresses its
fields by their names (``gain``, ``viscous``, ``deadzone``, ``mode``, ``lookahead``, ...).

``mode`` (:data:`COMPENSATION_MODES`, here) chooses what compensates:
``observer`` (the law above), ``feedforward`` (the friction model of the reference velocity,
``w (sign(v_ref) (Cf + ff_stribeck exp(-(v_ref / ff_stribeck_velocity)^2)) + sigma v_ref) + ff_offset``
with ``Cf``, ``sigma`` of ``[friction]`` and the weight ``w`` of
:func:`obsdesign.sampled.reference.reference_feedforward`: the pre-sliding curve of the reference
(``ff_presliding``) times the look-ahead/build-up ramp) or ``blend`` (the feed-forward plus the
low-passed observer estimate less the low-passed model part the observer also sees); both
scaled by ``gain``. docs/compensation-modes.md states the laws.

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
>>> CompensationSpec(mode="feedforward", lookahead=20).buildup
0.0
>>> CompensationSpec(mode="blend", deadzone=1e-4)
Traceback (most recent call last):
...
ValueError: compensation.deadzone: applies to mode 'observer' only; expected 0 with mode 'blend', found 0.0001
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ._registry import Entry, Registry
from ._validate import (
    DISTANCE,
    FORCE,
    MAX_SPEED,
    NONNEGATIVE_FORCE,
    SPEED,
    Choice,
    Integer,
    Range,
    param_field,
    validate_fields,
)

__all__ = ["CompensationSpec", "Flag", "COMPENSATION_MODES"]

#: Compensation modes of ``pid+observer`` (``[compensation] mode``; the law in docs/compensation-modes.md),
#: with the integer codes the sampled controller's kernel branches on.
COMPENSATION_MODES = Registry("compensation.mode", [
    Entry("observer", 0, "the observer's filtered friction estimate (the paper's law, with gain, viscous term and "
          "deadzone fade)"),
    Entry("feedforward", 1, "the friction model of the reference velocity (Coulomb + Stribeck + viscous + offset), "
          "with the reversal look-ahead ramp and the build-up distance"),
    Entry("blend", 2, "the feed-forward plus the low-passed observer estimate less the low-passed model: "
          "(1 - LP) model + LP estimate, each part of the friction counted once"),
])


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
    mode : str
        A name of :data:`obsdesign.compensation.COMPENSATION_MODES`: ``observer``,
        ``feedforward`` or ``blend`` (``viscous`` and ``deadzone`` are of ``observer`` only).
    ff_stribeck : float
        Stribeck force [N] of the feed-forward model at zero velocity, above ``Cf``.
    ff_stribeck_velocity : float
        Stribeck velocity [m/s] of the feed-forward model.
    ff_offset : float
        Constant force [N] of the feed-forward model (not weighted by the ramp).
    lookahead : int
        Samples over which the feed-forward is ramped to zero before a reversal of the
        reference velocity (0: none).
    buildup : float
        Reference distance [m] over which the feed-forward builds up after a start or a reversal
        (0: at once).
    ff_presliding : bool
        The feed-forward model's Coulomb term follows the pre-sliding curve eq:2:3:3-4 of
        ``[friction] s`` along the reference (its memory of the last reversal) instead of switching
        sign at once; a true velocity function (a drive's table) is ``false``.

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
    deadzone: float = param_field(SPEED, "m/s", "compensation fades out below this |v_hat| (0: off)", 0.0)
    mode: str = param_field(Choice(COMPENSATION_MODES.names()), "-",
                            "what compensates: observer estimate, reference feed-forward or their blend", "observer")
    ff_stribeck: float = param_field(NONNEGATIVE_FORCE, "N", "feed-forward Stribeck force above Cf at rest", 0.0)
    ff_stribeck_velocity: float = param_field(Range(low=1e-9, high=MAX_SPEED, low_inclusive=True, high_inclusive=True), "m/s",
                                              "feed-forward Stribeck velocity", 1e-3)
    ff_offset: float = param_field(FORCE, "N", "feed-forward constant force", 0.0)
    lookahead: int = param_field(Integer(minimum=0, maximum=1_000_000), "samples",
                                 "feed-forward ramp to zero before a reference reversal (0: off)", 0)
    buildup: float = param_field(DISTANCE, "m", "feed-forward build-up distance after a start (0: off)", 0.0)
    ff_presliding: bool = param_field(Flag(), "-",
                                      "feed-forward Coulomb term follows the pre-sliding curve of [friction] s", True)

    def __post_init__(self) -> None:
        validate_fields(self)
        if self.mode != "observer":
            for name, off in (("viscous", False), ("deadzone", 0.0)):
                if getattr(self, name) != off:
                    raise ValueError(f"compensation.{name}: applies to mode 'observer' only; expected "
                                     f"{0 if off is not False else 'false'} with mode {self.mode!r}, "
                                     f"found {getattr(self, name)!r}")

    @property
    def is_default(self) -> bool:
        """Whether the knobs are the paper's law (mode observer, gain 1, no viscous term, no deadzone)."""
        return self.mode == "observer" and self.gain == 1.0 and not self.viscous and self.deadzone == 0.0
