"""What a sweep folder guarantees: one sweep at a time, nothing overwritten by accident.

* **Lock.** A sweep holds an exclusive ``fcntl.flock`` on ``DIR/.lock`` from start to end
  (non-blocking: a second sweep in the same folder fails at once). The lock is released by
  the operating system when the process ends, however it ends.
* **No silent overwrite.** A folder that holds results (``results.csv`` or ``sweep.json``)
  is refused unless the sweep resumes it (``resume=True``, same settings) or replaces it
  (``force=True``, which also removes the old summary files and a streamed study's batch files).
* **Resume.** ``sweep.json`` must exist, parse and equal the new sweep's settings (the keys
  that differ are named); every row of ``results.csv`` is checked against the plan
  (:func:`obsdesign.sweeps.store.read_rows`).

Examples
--------
>>> import tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as tmp:
...     with SweepLock(tmp):
...         try:
...             SweepLock(tmp).__enter__()
...         except ValueError as e:
...             print(str(e).split(":")[0])
out_dir
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

__all__ = ["SweepLock", "check_start", "read_manifest", "SUMMARY_FILES"]

#: Files a finished sweep adds (removed by ``force``); ``montecarlo.json``: a streamed study's.
SUMMARY_FILES = ("summary.json", "summary_map.svg", "summary_distributions.svg", "montecarlo.json")


class SweepLock:
    """Exclusive, non-blocking lock of a sweep folder (``DIR/.lock``); a context manager.

    Parameters
    ----------
    folder : path
        The sweep folder (created if missing).
    """

    def __init__(self, folder: str | os.PathLike) -> None:
        self.folder = Path(folder)
        self._fd: int | None = None

    def __enter__(self) -> "SweepLock":
        import fcntl

        self.folder.mkdir(parents=True, exist_ok=True)
        path = self.folder / ".lock"
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise ValueError(f"out_dir: expected a folder no other sweep is using, found {str(self.folder)!r} "
                             f"locked by a running sweep ({str(path)!r})") from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._fd is not None:
            os.close(self._fd)  # releases the flock
            self._fd = None


def check_start(folder: Path, *, resume: bool, force: bool) -> None:
    """Refuse to start a new sweep over the results of another (unless ``force``).

    Parameters
    ----------
    folder : Path
        The sweep folder.
    resume : bool
        The sweep continues the folder's sweep.
    force : bool
        The sweep replaces the folder's results.
    """
    if resume and force:
        raise ValueError("resume, force: expected at most one of them, found both")
    held = [name for name in ("results.csv", "sweep.json") if (folder / name).exists()]
    if held and not resume and not force:
        raise ValueError(f"out_dir: {str(folder)!r} holds the results of a sweep ({', '.join(held)}); "
                         "continue it with --resume (resume=True) or replace it with --force (force=True)")
    if force:
        for name in (*SUMMARY_FILES, "results.csv", "sweep.json", ".checksums"):
            (folder / name).unlink(missing_ok=True)
        for batch in folder.glob("batches/b*.npz"):  # a streamed study's (obsdesign.sweeps.montecarlo)
            batch.unlink()


def read_manifest(path: Path, expected: dict) -> None:
    """Check that ``sweep.json`` exists, parses and describes the same sweep as ``expected``.

    Parameters
    ----------
    path : Path
        The folder's ``sweep.json``.
    expected : dict
        The manifest of the sweep being started.
    """
    if not path.is_file():
        raise ValueError(f"resume: {str(path)!r} is missing: the rows in results.csv cannot be matched to a sweep; "
                         "start again with --force")
    try:
        old = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"resume: {str(path)!r} is corrupt (not valid JSON: {e}); start again with --force") from None
    if not isinstance(old, dict):
        raise ValueError(f"resume: {str(path)!r} is corrupt (expected a JSON object, found {type(old).__name__})")
    if old != expected:
        differ = [key for key in expected if old.get(key) != expected[key]]
        differ += [key for key in old if key not in expected]
        raise ValueError(f"resume: the sweep in {str(path.parent)!r} was started with different settings "
                         f"(differs in: {', '.join(differ)})")
