"""Time-varying nonlinear simulation of plant, friction, observer and controller (numba)."""

from .scenarios import SCENARIOS as SCENARIOS
from .scenarios import band_limited_noise as band_limited_noise
from .simulate import COLUMNS as COLUMNS
from .simulate import SimResult as SimResult
from .simulate import simulate as simulate
from .sweep import SweepResult as SweepResult
from .sweep import sweep as sweep

__all__ = ["SCENARIOS", "band_limited_noise", "COLUMNS", "SimResult", "simulate", "SweepResult", "sweep"]
