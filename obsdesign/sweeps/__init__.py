"""Design sweeps and Monte-Carlo robustness, locally or on a Dask cluster.

:mod:`~obsdesign.sweeps.plan` (grid x draws, seeds), :mod:`~obsdesign.sweeps.store`
(``results.csv`` checkpoint), :mod:`~obsdesign.sweeps.run` (:func:`sweep`, executors),
:mod:`~obsdesign.sweeps.summary` (the keys of ``summary.json``) and
:mod:`~obsdesign.sweeps.montecarlo` (:func:`monte_carlo`: a study of 10^5 runs streamed to disk,
with :mod:`~obsdesign.sweeps.sketch` and :mod:`~obsdesign.sweeps.criteria`).
"""

from .._lazy import lazy_names

__all__ = ["SweepResult", "sweep", "SUMMARY_KEYS", "make_summary", "monte_carlo", "MonteCarloResult"]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'SweepResult': '.run',
    'sweep': '.run',
    'SUMMARY_KEYS': '.summary',
    'make_summary': '.summary',
    'monte_carlo': '.montecarlo',
    'MonteCarloResult': '.montecarlo',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
