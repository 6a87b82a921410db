"""Named choices with the integer codes the numba kernels branch on: :class:`Entry` and :class:`Registry`.

The numba kernels branch on small integers; everything above them (the API, the
command line's choices, the docs and the report) names the choices. A registry holds
both, once: the other lists of names (``choices=``, docstrings, docs tables) are read
from it. It imports nothing beyond the standard library, so the command line can read
its names before anything heavy loads, and a numba module can read a code at import
time (``SCHEDULES.code("true")`` is a plain ``int``, frozen into the compiled code like
any global). Codes are append-only: numba's cache does not see a renumbering in another file.

The kinds of choice live in their rooms: :data:`obsdesign.friction.registry.FRICTION_MODELS`,
:data:`obsdesign.estimators.registry.ESTIMATORS` and :mod:`obsdesign.sampled.choices`
(controllers, schedules, plants).

Examples
--------
>>> colours = Registry("colour", [Entry("red", 0, "warm"), Entry("blue", 1, "cold")])
>>> colours.names(), colours.code("blue"), "green" in colours
(('red', 'blue'), 1, False)
>>> colours.check("green")
Traceback (most recent call last):
...
ValueError: colour: expected one of red, blue, found 'green'
>>> colours.check("green", kind="paint")
Traceback (most recent call last):
...
ValueError: paint: expected one of red, blue, found 'green'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Iterator, Mapping, TypeVar

from ._validate import check_choice

__all__ = ["Entry", "Registry"]


@dataclass(frozen=True)
class Entry:
    """One choice: its name, the kernel's integer code, a one-line description and its parameters.

    Attributes
    ----------
    name : str
        The choice's name (what the API, the command line and the docs say).
    code : int
        The numba kernels' integer code (append-only: numba caches it).
    doc : str
        One line of description.
    parameters : tuple
        Its parameters as ``(name, unit, description, ...)`` tuples (empty: none).
    """

    name: str
    code: int
    doc: str
    parameters: tuple = ()


E = TypeVar("E", bound=Entry)


class Registry(Mapping[str, E]):
    """An ordered, read-only mapping ``name -> Entry`` with unique names and codes.

    ``registry[name]`` and :meth:`check` raise a ``ValueError`` naming the argument, the
    choices and the value; ``name in registry`` is a plain test.

    Parameters
    ----------
    kind : str
        The argument name used in error messages (e.g. ``'stiffness'``).
    entries : iterable of Entry
        The choices, in the order the command line and the docs list them.
    """

    def __init__(self, kind: str, entries: Iterable[E]) -> None:
        self.kind = kind
        self._entries: dict[str, E] = {}
        for entry in entries:
            self.register(entry)

    def register(self, entry: E) -> None:
        """Add an entry; its name and code must be new.

        Parameters
        ----------
        entry : Entry
            The new choice.
        """
        if not isinstance(entry, Entry):
            raise TypeError(f"{self.kind}: expected an Entry, found {type(entry).__name__}")
        if entry.name in self._entries or entry.code in {e.code for e in self._entries.values()}:
            raise ValueError(f"{self.kind}: {entry.name!r} or code {entry.code} is registered already")
        self._entries[entry.name] = entry

    def __getitem__(self, name: str) -> E:
        return self._entries[check_choice(self.kind, name, self._entries)]

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self._entries

    def get(self, name: object, default=None):
        """The entry of ``name``, or ``default`` where it is not registered (no error).

        Parameters
        ----------
        name : object
            A name.
        default : optional
            Returned for an unregistered name.
        """
        return self._entries.get(name, default) if isinstance(name, str) else default

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._entries)!r})"

    def names(self) -> tuple[str, ...]:
        """The names, in registration order (the command line's choices)."""
        return tuple(self._entries)

    def code(self, name: str) -> int:
        """The kernel's integer code of ``name`` (``ValueError`` naming the choices otherwise).

        Parameters
        ----------
        name : str
            A registered name.
        """
        return self[name].code

    def check(self, name: object, *, kind: str | None = None) -> str:
        """``name`` if registered, else a ``ValueError`` naming the argument, the choices and the value.

        Parameters
        ----------
        name : object
            The value to check.
        kind : str, optional
            The argument's name in the message (default: the registry's ``kind``).
        """
        return check_choice(self.kind if kind is None else kind, name, self._entries)

    def describe(self) -> Mapping[str, str]:
        """``{name: doc}`` for help texts and docs."""
        return {name: entry.doc for name, entry in self._entries.items()}
