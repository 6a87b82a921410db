"""The README's shell examples run as written, in a fresh directory.

Every line of every ```sh block of README.md is a command (a trailing backslash continues it;
``#`` starts its comment; ``# exit N`` in the comment is the exit status it promises, otherwise
0). The commands run in order, in one temporary directory whose ``.venv/bin/obsdesign`` and
``.venv/bin/python`` are wrappers around the interpreter running the tests, so a command later in
the block can read what an earlier one wrote (``identify -o axis.toml`` then ``observe --config
axis.toml``), as from a fresh clone after ``make``. Commands in :data:`LONG` are skipped unless
``OBSDESIGN_README_LONG=1``; ``make`` targets are not run here (``make test`` would run this test).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"

#: Commands not run by default, by their first words after the program, with the reason.
LONG = {
    "sweep": "long: 200 closed-loop runs",
    "report --sweep": "needs the sweep's folder",
    "compare": "long: every estimator on every plant",
    "tune": "long: a search over some 250 designs",
}
NOT_RUN = {"make": "make targets build .venv and run the suite (this test is part of it)"}

#: The example log's truth (obsdesign/datasets/make_example_log.py simulates with these).
TRUTH = {"m": 0.8, "sigma": 12.0, "Cf": 0.9}
#: Closed-loop identification bias allowed (noise fed back, pre-sliding outside the model).
RTOL = 0.05


def readme_commands(text: str) -> list[str]:
    """The commands of the ```sh blocks of ``text``, one string each (continuations joined).

    Examples
    --------
    >>> readme_commands("x\\n```sh\\na b \\\\\\n    c   # note\\nd\\n```\\n```python\\ne\\n```\\n")
    ['a b c   # note', 'd']
    """
    commands = []
    for block in re.findall(r"^```sh\n(.*?)^```", text, re.M | re.S):
        pending = ""
        for line in block.splitlines():
            if line.rstrip().endswith("\\"):
                pending += line.rstrip()[:-1].rstrip() + " "
                continue
            command = (pending + line.strip()).strip()
            pending = ""
            if command:
                commands.append(command)
    return commands


def _words(command: str) -> list[str]:
    return shlex.split(command, comments=True)


def _label(command: str) -> str:
    words = _words(command)
    if words[0] == "make":
        return " ".join(words[:2])
    if words[0].endswith("python"):
        return "python: " + (comment.strip() if (comment := command.partition(" #")[2]) else words[1])
    return " ".join(w for w in words[1:4] if not w.startswith("-") or w == "--sweep")


def _reason(command: str) -> tuple[str, str] | None:
    words = _words(command)
    if words[0] in NOT_RUN:
        return "not run", NOT_RUN[words[0]]
    rest = " ".join(words[1:])
    for start, why in LONG.items():
        if rest == start or rest.startswith(start + " "):
            return "long", why
    return None


COMMANDS = readme_commands(README.read_text(encoding="utf-8"))


def test_the_readme_has_the_data_examples():
    rest = [" ".join(_words(c)[1:3]) for c in COMMANDS]
    assert "identify log.csv" in rest and "observe log.csv" in rest
    # the line that writes log.csv comes before the first command that reads it
    first_read = next(i for i, c in enumerate(COMMANDS) if "log.csv" in _words(c)[1:3])
    assert any("example_log()" in c and "'log.csv'" in c for c in COMMANDS[:first_read])


@pytest.fixture(scope="module")
def fresh_dir(tmp_path_factory):
    """A directory with ``.venv/bin/obsdesign`` and ``.venv/bin/python`` as after ``make``."""
    work = tmp_path_factory.mktemp("readme")
    bin_dir = work / ".venv" / "bin"
    bin_dir.mkdir(parents=True)
    for name, tail in (("obsdesign", '-m obsdesign "$@"'), ("python", '"$@"')):
        wrapper = bin_dir / name
        wrapper.write_text(f"#!/bin/sh\nexec {shlex.quote(sys.executable)} {tail}\n", encoding="utf-8")
        wrapper.chmod(0o755)
    return work


def _params():
    for command in COMMANDS:
        why = _reason(command)
        marks = []
        if why and why[0] == "not run":
            marks = [pytest.mark.skip(reason=why[1])]
        elif why and os.environ.get("OBSDESIGN_README_LONG") != "1":
            marks = [pytest.mark.skip(reason=f"{why[1]} (OBSDESIGN_README_LONG=1 runs it)")]
        yield pytest.param(command, marks=marks, id=_label(command))


@pytest.mark.slow
@pytest.mark.parametrize("command", list(_params()))
def test_readme_command_runs_as_written(command, fresh_dir):
    comment = command.partition(" #")[2]
    expected = int(m.group(1)) if (m := re.search(r"\bexit (\d+)", comment)) else 0
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
               MPLBACKEND="Agg")
    proc = subprocess.run(["bash", "-c", command], cwd=fresh_dir, env=env, capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == expected, f"{command}\nstatus {proc.returncode}\n{proc.stdout[-2000:]}\n{proc.stderr}"
    assert "Traceback" not in proc.stderr
    words = _words(command)
    if words[1] == "identify":
        # the README's identify on the shipped log: the known axis within RTOL
        axis = tomllib.loads((fresh_dir / "axis.toml").read_text(encoding="utf-8"))
        found = {"m": axis["plant"]["m"], "sigma": axis["friction"]["sigma"], "Cf": axis["friction"]["Cf"]}
        assert found == pytest.approx(TRUTH, rel=RTOL), found
    for flag in ("--plot", "-o", "--out"):
        if flag in words and words[1] != "identify":
            target = fresh_dir / words[words.index(flag) + 1]
            assert target.exists() and (target.is_dir() or target.stat().st_size > 0), target
