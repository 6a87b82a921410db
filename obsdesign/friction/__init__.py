"""Plant friction models (numba kernels), chosen by name.

* :mod:`~obsdesign.friction.presliding`: the paper's Coulomb friction with pre-sliding
  memory (eq:2:3:1-2:3:5), code 0 (``paper``), run by the simulator's own plant step;
* ``lugre``, ``dahl``, ``gms`` (+ asymmetric levels and an offset): flat parameter and state
  arrays, dispatched on an integer code (:mod:`~obsdesign.friction.kernels`); the registry
  (:mod:`~obsdesign.friction.registry`) turns named parameters into those arrays.
  See docs/friction-models.md.
"""

from __future__ import annotations

from .common import DAHL as DAHL
from .common import GMS as GMS
from .common import LUGRE as LUGRE
from .common import PAPER as PAPER
from .driver import drive_displacement as drive_displacement
from .driver import simulate_block as simulate_block
from .kernels import friction_advance as friction_advance
from .kernels import friction_force as friction_force
from .kernels import friction_init as friction_init
from .kernels import friction_n_state as friction_n_state
from .kernels import friction_stiffness as friction_stiffness
from .kernels import friction_viscous as friction_viscous
from .kernels import stribeck as stribeck
from .presliding import coulomb as coulomb
from .presliding import coulomb_along as coulomb_along
from .presliding import coulomb_normalized as coulomb_normalized
from .presliding import presliding_shape as presliding_shape
from .presliding import stiffness as stiffness
from .presliding import track_reversal as track_reversal
from .registry import FRICTION_MODELS as FRICTION_MODELS
from .registry import FrictionModelInfo as FrictionModelInfo
from .registry import ParameterSpec as ParameterSpec
from .registry import friction_code as friction_code

__all__ = [
    "PAPER", "LUGRE", "DAHL", "GMS", "FRICTION_MODELS", "FrictionModelInfo", "ParameterSpec",
    "friction_code", "friction_n_state", "friction_init", "friction_force", "friction_advance",
    "friction_viscous", "friction_stiffness", "stribeck", "simulate_block", "drive_displacement",
    "coulomb", "coulomb_along", "coulomb_normalized", "presliding_shape", "stiffness", "track_reversal",
]
