"""Reading a Parquet file (data pipelines) with pyarrow: columns by name, units from field metadata.

Struct columns are flattened (``joint.position``); a column's unit is its field metadata ``unit``
(or ``units``); a timestamp column is read as seconds since its first value. Needs the extra
``parquet`` (``pip install "obsdesign[parquet]"``).

Examples
--------
>>> import tempfile, pathlib
>>> import pyarrow as pa, pyarrow.parquet as pq
>>> with tempfile.TemporaryDirectory() as d:
...     path = pathlib.Path(d) / "run.parquet"
...     field = pa.field("pos", pa.float64(), metadata={"unit": "mm"})
...     pq.write_table(pa.table({"pos": [1.0, 2.0]}, schema=pa.schema([field])), path)
...     log = read_parquet(path)
>>> log.channels["pos"].unit, log.channels["pos"].values.tolist()
('mm', [1.0, 2.0])
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .logfile import Channel, LogFile

__all__ = ["read_parquet"]


def read_parquet(path: Path) -> LogFile:
    """The numeric and timestamp columns of a Parquet file.

    Parameters
    ----------
    path : Path
        The ``.parquet`` file.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pq.read_table(str(path))
    while any(pa.types.is_struct(f.type) for f in table.schema):
        table = table.flatten()
    channels = {}
    for field, column in zip(table.schema, table.columns):
        meta = {k.decode("utf-8", "replace"): v.decode("utf-8", "replace") for k, v in (field.metadata or {}).items()}
        unit = (meta.get("unit") or meta.get("units") or "").strip() or None
        if pa.types.is_timestamp(field.type):
            ns = column.cast(pa.timestamp("ns")).to_numpy(zero_copy_only=False).astype("int64")
            values = (ns - ns[0]) / 1e9 if ns.size else ns.astype(float)
            unit = "s"
        elif pa.types.is_integer(field.type) or pa.types.is_floating(field.type) or pa.types.is_boolean(field.type):
            values = column.to_numpy(zero_copy_only=False)
        else:
            continue
        channels[field.name] = Channel(name=field.name, values=np.asarray(values), unit=unit,
                                       unit_from="file" if unit else "")
    meta = {k.decode("utf-8", "replace"): v.decode("utf-8", "replace")[:200]
            for k, v in (table.schema.metadata or {}).items() if not k.startswith(b"ARROW:")}
    return LogFile(name=path.name, format="Parquet", channels=channels, metadata=meta, kind="column")
