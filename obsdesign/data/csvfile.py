"""Reading a logged CSV table as the tools write it: a header block, a units row, a decimal comma.

The table is a header row of column names above numeric rows; above it may stand a header block
(``Key;Value`` lines, kept as the log's metadata), between the names and the numbers a row of units
(``s;mm;A``). Lines starting with ``#`` are comments anywhere. The delimiter (``,`` ``;`` tab ``|``
whitespace) and the decimal mark (``.`` or ``,``; a comma only where the delimiter is not one) are
detected or given; digit grouping (``1.234,5``, ``1,234.5``) is refused. UTF-8 with or without a
byte-order mark, UTF-16 with one, and else Latin-1 (what Windows tools in a European locale write).
A column's unit comes from its name where it is written there (``pos [mm]``, ``pos (mm)``: the
name is then ``pos``; ``pos_mm``: a hint used where it fits) or from the units row.

Examples
--------
>>> import tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "log.csv"
...     _ = p.write_text("# axis 2, run 7\\ntime_ms;pos_mm\\n0;1.5\\n1;1.75\\n")
...     table = read_csv(p)
>>> list(table.channels), table.channels["pos_mm"].values.tolist()
(['time_ms', 'pos_mm'], [1.5, 1.75])
>>> detect_delimiter("a;b;c", "1,5;2;3")
';'
"""

from __future__ import annotations

import codecs
import csv
import io
import re
from pathlib import Path

import numpy as np

from .._validate import MAX_CSV_BYTES, MAX_CSV_LINE
from .logfile import Channel, FileRefused, LogFile

__all__ = ["read_csv", "detect_delimiter", "DELIMITERS", "parse_delimiter", "DECIMALS", "parse_decimal"]

#: Delimiter names accepted by ``--delimiter`` and ``load_trace(delimiter=...)``; ``space``: any whitespace.
DELIMITERS = {",": ",", ";": ";", "tab": "\t", "\t": "\t", "|": "|", "space": " ", " ": " "}
#: Decimal marks accepted by ``--decimal`` and ``load_trace(decimal=...)``.
DECIMALS = (".", ",")
#: A number written with digit grouping (``1.234,5``, ``1,234.5``, ``1'234``, ``1 234``).
_GROUPED = re.compile(r"^[+-]?\d{1,3}([.,'\u00a0\u202f ]\d{3})+([.,]\d*)?$")
#: A unit written in a column's name: ``pos [mm]``, ``pos[mm]``, ``pos (mm)``, ``pos / mm``.
_NAME_UNIT = re.compile(r"^(?P<name>.*?)(?:\s*\[(?P<b>[^\[\]]*)\]|\s+\((?P<p>[^()]*)\)|\s+/\s+(?P<s>\S+))$")
#: A unit hint at the end of a name: ``pos_mm``, ``i_mA``, ``torque_pct`` (letters, µ, % only).
_SUFFIX = re.compile(r"_(?P<unit>[A-Za-z\u00b5\u03bc%]{1,6})$")


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


def parse_decimal(value: object) -> str | None:
    """The decimal mark ``'.'`` or ``','`` (``None``: detect it).

    Parameters
    ----------
    value : str or None
        ``'.'`` or ``','``.

    Examples
    --------
    >>> parse_decimal(",")
    ','
    """
    if value is None or (isinstance(value, str) and value in DECIMALS):
        return value
    raise ValueError(f"decimal: expected '.' or ',' (or None to detect it), found {value!r}")


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


def _number(text: str, decimal: str) -> float | None:
    """The number ``text`` with the decimal mark ``decimal``, or ``None``."""
    text = text.strip()
    if decimal == ",":
        if "." in text:
            return None
        text = text.replace(",", ".")
    try:
        return float(text)
    except ValueError:
        return None


def _decode(path: Path) -> tuple[str, str]:
    raw = path.read_bytes()
    if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        try:
            return raw.decode("utf-16"), "UTF-16"
        except UnicodeDecodeError as e:
            raise FileRefused(f"path: expected a text CSV file, found a UTF-16 byte-order mark and undecodable "
                              f"bytes at byte {e.start} of {path.name!r}") from None
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise FileRefused(f"path: expected a text CSV file, found a NUL byte at byte {nul} of {path.name!r} "
                          "(a binary file)")
    try:
        return raw.decode("utf-8-sig"), "UTF-8"
    except UnicodeDecodeError:
        return raw.decode("latin-1"), "Latin-1"


