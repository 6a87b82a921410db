"""Measured data: traces from CSV and MATLAB files, identification of the plant and friction.

``load_trace`` reads a displacement/force record and checks it; ``identify`` fits the
inverse dynamic model (mass, viscous and Coulomb friction, offset) and, where the data
resolve it, the pre-sliding factor ``s``; ``Identification.to_config`` turns the result
into a complete design config; ``observe`` runs the designed observer over a trace. See ``docs/measured-data.md``.
"""

from __future__ import annotations

from .identify import Identification as Identification
from .identify import identify as identify
from .observe import Observation as Observation
from .observe import model_friction_state as model_friction_state
from .observe import observe as observe
from .rules import config_from as config_from
from .trace import Trace as Trace
from .trace import load_trace as load_trace

__all__ = ["Trace", "load_trace", "Identification", "identify", "config_from", "Observation", "observe",
           "model_friction_state"]
