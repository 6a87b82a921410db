"""The standard closed-loop cases: the scenarios of the estimator comparison and of the ``tracking``
tuning objective (:mod:`obsdesign.comparison`, :mod:`obsdesign.design.tune`), defined once.

>>> sorted(CASES), TRANSIENT
(['excitation', 'positioning', 'tracking'], 0.5)
"""

from __future__ import annotations

from ..loop.scenarios import Chirp, Excitation, Positioning

__all__ = ["CASES", "TRANSIENT"]

#: Scenario name -> (spec, duration [s]).
CASES = {
    "excitation": (Excitation(force_rms=1.0, bandwidth=5.0), 5.0),
    "positioning": (Positioning(step_size=1e-3, step_up=0.5, step_down=3.0), 4.0),
    "tracking": (Chirp(f0=0.5, f1=3.0), 8.0),
}
#: Start-up interval [s] left out of the RMS errors.
TRANSIENT = 0.5