def _name_and_unit(text: str) -> tuple[str, str | None, str]:
    """A header field's name, its unit and where the unit was found (``'header'``, ``'name'``, ``''``)."""
    m = _NAME_UNIT.match(text)
    if m and m.group("name").strip():
        unit = next(g for g in (m.group("b"), m.group("p"), m.group("s")) if g is not None).strip()
        return m.group("name").strip(), unit or None, "header" if unit else ""
    m = _SUFFIX.search(text)
    return text, (m.group("unit") if m else None), ("name" if m else "")


def _is_units_row(fields: list[str]) -> bool:
    from .units import is_unit

    units = [f.strip().strip("[]()").strip() for f in fields]
    return any(units) and all(is_unit(u) for u in units if u)


def _table_start(lines: list[tuple[int, str]], delimiter: str | None) -> tuple[str, int, int]:
    """The delimiter, the index of the first numeric row and its field count."""
    for delim in (delimiter,) if delimiter is not None else (",", ";", "\t", "|", " "):
        for k, (_, line) in enumerate(lines):
            fields = _split(line, delim)
            if len(fields) < 2 or not all(_number(f, ".") is not None or _number(f, ",") is not None
                                          for f in fields):
                continue
            if k > 0 and len(_split(lines[k - 1][1], delim)) == len(fields):
                return delim, k, len(fields)
            break
    return "", -1, 0


def _bad_field(fields: list[str], decimal: str) -> str:
    bad = next(f for f in fields if _number(f, decimal) is None)
    if _GROUPED.match(bad.strip()) and _number(bad, "," if decimal == "." else ".") is None:
        return f"{bad!r}; digit grouping (thousands separators) is not read: export the numbers without it"
    if decimal == "." and _number(bad, ",") is not None:
        return f"{bad!r}; a decimal comma: read it with decimal=',' (--decimal ',')"
    if decimal == "," and _number(bad, ".") is not None:
        return f"{bad!r}; a decimal point in a file read with decimal ',' (digit grouping, or --decimal '.')"
    return repr(bad)


