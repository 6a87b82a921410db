"""The tuning objectives of :func:`obsdesign.design.tune` (light: the command line reads it before any numerics).

>>> OBJECTIVES.names(), TRACKING_SCENARIOS
(('estimate-error', 'tracking'), ('tracking', 'positioning'))
"""

from __future__ import annotations

from .._registry import Entry, Registry

__all__ = ["OBJECTIVES", "TRACKING_SCENARIOS"]

#: The tuning objectives (lower is better).
OBJECTIVES = Registry("objective", [
    Entry("estimate-error", 0, "predicted RMS error of the compensated friction estimate under the config's noise "
          "(noise propagation + tracking lag of Coulomb reversals) [N]"),
    Entry("tracking", 1, "RMS tracking error of a comparison scenario by simulation [m]"),
])
#: Scenarios of :data:`obsdesign.comparison.SCENARIOS` the ``tracking`` objective accepts (closed loop).
TRACKING_SCENARIOS = ("tracking", "positioning")
