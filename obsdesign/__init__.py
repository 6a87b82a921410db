"""obsdesign: design, verify and validate reduced-order friction observers.

Implements M. Ruderman, "Reduced-order asymptotic observer of nonlinear
friction for precise motion control": symbolic derivation, numeric design and
stability verdicts, simulation and reports.
"""

from .design import check_stability as check_stability
from .design import design_observer as design_observer
from .design import design_pid as design_pid
from .design import noise_analysis as noise_analysis
from .design import pid_from_config as pid_from_config
from .design import pid_from_gains as pid_from_gains
from .params import Config as Config
from .params import FrictionParams as FrictionParams
from .params import ObserverSpec as ObserverSpec
from .params import PIDSpec as PIDSpec
from .params import PlantParams as PlantParams
from .params import SensorSpec as SensorSpec
from .params import load_config as load_config
from .params import load_preset as load_preset
from .params import preset_names as preset_names
from .sim import SimResult as SimResult
from .sim import simulate as simulate
from .symbolic import Derivation as Derivation
from .symbolic import derive as derive

__version__ = "0.1.0"

__all__ = [
    "Config",
    "FrictionParams",
    "ObserverSpec",
    "PIDSpec",
    "PlantParams",
    "SensorSpec",
    "load_config",
    "load_preset",
    "preset_names",
    "Derivation",
    "derive",
    "check_stability",
    "design_observer",
    "design_pid",
    "noise_analysis",
    "pid_from_config",
    "pid_from_gains",
    "SimResult",
    "simulate",
]
