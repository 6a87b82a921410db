"""A digest of data: the key of a result computed from it (the report's kept figures, issue 37).

Examples
--------
>>> data_digest({"a": (1, 2.5)}) == data_digest({"a": (1, 2.5)}), data_digest(1.0) == data_digest(1)
(True, False)
"""

from __future__ import annotations

import dataclasses
import hashlib
import types
from typing import Any

__all__ = ["data_digest"]


def data_digest(value: Any, ignore: tuple[str, ...] = ()) -> str:
    """SHA-256 of everything reachable from ``value``: the key of a result computed from it.

    Numbers by their bits, arrays by dtype, shape and bytes, strings, slices, containers in their order,
    dataclasses, named tuples and plain objects by their type's qualified name and every attribute
    (``__dict__`` and ``__slots__``), functions and classes by their qualified name. Two values with the
    same digest hold the same data, so a pure function of them gives the same result; an object of
    another kind (a file, a lock, a generator) is a :class:`TypeError` (the caller computes instead).
    Dictionary entries whose key is in ``ignore`` are left out (a run's wall time: not data).

    Examples
    --------
    >>> import numpy as np
    >>> data_digest({"a": np.arange(3.0), "b": (1, 0.1)}) == data_digest({"a": np.arange(3.0), "b": (1, 0.1)})
    True
    >>> data_digest(np.arange(3.0)) == data_digest(np.arange(3))          # another dtype
    False
    >>> data_digest([0.1 + 0.2]) == data_digest([0.3])                    # another double
    False
    """
    h = hashlib.sha256()
    _digest_into(h, value, set(), 0, frozenset(ignore))
    return h.hexdigest()


def _digest_into(h: Any, value: Any, active: set, depth: int, ignore: frozenset = frozenset()) -> None:
    if depth > 200:
        raise TypeError("data_digest: nested deeper than 200 levels")
    if value is None or isinstance(value, (bool, int, str, bytes)):
        h.update(f"{type(value).__name__}:{len(value) if isinstance(value, (str, bytes)) else ''}:".encode())
        h.update(value if isinstance(value, bytes) else repr(value).encode() if not isinstance(value, str)
                 else value.encode("utf-8", "surrogatepass"))
        return
    if isinstance(value, (float, complex)):
        h.update((f"({value.real.hex()},{value.imag.hex()})" if isinstance(value, complex) else float(value).hex()).encode() + b";")
        return
    if isinstance(value, (types.FunctionType, types.BuiltinFunctionType, type, types.ModuleType)):
        h.update(f"callable:{getattr(value, '__module__', '')}.{getattr(value, '__qualname__', value.__name__)};".encode())
        return
    if isinstance(value, (slice, range)):
        h.update(f"{type(value).__name__}:".encode())
        for part in (value.start, value.stop, value.step):
            _digest_into(h, part, active, depth + 1, ignore)
        return
    if type(value).__module__ == "numpy" and hasattr(value, "dtype"):  # arrays and NumPy scalars
        import numpy as np

        arr = np.asarray(value)
        if arr.dtype.hasobject:
            h.update(f"objects{arr.shape}:".encode())
            for item in arr.ravel():
                _digest_into(h, item, active, depth + 1, ignore)
            return
        h.update(f"nd:{arr.dtype.str}:{arr.shape}:".encode())
        h.update(np.ascontiguousarray(arr).tobytes())
        return
    if id(value) in active:
        raise TypeError("data_digest: a cycle")
    active.add(id(value))
    try:
        h.update(f"{type(value).__module__}.{type(value).__qualname__}(".encode())
        if isinstance(value, (list, tuple)):
            for item in value:
                _digest_into(h, item, active, depth + 1, ignore)
        elif isinstance(value, dict):
            for k, item in value.items():
                if k in ignore:
                    continue
                _digest_into(h, k, active, depth + 1, ignore)
                _digest_into(h, item, active, depth + 1, ignore)
        elif isinstance(value, (set, frozenset)):
            for text in sorted(data_digest(item, tuple(ignore)) for item in value):
                h.update(text.encode())
        elif dataclasses.is_dataclass(value) or hasattr(value, "__dict__") or hasattr(type(value), "__slots__"):
            attrs = dict(vars(value)) if hasattr(value, "__dict__") else {}
            for cls in type(value).__mro__:
                for name in getattr(cls, "__slots__", ()):
                    if name not in attrs and hasattr(value, name):
                        attrs[name] = getattr(value, name)
            for name in sorted(attrs):
                _digest_into(h, name, active, depth + 1, ignore)
                _digest_into(h, attrs[name], active, depth + 1, ignore)
        else:
            raise TypeError(f"data_digest: cannot digest a {type(value).__name__}")
        h.update(b")")
    finally:
        active.discard(id(value))
