"""Design sweeps and Monte-Carlo robustness, locally or on a Dask cluster.

:mod:`~obsdesign.sweeps.plan` (grid x draws, seeds), :mod:`~obsdesign.sweeps.store`
(``results.csv`` checkpoint), :mod:`~obsdesign.sweeps.run` (:func:`sweep`, executors) and
:mod:`~obsdesign.sweeps.summary` (the keys of ``summary.json``).
"""

from .._lazy import lazy_names

__all__ = ["SweepResult", "sweep", "SUMMARY_KEYS", "make_summary"]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'SweepResult': '.run',
    'sweep': '.run',
    'SUMMARY_KEYS': '.summary',
    'make_summary': '.summary',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
