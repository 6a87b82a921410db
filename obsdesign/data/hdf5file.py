"""Reading an HDF5 file (DAQ systems, data loggers) with h5py: datasets by path, units from attributes.

Every numeric dataset is a channel named by its path (``group/dataset``, without the leading
``/``); a compound dataset (a table) gives one channel per numeric field (``group/table/field``).
The unit is the attribute ``unit`` (or ``units``, ``Unit``). Needs the extra ``hdf5``
(``pip install "obsdesign[hdf5]"``).

Examples
--------
>>> import tempfile, pathlib
>>> import h5py, numpy as np
>>> with tempfile.TemporaryDirectory() as d:
...     path = pathlib.Path(d) / "run.h5"
...     with h5py.File(path, "w") as f:
...         f["axis/pos"] = np.arange(3.0)
...         f["axis/pos"].attrs["unit"] = "mm"
...     log = read_hdf5(path)
>>> list(log.channels), log.channels["axis/pos"].unit
(['axis/pos'], 'mm')
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .logfile import Channel, FileRefused, LogFile

__all__ = ["read_hdf5"]


def _unit(attrs) -> str | None:
    for key in ("unit", "units", "Unit", "Units"):
        if key in attrs:
            value = attrs[key]
            value = value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
            return value.strip() or None
    return None


def read_hdf5(path: Path) -> LogFile:
    """The numeric datasets of an HDF5 file.

    Parameters
    ----------
    path : Path
        The ``.h5`` file.
    """
    import h5py

    if not h5py.is_hdf5(str(path)):
        raise FileRefused(f"path: expected an HDF5 file, found one without the HDF5 signature: {path.name!r}")
    channels = {}
    with h5py.File(str(path), "r") as f:
        def visit(name, obj):
            if not isinstance(obj, h5py.Dataset):
                return
            unit = _unit(obj.attrs)
            if obj.dtype.names:
                data = obj[()]
                for field in obj.dtype.names:
                    if data[field].dtype.kind in "biuf":
                        key = f"{name}/{field}"
                        channels[key] = Channel(name=key, values=np.asarray(data[field]))
            elif obj.dtype.kind in "biuf":
                channels[name] = Channel(name=name, values=np.asarray(obj[()]), unit=unit,
                                         unit_from="file" if unit else "")

        f.visititems(visit)
        meta = {str(k): (v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v)) for k, v in f.attrs.items()}
    return LogFile(name=path.name, format="HDF5", channels=channels, metadata=meta)
