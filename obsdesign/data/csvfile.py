"""Reading a logged CSV table: ``#`` comment lines, a header row, the delimiter found or given.

Examples
--------
>>> import tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "log.csv"
...     _ = p.write_text("# axis 2, run 7\\ntime_ms;pos_mm\\n0;1.5\\n1;1.75\\n")
...     table = read_csv(p)
>>> sorted(table), table["pos_mm"].tolist()
(['pos_mm', 'time_ms'], [1.5, 1.75])
>>> detect_delimiter("a;b;c", "1,5;2;3")
';'
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from .._validate import MAX_CSV_BYTES, MAX_CSV_LINE

__all__ = ["read_csv", "detect_delimiter", "DELIMITERS", "parse_delimiter"]

#: Delimiter names accepted by ``--delimiter`` and ``load_trace(delimiter=...)``; ``space``: any whitespace.
DELIMITERS = {",": ",", ";": ";", "tab": "\t", "\t": "\t", "|": "|", "space": " ", " ": " "}


def parse_delimiter(value: object) -> str | None:
    """The delimiter character for a name of :data:`DELIMITERS` (``None``: detect it).

    Parameters
    ----------
    value : str or None
        ``','``, ``';'``, ``'tab'``, ``'space'``, ``'|'`` (or the character itself).
    """
    if value is None:
        return None
    if not isinstance(value, str) or value not in DELIMITERS:
        raise ValueError(f"delimiter: expected one of ',', ';', 'tab', 'space', '|' (or None to detect it), "
                         f"found {value!r}")
    return DELIMITERS[value]


def _split(line: str, delimiter: str) -> list[str]:
    if delimiter == " ":
        return line.split()
    return next(csv.reader([line], delimiter=delimiter, skipinitialspace=True))


def detect_delimiter(header: str, first_row: str) -> str:
    """The delimiter that splits ``header`` and ``first_row`` into the same number (> 1) of fields.

    Tried in the order ``,`` ``;`` tab ``|`` whitespace; a comma only if the row has no
    semicolon-separated fields of the same count (a decimal comma in a ``;`` file); ``,`` when
    none fits (a one-column file).

    Parameters
    ----------
    header : str
        The header line.
    first_row : str
        The first data line.
    """
    for delimiter in (",", ";", "\t", "|", " "):
        n_header, n_row = len(_split(header, delimiter)), len(_split(first_row, delimiter))
        if n_header > 1 and n_header == n_row:
            return delimiter
    return ","


def _name(delimiter: str) -> str:
    return {"\t": "tab", " ": "space"}.get(delimiter, repr(delimiter))


def read_csv(path: Path, delimiter: str | None = None) -> dict[str, np.ndarray]:
    """Columns by header name; lines starting with ``#`` (after spaces) are skipped everywhere.

    Parameters
    ----------
    path : Path
        The CSV file (UTF-8).
    delimiter : str, optional
        The delimiter character (``' '``: any whitespace); default :func:`detect_delimiter`.
    """
    if path.stat().st_size > MAX_CSV_BYTES:  # issue 36: sizes with a ceiling (and the next check)
        raise ValueError(f"path: expected a CSV file of at most {MAX_CSV_BYTES} bytes, found {path.stat().st_size}")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise ValueError(f"path: expected a UTF-8 text CSV file, found undecodable bytes at byte {e.start} "
                         f"of {path.name!r}") from e
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines())
             if line.strip() and not line.lstrip().startswith("#")]
    no, line = max(lines, key=lambda item: len(item[1]), default=(0, ""))
    if len(line) > MAX_CSV_LINE:
        raise ValueError(f"path: expected CSV lines of at most {MAX_CSV_LINE} characters, found {len(line)} on line "
                         f"{no} of {path.name!r}")
    if not lines:
        raise ValueError(f"path: expected a CSV file with a header row of column names, found no line that is "
                         f"neither empty nor a '#' comment in {path.name!r}")
    head_no, head = lines[0]
    body = lines[1:]
    if not body:  # issue 36: numpy's loadtxt would warn (a UserWarning naming a StringIO) before the error
        raise ValueError(f"path: expected rows of numbers below the header (line {head_no}), found none in {path.name!r}")
    found = delimiter is None
    if found:
        delimiter = detect_delimiter(head, body[0][1] if body else head)
    header = [h.strip().strip('"').strip("'").strip() for h in _split(head, delimiter)]
    how = f"the delimiter {_name(delimiter)}" + (" (detected; set it with --delimiter)" if found else "")
    seen: dict[str, int] = {}
    for i, name in enumerate(header):
        if name in seen:
            raise ValueError(f"path: expected distinct column names in {path.name!r}, found {name!r} as columns "
                             f"{seen[name] + 1} and {i + 1} of the header on line {head_no} (names are compared "
                             f"after stripping spaces and quotes)")
        seen[name] = i
    try:
        data = np.loadtxt(io.StringIO("\n".join(line for _, line in body)), ndmin=2, dtype=float,
                          delimiter=None if delimiter == " " else delimiter, comments=None)
        if data.size and data.shape[1] == len(header):
            return {name: data[:, i] for i, name in enumerate(header)}
    except ValueError:
        pass  # diagnosed line by line below
    rows = []
    for no, line in body:
        fields = _split(line, delimiter)
        if len(fields) != len(header):
            raise ValueError(f"path: expected {len(header)} values per row (one per header name, split by {how}), "
                             f"found {len(fields)} on line {no} of {path.name!r}")
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            bad = next(f for f in fields if not _is_float(f))
            hint = "; decimal commas are not read: use a decimal point" if "," in bad and delimiter != "," else ""
            raise ValueError(f"path: expected numeric CSV rows below the header (line {head_no}), found {bad!r} on "
                             f"line {no} of {path.name!r} (split by {how}){hint}") from None
    data = np.array(rows, dtype=float).reshape(len(rows), len(header))
    return {name: data[:, i] for i, name in enumerate(header)}


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True

