"""Warnings and advice about a design, shared by every command that uses one (``check``, ``simulate``,
``noise``, ``export``): the one place that decides what deserves a ``warning:`` line, and the rho
range whose switched sampled observer is certified (:func:`certified_rho_range`).

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

from .._memo import MemoWarning
from ..params import Config
import numpy as np

from .certificate import certify
from .observer import check_stability, design_observer

__all__ = ["design_warnings", "certified_rho_range"]


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
        warnings.simplefilter("default", MemoWarning)  # a refused memo entry is still said
        report = check_stability(cfg, search=False)  # the verdicts only: no search for the best P
    notes = list(report.warnings)
    failed = report.failed()
    if failed:
        notes.append(f"the observer design fails check ({', '.join(failed)}; see obsdesign check)")
    return tuple(notes)


def certified_rho_range(cfg: Config, rhos=None) -> tuple[float, float] | None:
    """The interval of ``rho`` over which the continuous certificate holds (so every dt is certified).

    Parameters
    ----------
    cfg : Config
        The design; ``rho`` is varied, everything else kept.
    rhos : array_like, optional
        The values tried (default 80 values, log-spaced from 0.5 to 20).

    Returns
    -------
    (float, float) or None
        The smallest and largest certified ``rho`` of the longest run of certified values, or None.

    Examples
    --------
    >>> import obsdesign as od
    >>> lo, hi = certified_rho_range(od.load_preset("table1"), [0.9, 0.99, 1.01, 2.0, 5.0])
    >>> lo, hi
    (1.01, 5.0)
    """
    rhos = np.geomspace(0.5, 20.0, 80) if rhos is None else np.asarray(rhos, float)
    ok = []
    for rho in rhos:
        c = certify(design_observer(cfg.override(rho=float(rho))), search=False)  # verdict and method only
        ok.append(c.certified and c.method == "continuous")
    best, run = None, None
    for i, flag in enumerate(ok):
        if flag:
            run = (run[0], i) if run else (i, i)
            if best is None or run[1] - run[0] > best[1] - best[0]:
                best = run
        else:
            run = None
    return None if best is None else (float(rhos[best[0]]), float(rhos[best[1]]))
