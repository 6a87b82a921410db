"""Shared by the analysis scripts: output folder, claims table, assertions."""

from __future__ import annotations

import argparse
from pathlib import Path

from obsdesign.report.figures import save_figure

#: Default folder of the figures (``--out``); the gallery of ``make docs`` gives each script its own.
OUT = Path(__file__).resolve().parent / "out"


def parse_out(description: str) -> Path:
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--out", default=str(OUT), help="folder for the figures")
    out = Path(ap.parse_args().out)
    out.mkdir(parents=True, exist_ok=True)
    return out


def report(claims, fig, path: Path) -> None:
    """Print the claims, save the figure."""
    for c in claims:
        print(f"[{'reproduced' if c.reproduced else 'NOT reproduced'}] ({c.source}) {c.statement}\n"
              f"    paper: {c.paper}\n    ours:  {c.measured}")
    save_figure(fig, path)
    print(f"figure: {path}")


def require(claims, *indices: int) -> None:
    """Fail (AssertionError) unless the listed claims reproduced."""
    for i in indices:
        assert claims[i].reproduced, f"claim not reproduced: {claims[i].statement}: {claims[i].measured}"
