"""An on-disk memo of pure results: computed once per input, code and library version.

Some numbers every command prints come from heavy libraries: the stability certificate's searched
Lyapunov matrix (SciPy's Nelder-Mead from SciPy's Lyapunov solutions), the PID loop's margins,
peaks and poles (python-control), the report's symbolic derivation (SymPy). Importing those
libraries is most of a short command's time. This module keeps such a result on disk, keyed by

- a *namespace* (what is computed) and the exact inputs (floats by their bits, ``float.hex``);
- the package's own source (a SHA-256 of every ``.py`` and ``.toml`` file of ``obsdesign``: code and
  presets), so any edit of what computes a value is a new key;
- the installed NumPy, SciPy, python-control and SymPy (their distribution folders' names, which hold
  the versions, read beside them without importing them) and the Python version.

Only pure functions of that key are kept. A hit returns exactly the value the computation returned
(floats stored by their ``repr``, which round-trips every double), so outputs are identical with and
without the memo; ``tests/test_memo.py`` compares each kept result with a fresh computation. The
certificate's searched ``P`` is only a proposal: it is verified (NumPy) on every call, whatever its
origin, so even an entry edited by hand cannot certify a design.

The folder is ``$OBSDESIGN_CACHE_DIR``, else ``$XDG_CACHE_HOME/obsdesign``, else
``~/.cache/obsdesign``; ``OBSDESIGN_CACHE=off`` turns the memo off. Entries are written atomically
(temporary file, then rename); an unreadable, corrupt or unwritable entry is recomputed, never an
error. ``obsdesign cache --clear`` is not needed: deleting the folder is always safe.

Examples
--------
>>> import os, tempfile
>>> saved = os.environ.get("OBSDESIGN_CACHE_DIR")
>>> os.environ["OBSDESIGN_CACHE_DIR"] = tempfile.mkdtemp()
>>> calls = []
>>> def work():
...     calls.append(1)
...     return {"x": 0.1 + 0.2, "poles": [complex(-1.0, 2.0)], "m": float("inf")}
>>> a = memo("doc", (1.5, 2), work)
>>> b = memo("doc", (1.5, 2), work)
>>> a == b, a["x"] == 0.1 + 0.2, len(calls)
(True, True, 1)
>>> memo("doc", (1.5, 3), work)["m"], len(calls)      # another input: computed
(inf, 2)
>>> _ = os.environ.pop("OBSDESIGN_CACHE_DIR") if saved is None else os.environ.update(OBSDESIGN_CACHE_DIR=saved)
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import sys
from pathlib import Path
from typing import Any, Callable

__all__ = ["memo", "cache_dir", "enabled", "fingerprint", "source_hash", "list_of", "config_key"]

#: The libraries whose versions are part of every key (their results are what is kept); each installs
#: as ``<name>-<version>.dist-info`` beside its package (python-control's wheel as ``control-``).
_LIBRARIES = ("numpy", "scipy", "control", "sympy")
_FINGERPRINT: str | None = None


def enabled() -> bool:
    """False when ``OBSDESIGN_CACHE`` is ``off``, ``0``, ``no`` or ``false``."""
    return os.environ.get("OBSDESIGN_CACHE", "on").strip().lower() not in ("off", "0", "no", "false")


def cache_dir() -> Path:
    """The memo's folder (not created here)."""
    explicit = os.environ.get("OBSDESIGN_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "obsdesign"


def _library_versions() -> list[str]:
    import importlib.util

    out = []
    for name in _LIBRARIES:
        try:
            spec = importlib.util.find_spec(name)
        except (ImportError, ValueError):
            spec = None
        if spec is None or not spec.origin:
            out.append(f"{name}:absent")
            continue
        site = Path(spec.origin).parent.parent
        try:
            infos = sorted(e for e in os.listdir(site) if e.endswith(".dist-info") and e.lower().startswith(name + "-"))
        except OSError:
            infos = []
        out.append(f"{name}:{spec.origin}:{','.join(infos)}")
    return out


def source_hash(root: str | os.PathLike[str]) -> str:
    """SHA-256 of every ``.py`` and ``.toml`` file under ``root``: relative paths and contents, in a fixed order."""
    h = hashlib.sha256()
    root = os.fspath(root)
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if d != "__pycache__")
        for name in sorted(filenames):
            if name.endswith((".py", ".toml")):
                path = os.path.join(dirpath, name)
                h.update(os.path.relpath(path, root).replace(os.sep, "/").encode() + b"\0")
                with open(path, "rb") as fh:
                    h.update(fh.read() + b"\0")
    return h.hexdigest()


