"""Plant friction models by registry: ``lugre``, ``dahl``, ``gms`` (+ asymmetry, offset).

The numba kernels dispatch on an integer code (``paper`` 0 is reserved: its
kernel is :mod:`obsdesign.sim.friction`); the registry turns named parameters
into the flat arrays the kernels take. See docs/friction-models.md.
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
from .registry import FRICTION_MODELS as FRICTION_MODELS
from .registry import FrictionModelInfo as FrictionModelInfo
from .registry import ParameterSpec as ParameterSpec
from .registry import friction_code as friction_code

__all__ = [
    "PAPER", "LUGRE", "DAHL", "GMS", "FRICTION_MODELS", "FrictionModelInfo", "ParameterSpec",
    "friction_code", "friction_n_state", "friction_init", "friction_force", "friction_advance",
    "friction_viscous", "friction_stiffness", "stribeck", "simulate_block", "drive_displacement",
]
