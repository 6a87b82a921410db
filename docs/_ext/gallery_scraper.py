"""sphinx-gallery helpers for the analysis scripts, which write their figure to ``--out DIR``.

The scripts of ``analysis/`` save their figure with :func:`obsdesign.report.figures.save_figure`,
which closes it, so the matplotlib scraper finds nothing open; :func:`written_figures` picks up
the PNG files a script wrote into its own folder instead, and :func:`argv` gives each script
that folder (and ``emps.py`` the EMPS record). Both are named by string in ``conf.py``.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
ROOT = HERE.parent
#: Where the analysis scripts write their figures during the build (one folder per script).
OUT = HERE / "_build" / "gallery-out"
#: The EMPS benchmark record used by ``analysis/emps.py`` (as in tests/test_observe.py).
EMPS = Path(os.environ.get("OBSDESIGN_EMPS") or ROOT.parent / "shared" / "data" / "emps" / "DATA_EMPS.mat")


def _folder(src_file) -> Path | None:
    src = Path(src_file)
    return OUT / src.stem if src.parent.name == "analysis" else None


def argv(gallery_conf, script_vars) -> list[str]:
    """The command-line arguments of an example (``reset_argv``): ``--out`` for an analysis script."""
    out = _folder(script_vars["src_file"])
    if out is None:
        return []
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    return ([str(EMPS)] if out.name == "emps" else []) + ["--out", str(out)]


def written_figures(block, block_vars, gallery_conf) -> str:
    """The figures an analysis script wrote since the last block, moved into the gallery."""
    from sphinx_gallery.scrapers import figure_rst

    out = _folder(block_vars["src_file"])
    if out is None or not out.is_dir():
        return ""
    paths = []
    for png in sorted(out.glob("*.png")):
        target = Path(next(block_vars["image_path_iterator"]))
        shutil.move(png, target)
        paths.append(target)
    return figure_rst(paths, gallery_conf["src_dir"]) if paths else ""


def setup(app):
    return {"parallel_read_safe": True, "parallel_write_safe": True}
