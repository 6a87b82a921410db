"""The hostile-input suite (issue 36): every case runs under a deadline, so a hang fails instead of stalling.

:func:`within` (a fixture) arms ``SIGALRM``: a blocking system call (opening a FIFO) or a Python loop that outlasts
the deadline raises :class:`Hang` in the test. :func:`cli` runs the command line in this process
(``obsdesign.cli.main``) under it and returns the exit status and stderr lines.
"""

from __future__ import annotations

import contextlib
import signal

import pytest

#: Seconds a hostile case may take (the slowest command here, a short sweep, takes about 10 s).
DEADLINE = 120


class Hang(Exception):
    """The case outlasted its deadline."""


@contextlib.contextmanager
def _within(seconds: float = DEADLINE):
    def alarm(signum, frame):
        raise Hang(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@pytest.fixture
def within():
    """The deadline as a context manager: ``with within(30): ...``."""
    return _within


@pytest.fixture
def cli(capsys):
    from obsdesign.cli import main

    def run(*argv, seconds: float = DEADLINE):
        with _within(seconds):
            status = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return status, out, err.strip().splitlines()

    return run


@pytest.fixture
def memo_dir(tmp_path, monkeypatch):
    """An empty memo folder of this test only."""
    monkeypatch.setenv("OBSDESIGN_CACHE_DIR", str(tmp_path / "memo"))
    monkeypatch.delenv("OBSDESIGN_CACHE", raising=False)
    return tmp_path / "memo"
