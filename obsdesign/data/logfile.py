"""A measurement file read into named channels: the one loader of every log format.

:func:`read_log` reads a file by its extension (:data:`FORMATS`: CSV, MATLAB, TDMS, MDF4, HDF5,
MCAP, Parquet) into a :class:`LogFile`: channels by name (``group/channel`` where the format has
groups), each with the unit the file writes for it and, where the format carries one, its own
time base [s] (TDMS ``wf_increment``, the MDF master channel, MCAP message stamps). Every path
from a file to ``identify``, ``observe`` and ``report --data`` goes through it
(:func:`obsdesign.data.load_trace`); ``obsdesign channels FILE`` lists what it found.

The readers of the formats other than CSV and MATLAB need the field's own library, an optional
extra of the package (:data:`FORMATS` names it): ``pip install "obsdesign[tdms]"``, or
``obsdesign[formats]`` for all of them. A missing library is :class:`MissingExtra` (an
``ImportError``) naming the line to run.

Examples
--------
>>> import tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "log.csv"
...     _ = p.write_text("Scope;axis 2\\nt;pos [deg];i_mA\\n0;1,5;2\\n0,001;1,75;3\\n", encoding="latin-1")
...     log = read_log(p)
>>> log.format, list(log.channels), log.metadata["Scope"]
('CSV', ['t', 'pos', 'i_mA'], 'axis 2')
>>> [(c.name, c.unit, c.unit_from) for c in log.channels.values()]
[('t', None, ''), ('pos', 'deg', 'header'), ('i_mA', 'mA', 'name')]
>>> log.channels["pos"].values.tolist()
[1.5, 1.75]
"""

from __future__ import annotations

import importlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .formats import FORMATS, Format, extensions_text, format_of

__all__ = ["Channel", "LogFile", "FORMATS", "Format", "read_log", "MissingExtra", "FileRefused", "extensions_text",
           "common_time", "format_of"]


class MissingExtra(ImportError):
    """A format's library is not installed; the message names the ``pip install`` line to run."""


class FileRefused(ValueError):
    """A reader's own message about a file it cannot use (passed on as it is; anything else a format's
    library raises is turned into one line naming the format)."""


@dataclass(frozen=True, kw_only=True, eq=False)
class Channel:
    """One named series of a log file.

    Attributes
    ----------
    name : str
        The name to pick it by (``group/channel`` where the format has groups).
    values : ndarray
        The samples as stored (any numeric dtype; :func:`obsdesign.data.load_trace` checks them).
    unit : str or None
        The unit the file writes for it (``None``: none written).
    unit_from : str
        Where the unit was found: ``'header'`` (``pos [mm]``, ``pos (mm)``), ``'units row'``,
        ``'name'`` (a suffix such as ``pos_mm``: used only where it fits the column), ``'file'``
        (the format's metadata); ``''`` without a unit.
    time : ndarray or None
        The channel's own time base [s] where the format carries one, else ``None``.
    """

    name: str
    values: np.ndarray = field(repr=False)
    unit: str | None = None
    unit_from: str = ""
    time: np.ndarray | None = field(default=None, repr=False)

    @property
    def rate(self) -> float | None:
        """Samples per second of :attr:`time` (median step), or ``None``."""
        if self.time is None or self.time.size < 2:
            return None
        step = float(np.median(np.diff(self.time)))
        return 1.0 / step if step > 0 else None


