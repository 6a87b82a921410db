"""obsdesign: design, verify and validate reduced-order friction observers.

Implements M. Ruderman, "Reduced-order asymptotic observer of nonlinear
friction for precise motion control": symbolic derivation, numeric design and
stability verdicts, simulation and reports.

``import obsdesign`` loads only the parameters; the symbolic engine (SymPy), the
numeric design (python-control) and the simulator (numba) are imported on
first use of their names.
"""

from __future__ import annotations

import importlib

from ._version import __version__ as __version__
from .axis import AxisSpec as AxisSpec
from .params import Config as Config
from .params import FrictionParams as FrictionParams
from .params import ObserverSpec as ObserverSpec
from .params import PIDSpec as PIDSpec
from .params import PlantParams as PlantParams
from .params import SensorSpec as SensorSpec
from .params import load_preset as load_preset
from .params import preset_names as preset_names
from .provenance import load_config as load_config

#: Public names provided by subpackages that are imported lazily.
_LAZY = {
    "Derivation": "symbolic",
    "derive": "symbolic",
    "check_stability": "design",
    "design_observer": "design",
    "design_pid": "design",
    "noise_analysis": "design",
    "pid_from_config": "design",
    "pid_from_gains": "design",
    "SimResult": "sim",
    "simulate": "sim",
    "sweep": "sweeps",
    "SweepResult": "sweeps",
    "load_trace": "data",
    "identify": "data",
    "Trace": "data",
    "Identification": "data",
    "observe": "data",
    "Observation": "data",
}

__all__ = [
    "AxisSpec",
    "Config",
    "FrictionParams",
    "ObserverSpec",
    "PIDSpec",
    "PlantParams",
    "SensorSpec",
    "load_config",
    "load_preset",
    "preset_names",
    *_LAZY,
]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    if name in ("design", "loop", "sim", "report", "symbolic", "params", "cli", "export", "friction", "studies", "sweeps",
                "data", "estimators", "datasets"):
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'obsdesign' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
