"""Numeric callables compiled from the symbolic derivation (one source of truth).

Every number of the design package comes from an expression of
:func:`obsdesign.symbolic.derive`, turned into a NumPy function by SymPy's
``lambdify`` and cached. Arguments are passed by the names of
:data:`ARG_NAMES` (``m, sigma, beta, Cf, s, kappa, rho, k, L1, L2``); the
Laplace variable ``p`` comes last where an expression has it.

Examples
--------
>>> f = compiled("static", "gain_rule")
>>> L1, L2 = f(**model_values(m=0.538, sigma=21.1, kappa=8000.0, rho=4.0))
>>> round(float(L1), 3), float(L2)
(936.318, -120000.0)
"""

from __future__ import annotations

import functools
import math
from typing import Callable

import numpy as np
import sympy as sp

from ..symbolic import derive
from ..symbolic.derivation import LAPLACE
from ..symbolic.model import SYMBOLS

__all__ = ["ARG_NAMES", "compiled", "model_values", "poly_coeffs"]

ARG_NAMES = ("m", "sigma", "beta", "Cf", "s", "kappa", "rho", "k", "L1", "L2")
_ARGS = tuple(SYMBOLS[n] for n in ARG_NAMES)


def model_values(**values: float) -> dict[str, float]:
    """Argument dict for a compiled function; unspecified names are NaN.

    Parameters
    ----------
    **values : float
        Values by the names of :data:`ARG_NAMES`.
    """
    unknown = set(values) - set(ARG_NAMES)
    if unknown:
        raise ValueError(f"model_values: unknown names {sorted(unknown)}; expected {ARG_NAMES}")
    return {n: float(values.get(n, math.nan)) for n in ARG_NAMES}


def _expression(variant: str, what: str):
    d = derive(variant)
    L1, L2 = SYMBOLS["L1"], SYMBOLS["L2"]
    if what == "gain_rule":
        return [d.gain_rule[L1], d.gain_rule[L2]]
    if what == "coefficients":
        return [d.a0, d.a1]
    if what == "stability_bounds":
        return [rel.rhs for rel in d.stability_conditions]
    if what in ("A", "B", "C", "observer_matrix", "observer_input", "observer_output_gain"):
        return getattr(d, what)
    raise ValueError(f"compiled: unknown expression {what!r}")


@functools.lru_cache(maxsize=None)
def compiled(variant: str, what: str) -> Callable[..., object]:
    """A cached NumPy function of the named derivation result.

    Parameters
    ----------
    variant : {'lag', 'static'}
    what : str
        ``'gain_rule'`` (``[L1, L2]``), ``'coefficients'`` (``[a0, a1]``),
        ``'stability_bounds'`` (right-hand sides of Proposition 1), or a matrix
        attribute: ``'A'``, ``'B'``, ``'C'``, ``'observer_matrix'``,
        ``'observer_input'``, ``'observer_output_gain'``.

    Returns
    -------
    callable
        Takes the :data:`ARG_NAMES` as keyword arguments.
    """
    fn = sp.lambdify(_ARGS, _expression(variant, what), modules="numpy")

    def call(**kw: float):
        return fn(*(kw[n] for n in ARG_NAMES))

    return call


@functools.lru_cache(maxsize=None)
def poly_coeffs(variant: str, which: str) -> Callable[..., tuple[np.ndarray, np.ndarray]]:
    """Numerator and denominator coefficients (highest power first) of a noise transfer.

    ``which`` is ``'velocity'`` or ``'friction'``; the function takes the
    :data:`ARG_NAMES` as keywords (with ``k`` the constant stiffness).
    """
    if which not in ("velocity", "friction"):
        raise ValueError(f"poly_coeffs: expected 'velocity' or 'friction', found {which!r}")
    expr = getattr(derive(variant).noise, which)
    num, den = sp.fraction(sp.together(expr))
    num_c = sp.Poly(num, LAPLACE).all_coeffs()
    den_c = sp.Poly(den, LAPLACE).all_coeffs()
    fnum = sp.lambdify(_ARGS, num_c, modules="numpy")
    fden = sp.lambdify(_ARGS, den_c, modules="numpy")

    def call(**kw: float):
        args = [kw[n] for n in ARG_NAMES]
        num_v, den_v = np.asarray(fnum(*args), float), np.asarray(fden(*args), float)
        return num_v / den_v[0], den_v / den_v[0]

    return call
