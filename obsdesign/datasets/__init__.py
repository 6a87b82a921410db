"""Small data files shipped with the package, for examples and first steps.

``example_log()`` is the path of a synthetic record of a voice-coil axis under PID control
(``t, x, u``: time [s], measured displacement [m], actuator force [N]; 8 s at 1 kHz). It was
written by :mod:`obsdesign.datasets.make_example_log` from a simulation whose parameters are
known (mass 0.8 kg, viscous 12 N s/m, Coulomb 0.9 N, pre-sliding factor 2e4 1/m; 0.2 um of
sensor noise and a 1 um encoder), so an identification of it can be checked against the truth.
Importing this module loads nothing beyond the standard library.

Examples
--------
>>> from obsdesign.datasets import example_log
>>> path = example_log()
>>> path.name
'example_log.csv'
>>> path.read_text(encoding="utf-8").splitlines()[0]
't,x,u'
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["example_log", "EXAMPLE_LOG"]

#: File name of the example log inside this package.
EXAMPLE_LOG = "example_log.csv"


def example_log() -> Path:
    """The path of the shipped example log (CSV with the header ``t,x,u``).

    The file belongs to the installed package: copy it before editing it. Its columns are
    the time ``t`` [s], the encoder displacement ``x`` [m] and the actuator force ``u`` [N]
    (so ``--input-gain`` is 1), sampled at 1 kHz; see :mod:`obsdesign.datasets.make_example_log`
    for how it was made and the parameters it was made with.

    Returns
    -------
    pathlib.Path
        A path on the file system (the package is installed as files, not as a zip archive).

    Raises
    ------
    FileNotFoundError
        If the installation lacks the file (a build that dropped the package data).

    Examples
    --------
    >>> import shutil, tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as d:
    ...     copy = shutil.copy(example_log(), pathlib.Path(d) / "log.csv")
    ...     len(pathlib.Path(copy).read_text(encoding="utf-8").splitlines())   # header + 8 s at 1 kHz
    8001
    """
    path = Path(str(resources.files(__name__).joinpath(EXAMPLE_LOG)))
    if not path.is_file():
        raise FileNotFoundError(f"example_log: expected the package data file {path}, found nothing; "
                                f"reinstall obsdesign (its wheel ships {EXAMPLE_LOG})")
    return path
