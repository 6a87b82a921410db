"""Compare two folders written by tools/capture_outputs.py byte for byte.

The fields that are measurements or dates, not results, are masked: ``sim_wall_s`` (the simulation's
wall time) in stdout, ``wall_s`` (a sweep's or a comparison's) in stdout and JSON files, the elapsed time
of a progress line in stderr, the date and the rendering time in a report's HTML; a sweep's ``.lock``
(the pid of the process that held it) is not compared. Prints each differing file; exit status 1 if any differs.

    python tools/compare_outputs.py /tmp/before /tmp/after
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

_WALL = [re.compile(r'("sim_wall_s": )[0-9.e+-]+'), re.compile(r"(sim_wall_s: )[0-9.e+-]+"),
         re.compile(r'("wall_s": )[0-9.e+-]+')]
_PROGRESS = re.compile(r"(runs, )[0-9.]+( s)")
_HTML = [re.compile(r"(Generated )\d{4}-\d{2}-\d{2}( by obsdesign \S+ in )[0-9.]+( s)")]


def _masked(path: Path) -> bytes:
    data = path.read_bytes()
    if path.name == ".lock":
        return b""
    if path.name == "stderr":
        return _PROGRESS.sub(r"\1<WALL>\2", data.decode()).encode()
    if path.name == "stdout" or path.suffix == ".json":
        text = data.decode()
        for pattern in _WALL:
            text = pattern.sub(r"\1<WALL>", text)
        data = text.encode()
    elif path.suffix == ".html":
        text = data.decode()
        for pattern in _HTML:
            text = pattern.sub(r"\1<DATE>\2<TIME>\3", text)
        data = text.encode()
    return data


def main(before: str, after: str) -> int:
    a, b = Path(before), Path(after)
    names = sorted({p.relative_to(a) for p in a.rglob("*") if p.is_file()}
                   | {p.relative_to(b) for p in b.rglob("*") if p.is_file()})
    bad = 0
    for name in names:
        pa, pb = a / name, b / name
        if not (pa.exists() and pb.exists()):
            print(f"only in one: {name}")
            bad += 1
        elif _masked(pa) != _masked(pb):
            print(f"differs: {name}")
            bad += 1
    print(f"{len(names)} files, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1], sys.argv[2]))
