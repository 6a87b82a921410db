"""Numeric design: observer gains and stability verdicts, PID, noise (python-control)."""

from .._lazy import lazy_names


__all__ = [
    "NoiseAnalysis", "band_limited_rms", "lowpass", "noise_analysis",
    "FrozenSystems", "ObserverArrays", "ObserverDesign", "is_stable", "StabilityReport", "check_stability", "design_observer",
    "PIDDesign", "design_pid", "pid_from_config", "pid_from_gains", "Condition",
    "design_warnings", "certified_rho_range", "certify", "StabilityCertificate",
    "tune", "TuneResult", "Constraints", "OBJECTIVES",
]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'NoiseAnalysis': '.noise',
    'band_limited_rms': '.noise',
    'lowpass': '.noise',
    'noise_analysis': '.noise',
    'FrozenSystems': '.observer',
    'ObserverDesign': '.observer',
    'StabilityReport': '.observer',
    'check_stability': '.observer',
    'design_observer': '.observer',
    'PIDDesign': '.pid',
    'design_pid': '.pid',
    'pid_from_config': '.pid',
    'pid_from_gains': '.pid',
    'Condition': '.._display',
    'ObserverArrays': '.observer',
    'is_stable': '.observer',
    'design_warnings': '.advisories',
    'certified_rho_range': '.advisories',
    'certify': '.certificate',
    'StabilityCertificate': '.certificate',
    'tune': '.tune',
    'TuneResult': '.tune',
    'Constraints': '.tune',
    'OBJECTIVES': '.objectives',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