def fingerprint() -> str:
    """SHA-256 of the package source, the libraries' versions and Python's (once per process)."""
    global _FINGERPRINT
    if _FINGERPRINT is None:
        parts = [source_hash(Path(__file__).parent), *_library_versions(), sys.version]
        _FINGERPRINT = hashlib.sha256("\n".join(parts).encode()).hexdigest()
    return _FINGERPRINT


def _key_text(value: Any) -> str:
    """An exact text of the inputs: floats by ``float.hex`` (bits), containers recursively."""
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return repr(value)
    if isinstance(value, float):
        return value.hex()
    if isinstance(value, complex):
        return f"({value.real.hex()},{value.imag.hex()})"
    if isinstance(value, (tuple, list)):
        return "(" + ",".join(_key_text(v) for v in value) + ")"
    tolist = getattr(value, "tolist", None)  # NumPy arrays and scalars
    if tolist is not None:
        return f"a{getattr(value, 'shape', ())}" + _key_text(tolist())
    raise TypeError(f"memo key: expected numbers, strings, tuples or arrays, found {type(value).__name__}")


def _encode(value: Any) -> Any:
    if isinstance(value, complex):
        return {"__complex__": [_encode(value.real), _encode(value.imag)]}
    if isinstance(value, float) and not math.isfinite(value):
        return {"__float__": repr(value)}
    if isinstance(value, tuple):
        return {"__tuple__": [_encode(v) for v in value]}
    if isinstance(value, list):
        return [_encode(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _encode(v) for k, v in value.items()}
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"memo value: expected numbers, strings, lists, tuples or dicts, found {type(value).__name__}")


def _decode(value: Any) -> Any:
    if isinstance(value, list):
        return [_decode(v) for v in value]
    if isinstance(value, dict):
        if set(value) == {"__complex__"}:
            re, im = value["__complex__"]
            return complex(_decode(re), _decode(im))
        if set(value) == {"__float__"}:
            return float(value["__float__"])
        if set(value) == {"__tuple__"}:
            return tuple(_decode(v) for v in value["__tuple__"])
        return {k: _decode(v) for k, v in value.items()}
    return value


def config_key(cfg) -> str:
    """The exact text of a :class:`~obsdesign.params.Config`'s values for a key (name and provenance left out).

    >>> import obsdesign as od
    >>> config_key(od.load_preset("vcm")) == config_key(od.load_preset("vcm").override(rho=4.0))
    True
    >>> config_key(od.load_preset("vcm")) == config_key(od.load_preset("vcm").override(rho=4.000001))
    False
    """
    values = {k: v for k, v in cfg.to_dict().items() if k not in ("name", "sources")}
    return json.dumps(values, sort_keys=True, default=repr)  # floats by repr: every bit


def list_of(n: int) -> Callable[[Any], bool]:
    """A ``valid`` test for :func:`memo`: a list of ``n`` items."""
    return lambda value: isinstance(value, list) and len(value) == n


def memo(namespace: str, inputs: Any, compute: Callable[[], Any], valid: Callable[[Any], bool] | None = None) -> Any:
    """``compute()``, or the value it returned before for the same namespace, inputs and code.

    Parameters
    ----------
    namespace : str
        What is computed (one per function whose result is kept).
    inputs : numbers, strings, tuples or arrays
        Everything the result depends on besides the package's code and the libraries.
    compute : callable
        Computes the value: numbers (complex, inf and nan included), strings, bools, None, and lists,
        tuples and dicts of them.
    valid : callable, optional
        Whether a value read from disk has the shape the caller needs; one that has not (an entry
        edited by hand, a truncated file) is computed again and rewritten.

    Returns
    -------
    object
        The value, equal (bit for bit in every float) to what ``compute()`` returns.
    """
    if not enabled():
        return compute()
    key = hashlib.sha256(f"{namespace}\n{_key_text(inputs)}\n{fingerprint()}".encode()).hexdigest()
    path = cache_dir() / namespace / f"{key}.json"
    try:
        with open(path, encoding="utf-8") as fh:
            value = _decode(json.load(fh))
        if valid is None or valid(value):
            return value
    except Exception:  # noqa: BLE001 (an unreadable entry, or one `valid` chokes on, is a miss)
        pass
    value = compute()
    try:
        text = json.dumps(_encode(value), allow_nan=False)
        path.parent.mkdir(parents=True, exist_ok=True)
        from ._io import atomic_write

        atomic_write(path, text)
    except (OSError, TypeError, ValueError):  # a read-only or full disk: the value is still right
        pass
    return value
