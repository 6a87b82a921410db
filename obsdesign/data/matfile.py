"""Reading a MATLAB ``.mat`` file (v5 and older, ``scipy.io.loadmat``): variables are channels.

Examples
--------
>>> import tempfile, pathlib
>>> import numpy as np
>>> from scipy import io as sio
>>> with tempfile.TemporaryDirectory() as d:
...     sio.savemat(pathlib.Path(d) / "run.mat", {"t": np.arange(3.0), "qm": np.ones((3, 1))})
...     log = read_mat(pathlib.Path(d) / "run.mat")
>>> log.format, sorted(log.channels), log.channels["qm"].values.shape
('MATLAB', ['qm', 't'], (3, 1))
"""

from __future__ import annotations

from pathlib import Path

from .logfile import Channel, FileRefused, LogFile

__all__ = ["read_mat"]


def read_mat(path: Path) -> LogFile:
    """The variables of a MATLAB file as channels (no units: the format has none).

    Parameters
    ----------
    path : Path
        The ``.mat`` file.
    """
    from scipy import io as sio

    try:
        raw = sio.loadmat(str(path))
    except MemoryError:
        raise FileRefused(f"path: not enough memory to read {path.name!r} (a MATLAB file whose variables "
                          "decompress to more than the memory available)") from None
    except Exception as e:  # noqa: BLE001 (scipy raises several types for a file that is not MATLAB)
        raise FileRefused(f"path: expected a MATLAB .mat file (v5 or older), found one scipy cannot read: "
                          f"{path.name!r} ({e})") from e
    channels = {k: Channel(name=k, values=v) for k, v in raw.items() if not k.startswith("__")}
    return LogFile(name=path.name, format="MATLAB", channels=channels, kind="variable")
