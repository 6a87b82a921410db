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
without the memo; ``tests/test_memo.py`` compares each kept result with a fresh computation.

Nothing read back is taken on trust (docs/cli.md, "The memo's trust model"); a failed check is a miss
(computed again, rewritten) with one :class:`MemoWarning`:

- the folder and its namespaces are created 0700 and used only if they are the user's own and not
  writable by others; an entry is read only if it is a regular file (no FIFO, device, folder or symbolic
  link) of at most :data:`MAX_ENTRY_BYTES`;
- every entry is signed: HMAC-SHA-256 of its format, key and value under the folder's secret (a 0600 file
  of 32 random bytes), so an entry edited, damaged, copied from elsewhere or written by another user is a miss;
- on load the value must be what :func:`_encode` writes (a strict schema) and pass the caller's ``valid``
  (its shape) and ``verify`` (a cheap re-verification against the inputs: margins, peaks, poles);
- values are data, never markup (the report's derivation is a tree rendered with escaping every time).
  The certificate's searched ``P`` is only a proposal: it is verified (NumPy) on every call.

The folder is ``$OBSDESIGN_CACHE_DIR``, else ``$XDG_CACHE_HOME/obsdesign``, else
``~/.cache/obsdesign``; ``OBSDESIGN_CACHE=off`` turns the memo off. Entries are written atomically
(temporary file, then rename); an unwritable folder is never an error. Deleting the folder is always safe.

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
import hmac
import json
import math
import os
import stat
import sys
import warnings
from pathlib import Path
from typing import Any, Callable

__all__ = ["memo", "MemoWarning", "MAX_ENTRY_BYTES", "cache_dir", "enabled", "fingerprint", "source_hash", "list_of", "config_key"]

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


_SCHEMA_DEPTH = 64
#: Ceiling of one entry on disk [bytes]: the largest kept value (a 4001-point frequency response) is
#: about 200 kB; anything larger is not read at all.
MAX_ENTRY_BYTES = 4 * 2**20
_FORMAT = 2
_NONFINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


class MemoWarning(UserWarning):
    """An entry (or the folder) of the result memo failed a check: the value was computed instead."""


class _Refused(Exception):
    """Why an entry is not used (the text of the warning)."""


def _canonical(encoded: Any) -> str:
    return json.dumps(encoded, sort_keys=True, separators=(",", ":"), allow_nan=False, ensure_ascii=True)


def _digest(key: str, canonical: str, secret: bytes) -> str:
    """The entry's signature: HMAC-SHA-256 of the format, key and value under the folder's secret."""
    return hmac.new(secret, f"{_FORMAT}\n{key}\n{canonical}".encode(), hashlib.sha256).hexdigest()


_SECRET = "secret"  # the file beside the namespaces' folders


def _secret(root: Path, *, create: bool) -> bytes | None:
    """The folder's signing secret (32 random bytes, hex, in a 0600 file only the user can read).

    An entry is used only if it is signed with it: an entry written by another user, copied from another
    machine or edited by hand is a miss. ``None`` when there is none yet and ``create`` is false.
    """
    path = root / _SECRET
    if create and not os.path.lexists(path):
        import tempfile

        fd, tmp = tempfile.mkstemp(dir=root, prefix=".secret.")  # 0600
        try:
            os.write(fd, os.urandom(32).hex().encode("ascii"))
            os.close(fd)
            os.link(tmp, path)  # never replaces a secret another process wrote meanwhile
        except FileExistsError:
            pass
        finally:
            os.unlink(tmp)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    if not stat.S_ISREG(st.st_mode) or st.st_size != 64:
        raise _Refused(f"its secret {path} is not a 64-byte regular file")
    if (hasattr(os, "getuid") and st.st_uid != os.getuid()) or st.st_mode & 0o077:
        raise _Refused(f"its secret {path} is readable by other users (mode {stat.S_IMODE(st.st_mode):o})")
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    try:
        text = os.read(fd, 65)
    finally:
        os.close(fd)
    try:
        return bytes.fromhex(text.decode("ascii"))
    except ValueError as e:
        raise _Refused(f"its secret {path} is not hexadecimal") from e


def _trusted_folder(path: Path, *, root: bool) -> None:
    """Refuse a folder that is a symbolic link (below the root), not a folder, not ours or writable by others."""
    st = os.lstat(path) if not root else os.stat(path)
    if stat.S_ISLNK(st.st_mode):
        raise _Refused(f"{path} is a symbolic link")
    if not stat.S_ISDIR(st.st_mode):
        raise _Refused(f"{path} is not a folder")
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        raise _Refused(f"{path} belongs to another user")
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise _Refused(f"{path} is writable by other users (mode {stat.S_IMODE(st.st_mode):o})")


def _folder(namespace: str, *, create: bool) -> Path | None:
    """The namespace's folder after its checks; None when absent and not created."""
    root = cache_dir()
    folder = root / namespace
    if create:
        root.mkdir(mode=0o700, parents=True, exist_ok=True)
        try:
            os.mkdir(folder, 0o700)
        except FileExistsError:
            pass
    elif not os.path.lexists(folder):
        return None
    _trusted_folder(root, root=True)
    _trusted_folder(folder, root=False)
    return folder


def _strict_decode(value: Any, depth: int = 0) -> Any:
    """:func:`_decode` that refuses what :func:`_encode` never writes (the schema of every entry)."""
    if depth > _SCHEMA_DEPTH:
        raise _Refused("nested deeper than any kept value")
    if isinstance(value, list):
        return [_strict_decode(v, depth + 1) for v in value]
    if isinstance(value, dict):
        if "__complex__" in value or "__float__" in value or "__tuple__" in value:
            (tag, inner), = value.items() if len(value) == 1 else [(None, None)]
            if tag == "__complex__" and isinstance(inner, list) and len(inner) == 2:
                re, im = (_strict_decode(v, depth + 1) for v in inner)
                if all(isinstance(v, float) for v in (re, im)):
                    return complex(re, im)
            elif tag == "__float__" and inner in _NONFINITE:
                return _NONFINITE[inner]
            elif tag == "__tuple__" and isinstance(inner, list):
                return tuple(_strict_decode(v, depth + 1) for v in inner)
            raise _Refused("holds a malformed tagged value")
        return {k: _strict_decode(v, depth + 1) for k, v in value.items()}
    if isinstance(value, float) and not math.isfinite(value):
        raise _Refused("holds a non-finite number outside its tag")
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise _Refused(f"holds a {type(value).__name__}")


def _no_constant(name: str) -> Any:
    raise _Refused(f"holds the JSON extension {name}")


def _read(path: Path, key: str, secret: bytes) -> Any:
    """The value of the entry at ``path``, or :class:`_Refused` (FileNotFoundError when there is none)."""
    st = os.lstat(path)
    if not stat.S_ISREG(st.st_mode):
        raise _Refused("is not a regular file" + (" (a symbolic link)" if stat.S_ISLNK(st.st_mode) else ""))
    if st.st_size > MAX_ENTRY_BYTES:
        raise _Refused(f"is larger than {MAX_ENTRY_BYTES} bytes")
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    fd = os.open(path, flags)
    try:
        st = os.fstat(fd)  # the file opened is the one checked (no swap in between)
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_ENTRY_BYTES:
            raise _Refused("changed into something else while being read")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            data = fh.read(MAX_ENTRY_BYTES + 1)
    finally:
        os.close(fd)
    if len(data) > MAX_ENTRY_BYTES:
        raise _Refused(f"is larger than {MAX_ENTRY_BYTES} bytes")
    try:
        entry = json.loads(data.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as e:
        raise _Refused("is not JSON") from e
    if not (isinstance(entry, dict) and set(entry) == {"format", "key", "digest", "value"}):
        raise _Refused("is not a memo entry (format, key, digest, value)")
    if entry["format"] != _FORMAT or entry["key"] != key:
        raise _Refused("is of another format or key")
    try:
        canonical = _canonical(entry["value"])
    except (TypeError, ValueError) as e:
        raise _Refused("holds a value JSON cannot write back") from e
    if not (isinstance(entry["digest"], str) and hmac.compare_digest(entry["digest"], _digest(key, canonical, secret))):
        raise _Refused("does not match its signature (edited, damaged or not written here)")
    return _strict_decode(entry["value"])


def _warn(text: str) -> None:
    # the text names the folder, not the entry: a lost secret fails every entry of a namespace, and the
    # command line prints each distinct warning once
    warnings.warn(f"result memo: {text}; computed instead", MemoWarning, stacklevel=3)


def memo(namespace: str, inputs: Any, compute: Callable[[], Any], valid: Callable[[Any], bool] | None = None,
         verify: Callable[[Any], str | None] | None = None) -> Any:
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
        The schema of a value read from disk (types, lengths, finite numbers): whether it has the shape
        the caller needs.
    verify : callable, optional
        A cheap re-verification of a value read from disk against the inputs (margins against the
        loop's own frequency response, poles against its characteristic polynomial): ``None`` when the
        value holds, else why not.

    Returns
    -------
    object
        The value, equal (bit for bit in every float) to what ``compute()`` returns.

    Warns
    -----
    MemoWarning
        An entry failed a check (not a regular file, too large, symbolic link, digest, schema,
        re-verification) or the folder is not the user's own: the value is computed (and the entry
        rewritten), one warning per entry.
    """
    if not enabled():
        return compute()
    key = hashlib.sha256(f"{namespace}\n{_key_text(inputs)}\n{fingerprint()}".encode()).hexdigest()
    try:
        folder = _folder(namespace, create=False)
        secret = _secret(cache_dir(), create=False) if folder is not None else None
    except OSError:
        folder = None  # an unreadable folder: computed, and the write below says nothing
    except _Refused as e:
        _warn_folder(e)
        return compute()
    if folder is not None and secret is not None:
        path = folder / f"{key}.json"
        why: str | None = None
        try:
            value = _read(path, key, secret)
            with warnings.catch_warnings():  # arithmetic on a forged value may overflow: it is refused, quietly
                warnings.simplefilter("ignore", RuntimeWarning)
                why = None if valid is None or valid(value) else "does not have the shape of the result"
                if why is None and verify is not None:
                    why = verify(value)
            if why is None:
                return value
        except FileNotFoundError:
            pass
        except _Refused as e:
            why = str(e)
        except Exception as e:  # noqa: BLE001 (an entry `valid` or `verify` chokes on, an unreadable file)
            why = f"cannot be read ({type(e).__name__})"
        if why is not None:
            _warn(f"an entry in {folder} {why}")
    value = compute()
    try:
        encoded = _encode(value)
        canonical = _canonical(encoded)
        folder = _folder(namespace, create=True)
        secret = _secret(cache_dir(), create=True)
        if secret is None or folder is None:
            raise OSError("the memo's folder or secret cannot be created")
        text = json.dumps({"format": _FORMAT, "key": key, "digest": _digest(key, canonical, secret), "value": encoded},
                          allow_nan=False)
        from ._io import atomic_write

        atomic_write(folder / f"{key}.json", text)
    except _Refused as e:
        _warn_folder(e)
    except (OSError, TypeError, ValueError):  # a read-only or full disk: the value is still right
        pass
    return value


def _warn_folder(e: _Refused) -> None:
    warnings.warn(f"result memo: not used, {e} (delete it or set OBSDESIGN_CACHE_DIR)", MemoWarning,
                  stacklevel=3)
