"""Reading an MCAP file (ROS 2 recordings) with mcap and mcap-ros2-support: joint states and numeric fields.

ROS 2 messages (CDR encoded) are decoded by their schema. A message with a ``name`` list and
lists of as many numbers beside it (``sensor_msgs/msg/JointState``: ``position``, ``velocity``,
``effort``) gives a channel per joint and list: ``/joint_states/position/joint1``. Any other
numeric field, nested ones too, gives ``/topic/field/subfield`` (``/cmd/data`` of a
``std_msgs/msg/Float64``). The time base of a topic's channels is the message's
``header.stamp`` where it has one, else the log time, in seconds since the topic's first message (messages in the order of their stamps).
ROS uses SI units (REP 103) but does not write them: a revolute joint's position is in rad and
its effort in N m, give them (``--position-unit rad --input-unit "N m"``). Needs the extra
``mcap`` (``pip install "obsdesign[mcap]"``).
"""

from __future__ import annotations

from numbers import Real
from pathlib import Path

import numpy as np

from .logfile import Channel, FileRefused, LogFile

__all__ = ["read_mcap"]

_MAGIC = b"\x89MCAP0\r\n"
_MISSING = float("nan")  # a joint or field missing from one message


def _fields(msg) -> list[str]:
    return [f for f in getattr(msg, "__slots__", ()) if not f.startswith("_")]


def _stamp(msg) -> int | None:
    header = getattr(msg, "header", None)
    stamp = getattr(header, "stamp", None)
    if stamp is None or not hasattr(stamp, "sec"):
        return None
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _flatten(prefix: str, msg, out: dict) -> None:
    """``out[name] = value`` for every number of ``msg`` (joint lists by joint name)."""
    fields = _fields(msg)
    names = getattr(msg, "name", None) if "name" in fields else None
    joints = list(names) if isinstance(names, (list, tuple)) and all(isinstance(n, str) for n in names) else None
    for f in fields:
        if f == "header" or (f == "name" and joints is not None):
            continue
        value = getattr(msg, f)
        key = f"{prefix}/{f}"
        if isinstance(value, bool) or isinstance(value, Real):
            out[key] = float(value)
        elif isinstance(value, (list, tuple, np.ndarray)) and len(value) and all(
                isinstance(v, Real) for v in value):
            labels = joints if joints is not None and len(joints) == len(value) else [str(i) for i in
                                                                                       range(len(value))]
            for label, v in zip(labels, value):
                out[f"{key}/{label}"] = float(v)
        elif _fields(value):
            _flatten(key, value, out)


def read_mcap(path: Path) -> LogFile:
    """The numeric channels of the ROS 2 messages of an MCAP file.

    Parameters
    ----------
    path : Path
        The ``.mcap`` file.
    """
    with open(path, "rb") as fh:
        if fh.read(8) != _MAGIC:
            raise FileRefused(f"path: expected an MCAP file (it starts with the MCAP magic), found other bytes at "
                              f"the start of {path.name!r}")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    series: dict[str, dict[str, list]] = {}
    times: dict[str, list[int]] = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
            if channel.message_encoding != "cdr":
                raise FileRefused(f"path: expected ROS 2 (cdr) messages, found the encoding "
                                  f"{channel.message_encoding!r} on {channel.topic!r} of {path.name!r}")
            values: dict[str, float] = {}
            _flatten(channel.topic.rstrip("/") or "/", decoded, values)
            stamp = _stamp(decoded)
            topic = series.setdefault(channel.topic, {})
            n = len(times.setdefault(channel.topic, []))
            times[channel.topic].append(message.log_time if stamp is None else stamp)
            for key, value in values.items():
                if key not in topic:
                    topic[key] = [_MISSING] * n
                topic[key].append(value)
            for key, column in topic.items():
                if len(column) == n:
                    column.append(_MISSING)
    channels = {}
    for name, columns in series.items():
        ns = np.asarray(times[name], dtype=np.int64)
        order = np.argsort(ns, kind="stable")  # the file's order is the writer's; the time base is the stamps'
        time = (ns[order] - ns[order[0]]) / 1e9
        for key, column in columns.items():
            channels[key] = Channel(name=key, values=np.asarray(column, dtype=float)[order], time=time)
    return LogFile(name=path.name, format="MCAP", channels=channels, metadata={})

