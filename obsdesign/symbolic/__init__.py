"""Symbolic derivation of the reduced-order friction observer (SymPy)."""

from .._lazy import lazy_names

__all__ = ["Derivation", "NoiseTransfer", "derive", "regular_form", "model_matrices"]

#: Public name -> module it comes from; loaded on first use (obsdesign._lazy).
_LAZY = {
    'Derivation': '.derivation',
    'NoiseTransfer': '.derivation',
    'derive': '.derivation',
    'regular_form': '.derivation',
    'model_matrices': '.model',
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
