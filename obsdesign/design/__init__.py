"""Numeric design: observer gains and stability verdicts, PID, noise (python-control)."""

from .advisories import design_warnings as design_warnings
from .noise import NoiseAnalysis as NoiseAnalysis
from .noise import band_limited_rms as band_limited_rms
from .noise import lowpass as lowpass
from .noise import noise_analysis as noise_analysis
from .observer import FrozenSystems as FrozenSystems
from .observer import ObserverDesign as ObserverDesign
from .observer import StabilityReport as StabilityReport
from .observer import check_stability as check_stability
from .observer import design_observer as design_observer
from .pid import PIDDesign as PIDDesign
from .pid import design_pid as design_pid
from .pid import pid_from_config as pid_from_config
from .pid import pid_from_gains as pid_from_gains
from .._display import Condition as Condition
from .observer import ObserverArrays as ObserverArrays
from .observer import is_stable as is_stable

__all__ = [
    "NoiseAnalysis", "band_limited_rms", "lowpass", "noise_analysis",
    "FrozenSystems", "ObserverArrays", "ObserverDesign", "is_stable", "StabilityReport", "check_stability", "design_observer",
    "PIDDesign", "design_pid", "pid_from_config", "pid_from_gains", "Condition",
    "design_warnings",
]
