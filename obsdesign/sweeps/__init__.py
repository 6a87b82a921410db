"""Design sweeps and Monte-Carlo robustness, locally or on a Dask cluster.

:mod:`~obsdesign.sweeps.plan` (grid x draws, seeds), :mod:`~obsdesign.sweeps.store`
(``results.csv`` checkpoint), :mod:`~obsdesign.sweeps.run` (:func:`sweep`, executors) and
:mod:`~obsdesign.sweeps.summary` (the keys of ``summary.json``).
"""

from .run import SweepResult as SweepResult
from .run import sweep as sweep
from .summary import SUMMARY_KEYS as SUMMARY_KEYS
from .summary import make_summary as make_summary

__all__ = ["SweepResult", "sweep", "SUMMARY_KEYS", "make_summary"]