def read_csv(path: Path, delimiter: str | None = None, decimal: str | None = None) -> LogFile:
    """The CSV file's columns, their units and its header block.

    Parameters
    ----------
    path : Path
        The CSV file (UTF-8, UTF-16 with a byte-order mark, or Latin-1).
    delimiter : str, optional
        The delimiter character (``' '``: any whitespace); default: the first of ``,`` ``;`` tab ``|``
        whitespace that splits a row into numbers and the line above it into as many fields.
    decimal : {'.', ','}, optional
        The decimal mark; default ``','`` where the delimiter is not a comma and the rows hold commas
        but no points, else ``'.'``.

    Returns
    -------
    LogFile
        ``format`` ``'CSV'``; ``metadata``: the header block's ``Key;Value`` lines and ``encoding``,
        ``delimiter``, ``decimal``.
    """
    if path.stat().st_size > MAX_CSV_BYTES:  # issue 36: sizes with a ceiling (and the line check below)
        raise FileRefused(f"path: expected a CSV file of at most {MAX_CSV_BYTES} bytes, found {path.stat().st_size}")
    text, encoding = _decode(path)
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines())
             if line.strip() and not line.lstrip().startswith("#")]
    no, line = max(lines, key=lambda item: len(item[1]), default=(0, ""))
    if len(line) > MAX_CSV_LINE:
        raise FileRefused(f"path: expected CSV lines of at most {MAX_CSV_LINE} characters, found {len(line)} on line "
                         f"{no} of {path.name!r}")
    if not lines:
        raise FileRefused(f"path: expected a CSV file with a header row of column names, found no line that is "
                          f"neither empty nor a '#' comment in {path.name!r}")
    found = delimiter is None
    delim, k, n = _table_start(lines, delimiter)
    if k < 0:  # no numeric row below a line of as many fields: name the first row that is not numeric
        delim = delimiter or detect_delimiter(lines[0][1], lines[1][1] if len(lines) > 1 else lines[0][1])
        how = f"the delimiter {_name(delim)}" + (" (detected; set it with --delimiter)" if found else "")
        if all(_number(f, ".") is not None or _number(f, ",") is not None for f in _split(lines[0][1], delim)):
            raise FileRefused(f"path: expected a header row of column names above the numeric rows, found numbers on "
                              f"line {lines[0][0]} of {path.name!r}")
        if len(lines) < 2:
            raise FileRefused(f"path: expected numeric CSV rows below the header (line {lines[0][0]}), found none in "
                              f"{path.name!r}")
        no, line = lines[1]
        for other in (delimiter,) if delimiter is not None else (",", ";", "\t", "|", " "):
            fields = _split(line, other)
            if len(fields) > 1 and all(_number(f, ".") is not None or _number(f, ",") is not None for f in fields):
                n_head = len(_split(lines[0][1], other))
                raise FileRefused(f"path: expected {n_head} values per row (one per header name, split by the "
                                  f"delimiter {_name(other)}), found {len(fields)} on line {no} of {path.name!r}")
        fields = _split(line, delim)
        dec = decimal or "."
        shown = _bad_field(fields, dec) if any(_number(f, dec) is None for f in fields) else repr(line)
        raise FileRefused(f"path: expected numeric CSV rows below the header (line {lines[0][0]}), found {shown} on "
                          f"line {no} of {path.name!r} (split by {how})")
    body = lines[k:]
    if decimal is None:
        joined = "".join(line for _, line in body)
        decimal = "," if delim != "," and "," in joined and "." not in joined else "."
    elif decimal == delim:
        raise FileRefused(f"decimal: expected a decimal mark other than the delimiter, found {decimal!r} for both")
    how = (f"the delimiter {_name(delim)}" + (" (detected; set it with --delimiter)" if found else "")
           + f", decimal {decimal!r}")
    upper = [(no, _split(line, delim)) for no, line in lines[max(0, k - 2):k]]
    units_row = None
    if len(upper) == 2 and len(upper[0][1]) == n and _is_units_row(upper[1][1]):
        (head_no, raw_names), (units_no, units_row) = upper
        block_end = k - 2
    else:
        head_no, raw_names = upper[-1]
        block_end = k - 1
        if any(_number(f, decimal) is not None for f in raw_names):
            raise FileRefused(f"path: expected a header row of {n} column names above the first numeric row "
                              f"(line {lines[k][0]}), found numbers in line {head_no} of {path.name!r}")
    metadata = {}
    for _, line in lines[:block_end]:
        fields = [f.strip() for f in _split(line, delim)] if delim != " " else line.split(None, 1)
        if len(fields) == 1:
            key, _, value = fields[0].partition(next((c for c in fields[0] if c in ":="), "\0"))
            fields = [key, value]
        key = fields[0].strip()
        if key:
            metadata[key] = " ".join(f for f in fields[1:] if f).strip()
    metadata.update(encoding=encoding, delimiter=_name(delim).strip("'"), decimal=decimal)
    names, units = [], []
    for i, raw in enumerate(raw_names):
        name, unit, where = _name_and_unit(raw.strip().strip('"').strip("'").strip())
        if units_row is not None:
            row_unit = units_row[i].strip().strip("[]()").strip()
            if row_unit:
                unit, where = row_unit, "units row"
        names.append(name)
        units.append((unit, where))
    seen: dict[str, int] = {}
    for i, name in enumerate(names):
        if name in seen:
            raise FileRefused(f"path: expected distinct column names in {path.name!r}, found {name!r} as columns "
                              f"{seen[name] + 1} and {i + 1} of the header on line {head_no} (names are compared "
                              f"after stripping spaces, quotes and a unit in brackets)")
        seen[name] = i
    data = None
    try:
        body_text = "\n".join(line for _, line in body)
        if decimal == ",":
            if "." in body_text:
                raise ValueError("a point in a decimal-comma file")
            body_text = body_text.replace(",", ".")
        parsed = np.loadtxt(io.StringIO(body_text), ndmin=2, dtype=float, delimiter=None if delim == " " else delim,
                            comments=None)
        if parsed.size and parsed.shape[1] == n:
            data = parsed
    except ValueError:
        pass  # diagnosed line by line below
    if data is None:
        rows = []
        for no, line in body:
            fields = _split(line, delim)
            if len(fields) != n:
                raise FileRefused(f"path: expected {n} values per row (one per header name, split by {how}), "
                                  f"found {len(fields)} on line {no} of {path.name!r}")
            values = [_number(f, decimal) for f in fields]
            if any(v is None for v in values):
                raise FileRefused(f"path: expected numeric CSV rows below the header (line {head_no}), found "
                                  f"{_bad_field(fields, decimal)} on line {no} of {path.name!r} (split by {how})")
            rows.append(values)
        data = np.array(rows, dtype=float).reshape(len(rows), n)
    channels = {name: Channel(name=name, values=data[:, i], unit=unit, unit_from=where if unit else "")
                for i, (name, (unit, where)) in enumerate(zip(names, units))}
    return LogFile(name=path.name, format="CSV", channels=channels, metadata=metadata, kind="column")

