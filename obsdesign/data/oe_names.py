"""What :func:`~obsdesign.data.output_error.refine` can fit: its models, methods and parameter names, and its
one failure that is not bad input.

Examples
--------
>>> default_method("lugre"), default_method("paper")
('segments', 'windows')
"""

from __future__ import annotations

from .._validate import check_choice
from ..friction.registry import FRICTION_MODELS
from .oe_segments import DYNAMIC, STATIC

__all__ = ["MODELS", "METHODS", "RefineFailed", "default_method", "refinable"]

_SKIP = ("Cf_neg", "sigma_neg", "N", "beta")


class RefineFailed(RuntimeError):
    """The refinement could not identify the parameters (a numerical failure, or the time budget ran out before a
    first fit); the message says why in one line."""

#: Plant friction models the refinement simulates: the registry's, less Dahl (the paper's pre-sliding shape
#: without its Stribeck or memory parameters: nothing the paper model does not already fit).
MODELS = tuple(name for name in FRICTION_MODELS.names() if name != "dahl")
#: Methods of :func:`refine`: ``windows`` (around reversals, :mod:`obsdesign.data.oe_plant`) and ``segments``
#: (the whole record in segments, :mod:`obsdesign.data.oe_segments`; LuGre only).
METHODS = ("windows", "segments")


def default_method(model: str) -> str:
    """``'segments'`` for LuGre, ``'windows'`` for the others.

    Parameters
    ----------
    model : str
        A name of :data:`MODELS`.
    """
    return "segments" if check_choice("model", model, MODELS) == "lugre" else "windows"


def refinable(model: str, method: str | None = None) -> tuple[str, ...]:
    """Names :func:`refine` can fit for a plant friction ``model`` with ``method`` (default: :func:`default_method`).

    Parameters
    ----------
    model : str
        A name of :data:`MODELS`.
    method : str, optional
        A name of :data:`METHODS`.
    """
    info = FRICTION_MODELS[check_choice("model", model, MODELS)]
    method = default_method(model) if method is None else check_choice("method", method, METHODS)
    if method == "segments":  # the delay as identify found it, in whole samples
        if info.name != "lugre":
            raise ValueError(f"method: expected 'windows' for model {model!r} (segments fit LuGre only), found "
                             f"'segments'")
        return STATIC + ("Fs", "vs") + DYNAMIC
    names = tuple(n for n in info.scalar_parameters() if n not in _SKIP)
    if "offset" not in names:
        names += ("offset",)
    return names + ("m", "delay")
