"""The 3-state motion model with friction, in its two variants.

State ``w = (x, v, f)`` (eq:3:1). The variants differ only in how viscous
friction enters:

``lag``
    eq:3:1 as printed: viscous friction with first-order lag ``beta``,
    ``w3 = Fc + Fv`` and ``A[2, 1] = k + sigma/beta``.
``static``
    the paper's section 4 adjustment (``beta -> 0``): ``sigma v`` moves into
    ``A[1, 1] = -sigma/m`` and ``w3 = Fc``.

Everything downstream (regular form, observer, eigenvalues, gain rule, noise)
is derived from these matrices by one procedure in
:mod:`obsdesign.symbolic.derivation`.

Examples
--------
>>> from obsdesign.symbolic.model import model_matrices
>>> A, B, C = model_matrices("static")
>>> A.tolist()
[[0, 1, 0], [0, -sigma/m, -1/m], [0, k, 0]]
"""

from __future__ import annotations

import sympy as sp

from .._validate import Choice
from ..params import VARIANTS

__all__ = ["SYMBOLS", "model_matrices", "model_symbols", "check_variant"]

#: SymPy symbols shared by every derivation (positive where physical).
SYMBOLS: dict[str, sp.Symbol] = {
    "m": sp.Symbol("m", positive=True),
    "sigma": sp.Symbol("sigma", positive=True),
    "beta": sp.Symbol("beta", positive=True),
    "Cf": sp.Symbol("C_f", positive=True),
    "s": sp.Symbol("s", positive=True),
    "kappa": sp.Symbol("kappa", positive=True),
    "rho": sp.Symbol("rho", positive=True),
    "k": sp.Symbol("k", nonnegative=True),
    "L1": sp.Symbol("L_1", real=True),
    "L2": sp.Symbol("L_2", real=True),
}


def check_variant(variant: object) -> str:
    """Validate a model variant name.

    Parameters
    ----------
    variant : object
        The value to check.

    >>> check_variant("lag")
    'lag'
    >>> check_variant("dynamic")
    Traceback (most recent call last):
    ...
    ValueError: variant: expected one of 'lag', 'static', found 'dynamic'
    """
    if not isinstance(variant, str):
        raise TypeError(f"variant: expected a string, found {type(variant).__name__} {variant!r}")
    return Choice(VARIANTS).check("variant", variant)


def model_symbols(variant: str) -> dict[str, sp.Symbol]:
    """The symbols a variant's derivation uses (``beta`` only for ``lag``).

    Parameters
    ----------
    variant : {'lag', 'static'}
        Model variant.
    """
    check_variant(variant)
    return {name: sym for name, sym in SYMBOLS.items() if variant == "lag" or name != "beta"}


def model_matrices(variant: str) -> tuple[sp.ImmutableMatrix, sp.ImmutableMatrix, sp.ImmutableMatrix]:
    """System matrix ``A(k)``, input vector ``B`` and output row ``C`` (eq:3:1).

    Parameters
    ----------
    variant : {'lag', 'static'}
        Model variant (see module docstring).

    Returns
    -------
    A : ImmutableMatrix, shape (3, 3)
        Depends on the pre-sliding stiffness symbol ``k`` = dFc/dx.
    B : ImmutableMatrix, shape (3, 1)
    C : ImmutableMatrix, shape (1, 3)
        Displacement is the only measurement.
    """
    check_variant(variant)
    m, sigma, k = SYMBOLS["m"], SYMBOLS["sigma"], SYMBOLS["k"]
    if variant == "lag":
        beta = SYMBOLS["beta"]
        A = sp.ImmutableMatrix([[0, 1, 0], [0, 0, -1 / m], [0, k + sigma / beta, 0]])
    else:
        A = sp.ImmutableMatrix([[0, 1, 0], [0, -sigma / m, -1 / m], [0, k, 0]])
    B = sp.ImmutableMatrix([0, 1 / m, 0])
    C = sp.ImmutableMatrix([[1, 0, 0]])
    return A, B, C
