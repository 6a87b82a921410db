"""Write the export files of one format into a folder.

Examples
--------
>>> import obsdesign as od, tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as tmp:
...     paths = export(od.load_preset("vcm"), "c", tmp)
...     sorted(p.name for p in paths)
['obsdesign_observer.c', 'obsdesign_observer.h']
"""

from __future__ import annotations

import os
from pathlib import Path

from .._io import atomic_write
from ..params import Config
from . import FORMATS
from .codegen import c_files, export_spec, js_module, latex_document, octave_files, python_module

__all__ = ["export"]


def export(cfg: Config, fmt: str, out_dir: str | os.PathLike, *, variant: str | None = None,
           rho: float | None = None, dt: float | None = None) -> list[Path]:
    """Write the export files of one format into ``out_dir`` (created if missing).

    Parameters
    ----------
    cfg : Config
    fmt : {'latex', 'python', 'c', 'octave', 'js'}
        The format (:data:`obsdesign.export.FORMATS`).
    out_dir : path
        Output folder (created if missing); a file of the export's names there must not be a folder.
    variant, rho, dt : optional
        Overrides of the config.

    Returns
    -------
    list of Path
        The files written (each through a temporary file and a rename).
    """
    if not isinstance(fmt, str) or fmt not in FORMATS:
        raise ValueError(f"format: expected one of {', '.join(FORMATS)}, found {fmt!r}")
    spec = export_spec(cfg, variant=variant, rho=rho, dt=dt)
    if fmt == "latex":
        files = {f"obsdesign_{spec.variant}.tex": latex_document(spec)}
    elif fmt == "python":
        files = {"obsdesign_observer.py": python_module(spec)}
    elif fmt == "c":
        files = c_files(spec)
    elif fmt == "octave":
        files = octave_files(spec)
    else:
        files = {"obsdesign_observer.mjs": js_module(spec.variant, name=spec.cfg.name)}
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"output: expected a directory, found the file {str(out)!r}")
    for name in files:
        if (out / name).is_dir():
            raise ValueError(f"output: expected {name!r} in {str(out)!r} to be a file, found a folder")
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, text in files.items():
        atomic_write(out / name, text)
        paths.append(out / name)
    return paths
