"""The checkpoint of a sweep folder: ``sweep.json`` (its settings) and ``results.csv`` (one row per run).

``results.csv`` gets one complete line per finished run (one ``write``, flushed),
so an interrupted sweep keeps every finished row; :func:`read_rows` drops a torn
last line. At the end the file is rewritten in run order.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from .._format import csv_field

__all__ = ["FIXED_COLUMNS", "TAIL_COLUMNS", "csv_line", "csv_text", "read_rows", "typed_row"]

FIXED_COLUMNS = ("run", "grid_point", "sample", "seed")
TAIL_COLUMNS = ("status", "error")


def csv_line(columns: list[str], row: dict) -> str:
    """One complete CSV line (quoted where needed), so a single write never tears a row.

    Parameters
    ----------
    columns : list of str
        Column order.
    row : dict
        Values by column.
    """
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([csv_field(row.get(c)) for c in columns])
    return buf.getvalue()


def csv_text(columns: list[str], rows: list[dict]) -> str:
    """The whole ``results.csv``: header and rows.

    Parameters
    ----------
    columns : list of str
        Column order.
    rows : list of dict
        Values by column.
    """
    return ",".join(columns) + "\n" + "".join(csv_line(columns, row) for row in rows)


def read_rows(path: Path, columns: list[str]) -> dict[int, dict]:
    """Completed rows of an interrupted sweep, by run index; a torn last line is dropped.

    Parameters
    ----------
    path : Path
        The ``results.csv`` of the sweep.
    columns : list of str
        The columns the sweep writes.
    """
    text = path.read_text(encoding="utf-8")
    lines = text.split("\n")
    if lines and lines[-1] != "":
        lines = lines[:-1]  # no newline at the end: torn
    if not lines or lines[0] != ",".join(columns):
        raise ValueError(f"resume: {str(path)!r} does not hold rows of this sweep (different columns)")
    done = {}
    for row in csv.DictReader(io.StringIO("\n".join(lines) + "\n")):
        if None in row or any(v is None for v in row.values()):
            continue  # wrong number of fields: torn
        done[int(row["run"])] = row
    return done


def typed_row(row: dict, columns) -> dict:
    """Rows read back from CSV hold strings; convert numbers and booleans.

    Parameters
    ----------
    row : dict
        A row read from CSV (strings).
    columns : list of str
        Its columns.
    """
    out = {}
    for c in columns:
        v = row.get(c)
        if isinstance(v, str) and c not in TAIL_COLUMNS:
            if v == "":
                v = None
            elif v in ("true", "false"):
                v = v == "true"
            else:
                try:
                    v = int(v) if c in FIXED_COLUMNS else float(v)
                except ValueError:
                    pass
        out[c] = v
    return out