@dataclass(frozen=True, kw_only=True, eq=False)
class LogFile:
    """A file's channels and its metadata.

    Attributes
    ----------
    name : str
        The file's name.
    format : str
        The format's name (a key of :data:`FORMATS`).
    channels : dict
        Name -> :class:`Channel`, in the file's order.
    metadata : dict
        Key -> text: a CSV's header block (``Key;Value`` lines above the table), the file's own
        properties where the format has them, and how it was read (``encoding``, ``delimiter``, ``decimal``).
    kind : str
        What a channel is called in messages: ``'column'``, ``'variable'`` or ``'channel'``.
    """

    name: str
    format: str
    channels: dict
    metadata: dict = field(default_factory=dict)
    kind: str = "channel"

    def pick(self, param: str, name: str) -> Channel:
        """The channel ``name``; refused naming ``param`` and listing the channels found.

        >>> LogFile(name="a.csv", format="CSV", channels={}, kind="column").pick("position", "x")
        Traceback (most recent call last):
        ...
        ValueError: position: expected the name of a column, found 'x'; available: none
        """
        if name not in self.channels:
            raise ValueError(f"{param}: expected the name of a {self.kind}, found {name!r}; available: "
                             f"{', '.join(sorted(self.channels)) or 'none'}")
        return self.channels[name]

    def rows(self) -> list[tuple[str, str, int, str]]:
        """``(name, unit, length, rate)`` per channel: what ``obsdesign channels`` prints."""
        out = []
        for ch in self.channels.values():
            rate = ch.rate
            unit = "-" if ch.unit is None else ch.unit + ("" if ch.unit_from in ("file", "header") else
                                                          f" ({ch.unit_from})")
            out.append((ch.name, unit, int(np.size(ch.values)), "-" if rate is None else f"{rate:.6g} Hz"))
        return out


def read_log(path: str | os.PathLike, *, delimiter: str | None = None, decimal: str | None = None) -> LogFile:
    """Read a log file into named channels (the format by the extension).

    Parameters
    ----------
    path : str or path-like
        The file; its extension names the format (:data:`FORMATS`).
    delimiter, decimal : str, optional
        A CSV file's delimiter and decimal mark (default: detected); refused for other formats.

    Returns
    -------
    LogFile

    Raises
    ------
    ValueError
        An unknown extension, a missing file, a file that is not what its extension says (truncated,
        empty, another format), a CSV option for another format.
    MissingExtra
        The format's library is not installed (the message names ``pip install "obsdesign[...]"``).
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected a file path, found {type(path).__name__} {path!r}")
    p = Path(path)
    fmt = format_of(p)
    if fmt.name != "CSV":
        for param, value in (("delimiter", delimiter), ("decimal", decimal)):
            if value is not None:
                raise ValueError(f"{param}: expected None for a {fmt.name} file (it is not text), found {value!r}")
    if not p.is_file():
        raise ValueError(f"path: expected an existing file, found {str(p)!r}")
    if fmt.library is not None:
        try:
            importlib.import_module(fmt.library)
        except ImportError as e:
            raise MissingExtra(f"path: reading {fmt.name} files ({p.name!r}) needs the optional extra "
                               f"'{fmt.extra}': pip install \"obsdesign[{fmt.extra}]\" (missing: {e.name or e})"
                               ) from None
    module, _, function = fmt.reader.partition(":")
    reader = getattr(importlib.import_module(module), function)
    if fmt.name == "CSV":
        return reader(p, delimiter, decimal)
    if p.stat().st_size == 0:
        raise ValueError(f"path: expected a {fmt.name} file, found an empty file {p.name!r}")
    try:
        log = reader(p)
    except (FileRefused, MissingExtra):
        raise
    except MemoryError:
        raise ValueError(f"path: not enough memory to read {p.name!r}") from None
    except Exception as e:  # noqa: BLE001 (the libraries raise many types for a file that is not theirs)
        raise ValueError(f"path: expected a {fmt.name} file, found one {fmt.library or fmt.name} cannot read: "
                         f"{p.name!r} ({type(e).__name__}: {e})") from e
    return log


def common_time(log: LogFile, x: Channel, u: Channel, x_label: str, u_label: str) -> np.ndarray | None:
    """The file's own time base [s] of the position and input channels (the same for both), or ``None``.

    Parameters
    ----------
    log : LogFile
        The file (named in the message).
    x, u : Channel
        The position and input channels.
    x_label, u_label : str
        How messages name them.

    Examples
    --------
    >>> ch = Channel(name="x", values=np.zeros(3), time=np.arange(3.0))
    >>> common_time(LogFile(name="a", format="TDMS", channels={}), ch, ch, "x", "u").tolist()
    [0.0, 1.0, 2.0]
    """
    if x.time is None:
        return None
    if u.time is None or not np.array_equal(x.time, u.time):
        raise ValueError(f"input: expected samples at the times of the {x_label}, found {u_label} "
                         f"{'without a time base' if u.time is None else 'sampled at other times'} in "
                         f"{log.name!r} (give --time NAME or resample both to one time base)")
    return x.time
