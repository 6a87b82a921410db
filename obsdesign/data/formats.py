"""The log formats :func:`obsdesign.data.logfile.read_log` reads: the one list (no NumPy: the CLI's help reads it).

Examples
--------
>>> FORMATS["TDMS"].extra, format_of(Path("run.MF4")).name
('tdms', 'MDF4')
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["Format", "FORMATS", "extensions_text", "format_of"]


@dataclass(frozen=True)
class Format:
    """A file format.

    Attributes
    ----------
    name : str
        Its name (``'TDMS'``).
    extensions : tuple of str
        The file extensions, lower case with the dot.
    reader : str
        ``module:function`` reading a file into a :class:`LogFile`.
    extra : str or None
        The package's optional extra that installs its library (``None``: a core dependency).
    library : str or None
        The module the reader imports (checked before reading, to name the extra when it is missing).
    """

    name: str
    extensions: tuple[str, ...]
    reader: str
    extra: str | None = None
    library: str | None = None  # the module the reader imports (None: a core dependency)


#: The formats :func:`read_log` reads, the one list (the docs, the CLI help and the errors derive from it).
FORMATS = {f.name: f for f in (
    Format("CSV", (".csv",), "obsdesign.data.csvfile:read_csv"),
    Format("MATLAB", (".mat",), "obsdesign.data.matfile:read_mat"),
    Format("TDMS", (".tdms",), "obsdesign.data.tdmsfile:read_tdms", "tdms", "nptdms"),
    Format("MDF4", (".mf4", ".mdf"), "obsdesign.data.mdffile:read_mdf", "mdf", "asammdf"),
    Format("HDF5", (".h5", ".hdf5", ".hdf"), "obsdesign.data.hdf5file:read_hdf5", "hdf5", "h5py"),
    Format("MCAP", (".mcap",), "obsdesign.data.mcapfile:read_mcap", "mcap", "mcap_ros2"),
    Format("Parquet", (".parquet", ".pq"), "obsdesign.data.parquetfile:read_parquet", "parquet", "pyarrow"),
)}


def extensions_text() -> str:
    """``.csv, .mat, .tdms, ...``: every extension :func:`read_log` reads.

    >>> extensions_text()[:20]
    '.csv, .mat, .tdms, .'
    """
    return ", ".join(ext for f in FORMATS.values() for ext in f.extensions)


def format_of(path: Path) -> Format:
    """The :class:`Format` of ``path`` by its extension (case-insensitive).

    Parameters
    ----------
    path : Path
        The file.
    """
    ext = path.suffix.lower()
    for f in FORMATS.values():
        if ext in f.extensions:
            return f
    raise ValueError(f"path: expected a log file ({extensions_text()}), found extension {path.suffix or '(none)'!r}")
