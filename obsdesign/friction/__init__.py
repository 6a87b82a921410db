"""Friction models of the simulated plant (numba kernels).

:mod:`~obsdesign.friction.presliding`: the paper's Coulomb friction with pre-sliding
memory (eq:2:3:1-2:3:5). The models are chosen by name from
:data:`obsdesign.sim.registry.PLANT_FRICTION`.
"""

from .presliding import coulomb as coulomb
from .presliding import coulomb_along as coulomb_along
from .presliding import coulomb_normalized as coulomb_normalized
from .presliding import presliding_shape as presliding_shape
from .presliding import stiffness as stiffness
from .presliding import track_reversal as track_reversal

__all__ = ["coulomb", "coulomb_along", "coulomb_normalized", "presliding_shape", "stiffness", "track_reversal"]
