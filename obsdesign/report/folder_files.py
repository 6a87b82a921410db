"""Reading the files of a ``sweep`` or ``compare`` folder for the report, each error naming its file.

Nothing read here becomes markup: a figure is returned as a ``data:image/svg+xml;base64,...``
address for an ``<img>`` element (an SVG shown that way runs no script and loads nothing), text and
JSON are returned as values that the template escapes.
"""

from __future__ import annotations

import base64
import csv
import json
from pathlib import Path
from typing import Any

__all__ = ["read_text", "read_json", "read_csv_rows", "svg_data_url"]


def read_text(path: Path, what: str) -> str:
    """The UTF-8 text of ``path``; ``ValueError`` naming the file if it does not decode.

    Parameters
    ----------
    path : Path
        The file.
    what : str
        The folder kind for the message (``"sweep"``, ``"compare"``).
    """
    try:
        return path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"{what}: {str(path)!r} is not UTF-8 text (byte {e.start}: {e.reason})") from None


def read_json(path: Path, what: str) -> Any:
    """The parsed JSON of ``path``; ``ValueError`` naming the file if it is not UTF-8 JSON.

    Nesting too deep for the parser (``[`` x 100000) is refused the same way, not as a RecursionError.

    Parameters
    ----------
    path : Path
        The file.
    what : str
        The folder kind for the message.
    """
    try:
        return json.loads(path.read_bytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{what}: {str(path)!r} is not valid UTF-8 JSON ({e})") from None
    except RecursionError:
        raise ValueError(f"{what}: {str(path)!r} is not valid UTF-8 JSON (nested too deeply)") from None


def read_csv_rows(path: Path, what: str, columns: tuple[str, ...]) -> list[dict[str, str]]:
    """The rows of a CSV file whose header is exactly ``columns``; ``ValueError`` naming the file otherwise.

    Parameters
    ----------
    path : Path
        The file.
    what : str
        The folder kind for the message.
    columns : tuple of str
        The expected header.
    """
    lines = read_text(path, what).splitlines()
    try:
        reader = csv.DictReader(lines)
        header = tuple(reader.fieldnames or ())
        rows = list(reader)
    except csv.Error as e:
        raise ValueError(f"{what}: {str(path)!r} is not CSV ({e})") from None
    if header != columns:
        raise ValueError(f"{what}: {str(path)!r}: expected the header {','.join(columns)}, "
                         f"found {','.join(header)[:200]!r}")
    return rows


def svg_data_url(path: Path, what: str) -> str:
    """``path`` as a ``data:image/svg+xml;base64,`` address, if it starts like an SVG document.

    Parameters
    ----------
    path : Path
        The figure.
    what : str
        The folder kind for the message.
    """
    data = path.read_bytes()
    if b"<svg" not in data[:4096]:
        raise ValueError(f"{what}: {str(path)!r} is not an SVG figure (no <svg element at its start)")
    return "data:image/svg+xml;base64," + base64.b64encode(data).decode("ascii")
