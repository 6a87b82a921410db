"""Time-varying nonlinear simulation of plant, friction, observer and controller (numba).

Two public steps, :func:`prepare` (design and sample the inputs of a run) and :func:`run`
(the numba kernel and the metrics); :func:`simulate` is both in one call.
"""

from .registry import CONTROLLERS as CONTROLLERS
from .registry import ESTIMATORS as ESTIMATORS
from .registry import PLANT_FRICTION as PLANT_FRICTION
from .registry import PLANTS as PLANTS
from .registry import SCHEDULES as SCHEDULES
from .result import COLUMNS as COLUMNS
from .result import SimResult as SimResult
from .scenarios import SCENARIOS as SCENARIOS
from .scenarios import Chirp as Chirp
from .scenarios import ConstantForce as ConstantForce
from .scenarios import Excitation as Excitation
from .scenarios import Positioning as Positioning
from .scenarios import band_limited_noise as band_limited_noise
from .simulate import LoopInputs as LoopInputs
from .simulate import prepare as prepare
from .simulate import run as run
from .simulate import simulate as simulate

__all__ = ["CONTROLLERS", "ESTIMATORS", "PLANT_FRICTION", "PLANTS", "SCHEDULES", "COLUMNS", "SimResult",
           "SCENARIOS", "Chirp", "ConstantForce", "Excitation", "Positioning", "band_limited_noise",
           "LoopInputs", "prepare", "run", "simulate"]
