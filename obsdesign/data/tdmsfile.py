"""Reading a TDMS file (LabVIEW, NI DAQ) with npTDMS: ``group/channel`` channels, units, the waveform time.

Each channel is named ``group/channel``; its unit is the ``unit_string`` property; its own time
base is ``wf_start_offset + k * wf_increment`` [s] where the channel is a waveform (``wf_increment``
set, ``wf_xunit_string`` seconds or absent). Needs the extra ``tdms`` (``pip install "obsdesign[tdms]"``).

Examples
--------
>>> import tempfile, pathlib
>>> import numpy as np
>>> from nptdms import ChannelObject, TdmsWriter
>>> with tempfile.TemporaryDirectory() as d:
...     path = pathlib.Path(d) / "run.tdms"
...     with TdmsWriter(path) as w:
...         w.write_segment([ChannelObject("axis", "pos", np.arange(4.0), properties={
...             "unit_string": "mm", "wf_increment": 0.001, "wf_start_offset": 0.0})])
...     log = read_tdms(path)
>>> ch = log.channels["axis/pos"]
>>> ch.unit, ch.time.tolist(), log.format
('mm', [0.0, 0.001, 0.002, 0.003], 'TDMS')
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .logfile import Channel, LogFile

__all__ = ["read_tdms"]


def _text(props: dict, *keys: str) -> str | None:
    for key in keys:
        value = props.get(key)
        if isinstance(value, str) and value.strip():
            return value.strip()
    return None


def read_tdms(path: Path) -> LogFile:
    """The channels of a TDMS file (named ``group/channel``).

    Parameters
    ----------
    path : Path
        The ``.tdms`` file.
    """
    from nptdms import TdmsFile

    f = TdmsFile.read(str(path))
    channels = {}
    for group in f.groups():
        for ch in group.channels():
            props = dict(ch.properties)
            values = np.asarray(ch[:])
            time = None
            inc = props.get("wf_increment")
            xunit = _text(props, "wf_xunit_string")
            if inc is not None and float(inc) > 0 and xunit in (None, "s", "sec", "Seconds", "seconds"):
                time = float(props.get("wf_start_offset", 0.0) or 0.0) + np.arange(values.size) * float(inc)
            name = f"{group.name}/{ch.name}"
            unit = _text(props, "unit_string", "unit", "NI_UnitDescription")
            channels[name] = Channel(name=name, values=values, unit=unit, unit_from="file" if unit else "", time=time)
    meta = {str(k): str(v) for k, v in f.properties.items()}
    return LogFile(name=path.name, format="TDMS", channels=channels, metadata=meta)
