"""A quick check that an address is a Dask scheduler, before ``distributed`` connects to it.

``distributed`` trusts the first bytes a peer sends: a port that answers something else
(an HTTP server, a proxy) makes it read a frame length of exabytes, and a port that
accepts but stays silent can hold it far beyond its ``timeout``. A Dask scheduler sends
its handshake as soon as a connection is accepted, a small message whose first 8 bytes
are its length (native ``uint64``). :func:`probe_scheduler` reads those 8 bytes within
a time limit and refuses anything else with one line.

Examples
--------
>>> probe_scheduler("tcp://127.0.0.1", timeout=1.0)
Traceback (most recent call last):
...
ValueError: scheduler: expected an address tcp://HOST:PORT, found 'tcp://127.0.0.1'
"""

from __future__ import annotations

import socket
import struct
import time

__all__ = ["probe_scheduler"]

#: Largest first message accepted from a scheduler (its handshake is a few hundred bytes).
_MAX_HANDSHAKE = 1 << 20


def probe_scheduler(address: str, *, timeout: float = 5.0) -> None:
    """Refuse ``address`` unless a Dask scheduler answers there within ``timeout`` seconds.

    Parameters
    ----------
    address : str
        ``tcp://HOST:PORT`` (other schemes, such as ``tls://``, are left to ``distributed``).
    timeout : float
        Seconds for connecting and for the scheduler's first bytes each.

    Raises
    ------
    ValueError
        Naming the address and what was found.
    """
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme != "tcp":
        return
    host, colon, port_text = rest.rstrip("/").rpartition(":")
    if not colon or not host or not port_text.isdigit() or not 0 < int(port_text) < 65536:
        raise ValueError(f"scheduler: expected an address tcp://HOST:PORT, found {address!r}")
    host = host.strip("[]")
    try:
        with socket.create_connection((host, int(port_text)), timeout=timeout) as sock:
            deadline = time.monotonic() + timeout
            head = b""
            while len(head) < 8:
                sock.settimeout(max(0.01, deadline - time.monotonic()))
                chunk = sock.recv(8 - len(head))
                if not chunk:
                    raise ValueError(f"scheduler: {address!r} closed the connection without a Dask handshake; "
                                     "expected a Dask scheduler")
                head += chunk
    except socket.timeout:
        raise ValueError(f"scheduler: {address!r} sent no Dask handshake within {timeout:g} s; "
                         "expected a Dask scheduler (is it a dashboard or another service?)") from None
    except OSError as e:
        raise ValueError(f"scheduler: cannot reach {address!r} ({e.strerror or e})") from None
    (length,) = struct.unpack("Q", head)
    if not 0 < length <= _MAX_HANDSHAKE:
        raise ValueError(f"scheduler: {address!r} answered {head!r}, not a Dask handshake; "
                         "expected a Dask scheduler")
