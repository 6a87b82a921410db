"""Reading an MDF4 file (ASAM MDF: automotive and test-bench loggers) with asammdf.

Each channel is named as the file names it (``group N/name`` where a name repeats across groups);
its unit is the channel's unit, its own time base its group's master channel [s] (the master
channels themselves are not listed). Values are the physical ones (conversions applied). Needs
the extra ``mdf`` (``pip install "obsdesign[mdf]"``).

Examples
--------
>>> import tempfile, pathlib
>>> import numpy as np
>>> from asammdf import MDF, Signal
>>> with tempfile.TemporaryDirectory() as d:
...     path = pathlib.Path(d) / "run.mf4"
...     mdf = MDF(version="4.10")
...     _ = mdf.append([Signal(np.arange(4.0), np.arange(4) * 0.001, name="pos", unit="deg")])
...     _ = mdf.save(path)
...     _ = mdf.close()
...     log = read_mdf(path)
>>> log.channels["pos"].unit, log.channels["pos"].time.tolist()
('deg', [0.0, 0.001, 0.002, 0.003])
"""

from __future__ import annotations

import gc
import logging
import sys
from collections import Counter
from pathlib import Path

import numpy as np

from .logfile import Channel, FileRefused, LogFile

__all__ = ["read_mdf"]


def _open(MDF, path: Path):
    """``MDF(path)``; a file asammdf cannot read is refused in one line (its half-built object's ``__del__``
    fails too: that is silenced, it would print a second message)."""
    hook = sys.unraisablehook
    sys.unraisablehook = lambda unraisable: None
    try:
        try:
            return MDF(str(path))
        except Exception as e:  # noqa: BLE001 (asammdf raises many types for a file that is not MDF)
            error = f"{type(e).__name__}: {e}"
        gc.collect()
    finally:
        sys.unraisablehook = hook
    raise FileRefused(f"path: expected an MDF4 file, found one asammdf cannot read: {path.name!r} ({error})")


def read_mdf(path: Path) -> LogFile:
    """The channels of an MDF file (version 4, or 3 as asammdf reads it).

    Parameters
    ----------
    path : Path
        The ``.mf4`` (``.mdf``) file.
    """
    with open(path, "rb") as fh:
        if fh.read(8) != b"MDF     ":
            raise FileRefused(f"path: expected an MDF file (it starts with 'MDF'), found other bytes at the start "
                              f"of {path.name!r}")
    from asammdf import MDF

    quiet = logging.getLogger("asammdf")
    level = quiet.level
    quiet.setLevel(logging.CRITICAL)  # asammdf logs what it finds odd; the errors come here as exceptions
    try:
        mdf = _open(MDF, path)
        try:
            found = []
            for g, group in enumerate(mdf.groups):
                master = mdf.masters_db.get(g)
                for i, ch in enumerate(group.channels):
                    if i != master and ch.name:
                        found.append((g, i, ch.name))
            counts = Counter(name for _, _, name in found)
            channels = {}
            for g, i, name in found:
                sig = mdf.get(name, group=g, index=i, raw=False)
                key = name if counts[name] == 1 else f"group {g}/{name}"
                values = np.asarray(sig.samples)
                unit = (sig.unit or "").strip() or None
                channels[key] = Channel(name=key, values=values, unit=unit, unit_from="file" if unit else "",
                                        time=np.asarray(sig.timestamps, dtype=float))
            meta = {"comment": str(mdf.header.comment)} if getattr(mdf.header, "comment", "") else {}
        finally:
            mdf.close()
    finally:
        quiet.setLevel(level)
    return LogFile(name=path.name, format="MDF4", channels=channels, metadata=meta)
