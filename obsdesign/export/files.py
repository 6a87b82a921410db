"""Write the export files of one format into a folder: the observer, or the whole controller.

Examples
--------
>>> import obsdesign as od, tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as tmp:
...     paths = export(od.load_preset("vcm"), "c", tmp)
...     sorted(p.name for p in paths)
['obsdesign_observer.c', 'obsdesign_observer.h']
>>> with tempfile.TemporaryDirectory() as tmp:
...     paths = export(od.load_preset("vcm"), "c", tmp, what="controller")
...     sorted(p.name for p in paths)
['obsdesign_controller.c', 'obsdesign_controller.h']
>>> export(od.load_preset("vcm"), "latex", ".", what="controller")
Traceback (most recent call last):
...
ValueError: format: the controller is exported as one of python, c, octave, js, fmu, st, found 'latex'
>>> export(od.load_preset("vcm"), "c", ".", estimator="eso")
Traceback (most recent call last):
...
ValueError: estimator: applies to what='controller' only, found 'eso' with what='observer'
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from .._io import atomic_write
from ..params import Config
from . import CONTROLLER_FORMATS, FMI_VERSIONS, FORMATS, TARGET_FORMATS, TARGETS, WHAT
from .codegen import c_files, export_spec, js_module, latex_document, octave_files, python_module

__all__ = ["export"]



def export(cfg: Config, fmt: str, out_dir: str | os.PathLike, *, what: str = "observer",
           controller: str | None = None, schedule: str | None = None,
           estimator: str | None = None, table: dict | None = None, target: str = "host",
           waits: bool = False, fmi_version: str | None = None) -> list[Path]:
    """Write the export files of one format into ``out_dir`` (created if missing).

    Parameters
    ----------
    cfg : Config
        The design (change values with :meth:`obsdesign.Config.override` before).
    fmt : str
        The format, a name of :data:`obsdesign.export.FORMATS`.
    out_dir : path
        Output folder (created if missing); a file of the export's names there must not be a folder.
    what : {'observer', 'controller'}
        ``observer``: the derivation (LaTeX) or the discrete observer; ``controller``: the whole
        sampled controller of the simulator (observer, low-pass, PID, compensation of the config's
        ``[compensation]`` section, saturation): ``obsdesign_controller.h/.c``, ``obsdesign_controller.py``,
        ``obsdesign_controller*.m``, ``obsdesign_controller.mjs``, ``obsdesign_controller.fmu``
        (:mod:`~obsdesign.export.fmu`: compiled for this platform when a C compiler is found),
        ``obsdesign_controller.st`` and ``.xml`` (:mod:`~obsdesign.export.st`). No exported controller delays its
        command by the drive's delay (``[hardware] delay_samples`` d); with d > 0 it keeps its last d commands
        and feeds its estimator the one the drive applies. The observer's ``fmu`` and ``st`` are
        ``obsdesign_observer.fmu``, ``obsdesign_observer.st`` and ``.xml``.
    controller : str, optional
        With ``what='controller'``: the controller of :func:`obsdesign.simulate` to generate
        (:data:`obsdesign.export.controller.EXPORTED_CONTROLLERS`, default ``pid+observer``).
    schedule : str, optional
        With ``what='controller'``: the stiffness schedule (:data:`obsdesign.export.controller.SCHEDULE_NAMES`,
        default ``estimated``, with the reversal hysteresis, as the simulator's default). The observer
        export has the ``estimated-raw`` one.
    estimator : str, optional
        With ``what='controller'``: the estimator (:data:`obsdesign.sampled.choices.ESTIMATORS`,
        default ``paper``).
    table : dict, optional
        With ``what='friction-table'`` (format ``c``: ``friction_table.csv`` and ``friction_table.h``):
        the options of :func:`obsdesign.export.friction_table.friction_table` (``points``,
        ``v_max``, ``velocities``, ``motor_constant``).

    target : str
        With ``what='controller'``: a name of :data:`obsdesign.export.TARGETS`; ``host`` (double, bit-exact
        with :func:`obsdesign.simulate`; every format), ``cortex-m4f`` (format ``c``: float32, encoder
        counts, a fixed cost a sample: :func:`obsdesign.export.mcu.mcu_controller_files`) or ``real``
        (format ``st``: the same float32 arithmetic in ``REAL``, :mod:`obsdesign.export.st_real`).
    waits : bool
        With ``what='controller'``: the controller that waits (returns its command of d samples earlier),
        for a bench WITHOUT the drive's delay (:func:`obsdesign.export.controller.controller_files`).
    fmi_version : {'2', '3'}, optional
        With format ``fmu``: the FMI version (:data:`obsdesign.export.FMI_VERSIONS`; default ``'2'``),
        :func:`obsdesign.export.fmu.fmu_archive`.

    Returns
    -------
    list of Path
        The files written (each through a temporary file and a rename).
    """
    if not isinstance(fmt, str) or fmt not in FORMATS:
        raise ValueError(f"format: expected one of {', '.join(FORMATS)}, found {fmt!r}")
    if not isinstance(what, str) or what not in WHAT:
        raise ValueError(f"what: expected one of {', '.join(WHAT)}, found {what!r}")
    if not isinstance(target, str) or target not in TARGETS:
        raise ValueError(f"target: expected one of {', '.join(TARGETS)}, found {target!r}")
    if target != "host" and (what != "controller" or fmt != TARGET_FORMATS[target]):
        raise ValueError(f"target: {target!r} applies to what='controller' in format {TARGET_FORMATS[target]!r} "
                         f"only, found what={what!r}, format={fmt!r}")
    if fmi_version is not None and fmt != "fmu":
        raise ValueError(f"fmi_version: applies to format 'fmu' only, found {fmi_version!r} with format {fmt!r}")
    fmi = FMI_VERSIONS[0] if fmi_version is None else fmi_version  # checked by fmu_archive
    if what == "friction-table":
        if fmt != "c":
            raise ValueError(f"format: the friction table is written as CSV and a C array; expected c, found {fmt!r}")
        from .friction_table import friction_table, table_files

        return _write(table_files(friction_table(cfg, **(table or {}))), out_dir)
    if table is not None:
        raise ValueError(f"table: applies to what='friction-table' only, found {table!r} with what={what!r}")
    if waits is not False and what != "controller":
        raise ValueError(f"waits: applies to what='controller' only, found {waits!r} with what={what!r}")
    if what == "controller":
        if fmt not in CONTROLLER_FORMATS:
            raise ValueError(f"format: the controller is exported as one of {', '.join(CONTROLLER_FORMATS)}, "
                             f"found {fmt!r}")
        from .controller import controller_files

        if not isinstance(cfg, Config):
            raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
        if target == "cortex-m4f":
            from .mcu import mcu_controller_files

            out: dict[str, str | bytes] = dict(mcu_controller_files(cfg, controller=controller, schedule=schedule,
                                                                    estimator=estimator, waits=waits))
        elif fmt == "fmu":
            from .fmu import FMU_NAME, fmu_archive

            out = {FMU_NAME: fmu_archive(cfg, controller=controller, schedule=schedule, estimator=estimator,
                                         waits=waits, fmi_version=fmi)}
        elif target == "real":
            from .st_real import real_block_files

            out = dict(real_block_files(cfg, controller=controller, schedule=schedule, estimator=estimator,
                                        waits=waits))
        elif fmt == "st":
            from .st import st_files

            out = dict(st_files(cfg, controller=controller, schedule=schedule, estimator=estimator, waits=waits))
        else:
            out = dict(controller_files(cfg, fmt, controller=controller, schedule=schedule, estimator=estimator,
                                        waits=waits))
        return _write(out, out_dir)
    for name, value in (("controller", controller), ("schedule", schedule), ("estimator", estimator)):
        if value is not None:
            raise ValueError(f"{name}: applies to what='controller' only, found {value!r} with what='observer'")
    if fmt == "fmu":
        from .fmu import OBSERVER_FMU_NAME, fmu_archive

        return _write({OBSERVER_FMU_NAME: fmu_archive(cfg, what="observer", fmi_version=fmi)}, out_dir)
    if fmt == "st":
        from .st import st_files

        return _write(st_files(cfg, what="observer"), out_dir)
    spec = export_spec(cfg)
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
    return _write(files, out_dir)


def _write(files: Mapping[str, str | bytes], out_dir) -> list[Path]:
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
