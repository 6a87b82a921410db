"""Symbolic derivation of the reduced-order friction observer (SymPy)."""

from .derivation import Derivation as Derivation
from .derivation import NoiseTransfer as NoiseTransfer
from .derivation import derive as derive
from .derivation import regular_form as regular_form
from .model import model_matrices as model_matrices

__all__ = ["Derivation", "NoiseTransfer", "derive", "regular_form", "model_matrices"]
