"""The ``[hardware]`` section of a config: what the drive does that no controller setting changes.

``delay_samples`` is the drive's delay between the sampled position and the applied command, in
whole samples: the command computed from the measurement of sample ``n`` acts on the plant from
sample ``n + d`` on (computation, communication, the amplifier's update). It is a property of the
hardware, not of the controller: the simulator puts it between the controller and the plant
(:func:`obsdesign.sim.kernel.run_loop`), every loop analysis puts it in the loop
(:mod:`obsdesign.design.sampled_loop`), and ``export`` never adds it, so the exported controller on
the hardware that has the delay runs the loop that was simulated. docs/delay.md shows what counting
it twice does (a 4 kHz rotary axis oscillating at 273 Hz).

The section is optional in TOML (default 0). A config written before it existed may carry the field
as ``[pid] delay_samples``: it is read with a ``FutureWarning`` and written back under ``[hardware]``
(:func:`move_legacy_delay`).

Examples
--------
>>> HardwareSpec().delay_samples
0
>>> HardwareSpec(delay_samples=-1)
Traceback (most recent call last):
...
ValueError: hardware.delay_samples: expected an integer >= 0 and <= 10000, found -1
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

from ._validate import MAX_DELAY_SAMPLES, Integer, document_fields, param_field, validate_fields

__all__ = ["HardwareSpec", "move_legacy_delay"]


@document_fields
@dataclass(frozen=True, kw_only=True)
class HardwareSpec:
    """The drive's properties the loop has but the controller does not set.

    Examples
    --------
    >>> HardwareSpec(delay_samples=1).delay_samples
    1
    """

    _section = "hardware"
    delay_samples: int = param_field(
        Integer(minimum=0, maximum=MAX_DELAY_SAMPLES), "samples",
        "the drive's delay: the command computed from sample n acts from sample n + d (not a controller setting)", 0
    )

    def __post_init__(self) -> None:
        validate_fields(self)


def move_legacy_delay(data: dict[str, Any], *, source: str = "config") -> dict[str, Any]:
    """``data`` (a parsed config) with a legacy ``[pid] delay_samples`` moved to ``[hardware]``.

    Parameters
    ----------
    data : dict
        The parsed TOML document (not changed).
    source : str
        Where it comes from, for the messages.

    Returns
    -------
    dict
        ``data`` itself when there is nothing to move, else a copy with the field moved.

    Raises
    ------
    ValueError
        Both ``[pid] delay_samples`` and ``[hardware] delay_samples`` are set.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     out = move_legacy_delay({"pid": {"tau": 0.01, "delay_samples": 1}})
    >>> out
    {'pid': {'tau': 0.01}, 'hardware': {'delay_samples': 1}}
    >>> print(w[0].message)
    config: [pid] delay_samples is the drive's delay, not a controller setting; read as [hardware] delay_samples = 1 (write it there: obsdesign config prints the new layout)
    """
    pid = data.get("pid")
    if not isinstance(pid, dict) or "delay_samples" not in pid:
        return data
    hardware = data.get("hardware", {})
    if isinstance(hardware, dict) and "delay_samples" in hardware:
        raise ValueError(f"{source}: delay_samples is set in [pid] and in [hardware]; expected it once, in "
                         f"[hardware] (found {pid['delay_samples']!r} and {hardware['delay_samples']!r})")
    out = dict(data)
    pid = dict(pid)
    value = pid.pop("delay_samples")
    out["pid"] = pid
    out["hardware"] = {**(hardware if isinstance(hardware, dict) else {}), "delay_samples": value}
    warnings.warn(f"{source}: [pid] delay_samples is the drive's delay, not a controller setting; read as "
                  f"[hardware] delay_samples = {value!r} (write it there: obsdesign config prints the new layout)",
                  FutureWarning, stacklevel=3)
    return out
