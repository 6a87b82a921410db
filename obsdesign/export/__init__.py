"""Export the derivation and a designed observer as LaTeX, Python, C, Octave or JavaScript, the controller
also as an FMU (:mod:`~obsdesign.export.fmu`) and IEC 61131-3 Structured Text (:mod:`~obsdesign.export.st`).

:func:`export` (in :mod:`~obsdesign.export.files`) writes one format's files;
:mod:`~obsdesign.export.codegen` prints them from the symbolic derivation. The
heavy modules load on first use, so the command line can read :data:`FORMATS`
before it parses its arguments.

Examples
--------
>>> import obsdesign as od, tempfile
>>> from obsdesign.export import export
>>> with tempfile.TemporaryDirectory() as tmp:
...     paths = export(od.load_preset("vcm"), "c", tmp)
...     sorted(p.name for p in paths)
['obsdesign_observer.c', 'obsdesign_observer.h']
"""

from __future__ import annotations

#: The export formats, in the order the command line lists them.
FORMATS = ("latex", "python", "c", "octave", "js", "fmu", "st")
#: What can be exported: the observer (default), the whole sampled controller, or the feed-forward
#: friction model as a drive's velocity table (:mod:`obsdesign.export.friction_table`).
WHAT = ("observer", "controller", "friction-table")
#: The formats of the whole sampled controller: the code formats (not the derivation's LaTeX).
CONTROLLER_FORMATS = tuple(fmt for fmt in FORMATS if fmt != "latex")
#: The arithmetic targets of the controller: ``host`` (double, bit-exact with simulate; every format),
#: ``cortex-m4f`` (float32, encoder counts, fixed cost: :mod:`obsdesign.export.mcu`; format ``c``) and ``real``
#: (the same float32 arithmetic as IEC 61131-3 ``REAL``: :mod:`obsdesign.export.st_real`; format ``st``).
TARGETS = ("host", "cortex-m4f", "real")
#: The one format of each target but ``host``.
TARGET_FORMATS = {"cortex-m4f": "c", "real": "st"}

#: The FMI versions of the ``fmu`` format (:func:`obsdesign.export.fmu.fmu_archive`): 2.0 (the first: the default)
#: and 3.0, co-simulation, around the same generated C.
FMI_VERSIONS = ("2", "3")

#: The formats packaged for a tool, of the controller or the observer: an FMI 2.0/3.0 co-simulation FMU
#: and an IEC 61131-3 function block (not source languages of :func:`~obsdesign.export.controller.controller_files`).
# choice subset: the exports packaged for an importer or a PLC
TOOL_FORMATS = ("fmu", "st")

__all__ = ["export", "FORMATS", "WHAT", "CONTROLLER_FORMATS", "TOOL_FORMATS", "TARGETS", "TARGET_FORMATS",
           "FMI_VERSIONS"]


def __getattr__(name: str):
    if name == "export":
        from .files import export

        return export
    raise AttributeError(f"module 'obsdesign.export' has no attribute {name!r}")
