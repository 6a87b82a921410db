"""Registries of the sampled controller's choices: name -> integer code of the kernels, parameters, docs.

The numba kernel branches on small integers; everything above it (the API, the
CLI's choices, the docs and the report) names the choices. One registry per
kind of choice holds both, so adding a plant friction model or an estimator is
one new :class:`Entry` (and its branch in the kernel), not edits across the
command line, the kernel and the report.

Examples
--------
>>> ESTIMATORS.names()
('paper', 'paper-k0', 'eso', 'kalman', 'dob')
>>> SCHEDULES.code("true")
1
>>> SCHEDULES.code("guess")
Traceback (most recent call last):
...
ValueError: stiffness: expected one of estimated, true, constant, estimated-raw, found 'guess'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, Mapping

from .._validate import check_choice

__all__ = ["Entry", "Registry", "PLANT_FRICTION", "ESTIMATORS", "SCHEDULES", "CONTROLLERS", "PLANTS"]


@dataclass(frozen=True)
class Entry:
    """One choice: its name, the kernel's integer code, a one-line description and its
    parameters as ``(name, unit, description)`` triples."""

    name: str
    code: int
    doc: str
    parameters: tuple = ()


class Registry(Mapping):
    """An ordered, read-only mapping ``name -> Entry`` with unique codes.

    Parameters
    ----------
    kind : str
        The argument name used in error messages (e.g. ``'stiffness'``).
    entries : iterable of Entry
    """

    def __init__(self, kind: str, entries) -> None:
        self.kind = kind
        self._entries: dict[str, Entry] = {}
        for entry in entries:
            self.register(entry)

    def register(self, entry: Entry) -> None:
        """Add an entry; its name and code must be new."""
        if entry.name in self._entries or entry.code in {e.code for e in self._entries.values()}:
            raise ValueError(f"{self.kind}: {entry.name!r} or code {entry.code} is registered already")
        self._entries[entry.name] = entry

    def __getitem__(self, name: str) -> Entry:
        return self._entries[check_choice(self.kind, name, self._entries)]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def names(self) -> tuple[str, ...]:
        """The names, in registration order (the CLI's choices)."""
        return tuple(self._entries)

    def code(self, name: str) -> int:
        """The kernel's integer code of ``name`` (``ValueError`` naming the choices otherwise)."""
        return self[name].code

    def check(self, name: object) -> str:
        """``name`` if registered, else a ``ValueError`` naming the argument and the choices."""
        return self[name].name

    def describe(self) -> Mapping[str, str]:
        """``{name: doc}`` for help texts and docs."""
        return {name: entry.doc for name, entry in self._entries.items()}


#: Friction models of the simulated plant (``[plant_friction]`` in a config; codes of
#: :mod:`obsdesign.friction`). Each also takes ``Cf_neg``, ``sigma_neg`` and ``offset``.
PLANT_FRICTION = Registry("plant_friction", [
    Entry("paper", 0, "Coulomb friction with pre-sliding memory (eq:2:3:1-2:3:5) plus viscous friction "
          "sigma v, with the first-order lag beta of eq:2:2:2 when friction.beta is set",
          (("Cf", "N", "Coulomb friction level"), ("sigma", "N s/m", "viscous friction coefficient"),
           ("s", "1/m", "pre-sliding distance scaling factor"), ("beta", "s", "viscous friction lag"))),
    Entry("lugre", 1, "LuGre bristle model with a Stribeck curve (Canudas de Wit et al. 1995)",
          (("Fs", "N", "stiction level (default 1.5 Cf)"), ("vs", "m/s", "Stribeck velocity"),
           ("sigma0", "N/m", "bristle stiffness"), ("sigma1", "N s/m", "bristle damping"))),
    Entry("dahl", 2, "Dahl rate-independent pre-sliding model (Dahl 1968)",
          (("sigma0", "N/m", "rest stiffness"), ("alpha", "-", "shape exponent"))),
    Entry("gms", 3, "generalized Maxwell-slip model with N elements (Al-Bender et al. 2005)",
          (("N", "-", "number of elements"), ("K", "N/m", "total element stiffness"),
           ("C", "N/s", "attraction parameter"), ("Fs", "N", "stiction level (default 1.5 Cf)"))),
])

#: Estimators of velocity and friction run in the closed loop.
ESTIMATORS = Registry("estimator", [
    Entry("paper", 0, "the paper's reduced-order observer with its stiffness schedule (eq:3:1:2, Prop. 2)"),
    Entry("paper-k0", 1, "the same gains with the schedule off (k = 0 always: a linear reduced-order "
          "observer), the ablation of the pre-sliding schedule"),
    Entry("eso", 2, "linear extended state observer, poles at -omega_o, tuned by the fair noise rule"),
    Entry("kalman", 3, "steady-state Kalman filter with a random-walk friction, tuned by the fair noise rule"),
    Entry("dob", 4, "disturbance observer with Q = omega_q^2/(s + omega_q)^2, tuned by the fair noise rule"),
])

#: Stiffness schedules of the paper's observer.
SCHEDULES = Registry("stiffness", [
    Entry("estimated", 0, "pre-sliding branch driven by the measured displacement; a reversal is accepted once "
          "the displacement has come back from its extreme by more than 4 noise RMS (sensor.noise_rms)"),
    Entry("true", 1, "the simulated plant's stiffness (for analysis)"),
    Entry("constant", 2, "kappa always"),
    Entry("estimated-raw", 3, "pre-sliding branch with reversals at every sign change of v_hat (no hysteresis; "
          "the paper's reproductions)"),
])

#: Controllers of the loop.
CONTROLLERS = Registry("controller", [
    Entry("open-loop", 0, "the scenario's force, no feedback"),
    Entry("pid", 1, "parallel PID eq:PIDparallel with filtered derivative and conditional integration"),
    Entry("pid+observer", 2, "the PID plus the filtered friction estimate as compensation"),
])

#: Plant structures.
PLANTS = Registry("plant", [
    Entry("physical", 0, "the plant friction model (Coulomb with pre-sliding memory, viscous, optional lag)"),
    Entry("model", 1, "the 3-state LTV model eq:3:1 of the observer's variant"),
])
