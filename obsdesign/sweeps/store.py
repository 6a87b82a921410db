"""The checkpoint of a sweep folder: ``sweep.json`` (its settings) and ``results.csv`` (one row per run).

``results.csv`` gets one complete line per finished run (one ``write``, flushed),
so an interrupted sweep keeps every finished row; :func:`read_rows` drops a torn
last line. At the end the file is rewritten in run order. Beside it, ``.checksums``
gets ``run,digest`` per row written (:func:`checksum_line`): on resume a row whose
text differs from what the sweep wrote is refused, and a row without a digest (the
process ended between the two writes) is recomputed.
"""

from __future__ import annotations

import csv
import hashlib
import io
from pathlib import Path

from .._format import csv_field
from .summary import STATUS_VALUES

__all__ = ["FIXED_COLUMNS", "TAIL_COLUMNS", "csv_line", "csv_text", "read_rows", "typed_row", "checksum_line",
           "checksums_text"]

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


def checksum_line(columns: list[str], row: dict) -> str:
    """The ``.checksums`` line of a row: its run index and a digest of its CSV text.

    Parameters
    ----------
    columns : list of str
        Column order.
    row : dict
        Values by column.

    Examples
    --------
    >>> checksum_line(["run", "x"], {"run": 3, "x": 0.5})
    '3,3fc7bf8ade41fbae\\n'
    """
    digest = hashlib.sha256(csv_line(columns, row).encode("utf-8")).hexdigest()[:16]
    return f"{row['run']},{digest}\n"


def checksums_text(columns: list[str], rows: list[dict]) -> str:
    """The whole ``.checksums`` file of ``rows``.

    Parameters
    ----------
    columns : list of str
        Column order.
    rows : list of dict
        Values by column.
    """
    return "".join(checksum_line(columns, row) for row in rows)


def _read_checksums(path: Path) -> dict[str, str] | None:
    if not path.is_file():
        return None
    out = {}
    for line in path.read_text(encoding="utf-8", errors="replace").split("\n")[:-1]:  # last: torn or empty
        run, _, digest = line.strip().partition(",")
        out[run] = digest
    return out


def _check_row(row: dict, plan, where: str) -> None:
    """Refuse a row that cannot be a row of this plan (naming file and line)."""
    text = row["run"]
    try:
        run = int(text)
    except ValueError:
        run = -1
    if not 0 <= run < len(plan):
        raise ValueError(f"{where}: run {text!r} is not a run of this sweep (expected 0 to {len(plan) - 1}); "
                         "delete the line to recompute it")
    spec = plan[run]
    planned = {"grid_point": str(spec.grid_point), "sample": str(spec.sample), "seed": str(spec.seed),
               **{name: csv_field(value) for name, value in spec.params.items()}}
    for column, value in planned.items():
        if row[column] != value:
            raise ValueError(f"{where}: run {run}: {column} {row[column]!r} differs from the planned {value!r}; "
                             "delete the line to recompute it")
    if row["status"] not in STATUS_VALUES:
        raise ValueError(f"{where}: run {run}: status {row['status']!r} is not one of {', '.join(STATUS_VALUES)}; "
                         "delete the line to recompute it")
    for column, value in row.items():
        if column in planned or column in FIXED_COLUMNS or column in TAIL_COLUMNS or value in ("", "true", "false"):
            continue
        try:
            float(value)
        except ValueError:
            raise ValueError(f"{where}: run {run}: {column} {value!r} is not a number; "
                             "delete the line to recompute it") from None


def read_rows(path: Path, columns: list[str], plan: list | None = None) -> dict[int, dict]:
    """Completed rows of an interrupted sweep, by run index; a torn last line is dropped.

    With ``plan``, every row is checked: its run index in the plan, grid point, sample,
    seed and parameter values equal to the planned ones, a known status, numbers that
    parse, and its text equal to what the sweep wrote (``.checksums`` beside the file;
    a row without a digest there is left out, i.e. recomputed). A row that fails is
    refused with a ``ValueError`` naming the file and the line.

    Parameters
    ----------
    path : Path
        The ``results.csv`` of the sweep.
    columns : list of str
        The columns the sweep writes.
    plan : list of RunSpec, optional
        The sweep's plan (:func:`obsdesign.sweeps.plan.make_plan`).
    """
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"resume: {str(path)!r} is not UTF-8 text ({e.reason} at byte {e.start})") from None
    lines = text.split("\n")
    if lines and lines[-1] != "":
        lines = lines[:-1]  # no newline at the end: torn
    if not lines or lines[0].rstrip("\r") != ",".join(columns):
        raise ValueError(f"resume: {str(path)!r} does not hold rows of this sweep (different columns)")
    sums = _read_checksums(path.with_name(".checksums")) if plan is not None else None
    done = {}
    reader = csv.DictReader(io.StringIO("\n".join(lines) + "\n"))
    for row in reader:
        where = f"resume: {str(path)!r} line {reader.line_num}"
        if None in row or any(v is None for v in row.values()):
            if plan is not None:
                raise ValueError(f"{where}: expected {len(columns)} fields, found another number; "
                                 "delete the line to recompute it")
            continue
        if plan is None:
            done[int(row["run"])] = row
            continue
        _check_row(row, plan, where)
        if sums is not None:
            digest = sums.get(row["run"])
            if digest is None:
                continue  # written, but its digest was not: recompute
            if checksum_line(columns, row) != f"{row['run']},{digest}\n":
                raise ValueError(f"{where}: run {row['run']}: the row differs from the one the sweep wrote "
                                 f"(its digest in .checksums); delete the line to recompute it")
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
