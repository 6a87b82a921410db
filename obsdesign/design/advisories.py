"""Warnings about a design, shared by every command that uses one (``check``, ``simulate``,
``noise``, ``export``): the one place that decides what deserves a ``warning:`` line.

A design gets a warning when

* its fastest observer pole times ``dt`` exceeds 1 (the observer is faster than the
  sampling: :func:`obsdesign.design.check_stability`'s note), or
* a condition of :func:`~obsdesign.design.check_stability` fails (an unstable or
  unobservable design: a simulation of it may diverge, its noise variance is unbounded,
  and exported code would run an observer that does not converge).

Examples
--------
>>> import obsdesign as od
>>> design_warnings(od.load_preset("vcm"))
()
>>> notes = design_warnings(od.load_preset("vcm").override(rho=0.5))   # an unstable observer
>>> len(notes), notes[0].startswith("the observer design fails check ("), "discrete poles inside unit circle" in notes[0]
(1, True, True)
>>> print(design_warnings(od.load_preset("vcm").override(dt=0.01))[0][:61])
fastest observer pole -609.7 1/s times dt = 0.01 s is 6.1 > 1
"""

from __future__ import annotations

import warnings

from ..params import Config
from .observer import check_stability

__all__ = ["design_warnings"]


def design_warnings(cfg: Config) -> tuple[str, ...]:
    """The warnings of ``obsdesign check`` for a design, as sentences (empty when all is well).

    Parameters
    ----------
    cfg : Config
        The design (change values with :meth:`obsdesign.Config.override` before).

    Returns
    -------
    tuple of str
        The check's notes (fastest pole times dt > 1), then one note naming the failed
        conditions if any fail.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # returned instead
        report = check_stability(cfg)
    notes = list(report.warnings)
    failed = report.failed()
    if failed:
        notes.append(f"the observer design fails check ({', '.join(failed)}; see obsdesign check)")
    return tuple(notes)
