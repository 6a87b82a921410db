"""Numeric callables of the symbolic derivation (one source of truth, no SymPy at run time).

Every number of the design package comes from an expression of
:func:`obsdesign.symbolic.derive`. The expressions are turned into NumPy functions
once, by :mod:`obsdesign.symbolic.generate`, and shipped as source in
``obsdesign/design/_generated.py`` (each body as SymPy's ``lambdify`` prints it);
``tests/test_generated.py`` checks the file against a fresh derivation. Regenerate
after a change of the symbolic model::

    python -m obsdesign.design.numeric --regenerate

Arguments are passed by the names of :data:`ARG_NAMES` (``m, sigma, beta, Cf, s,
kappa, rho, k, L1, L2``).

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

__all__ = ["ARG_NAMES", "compiled", "model_values", "poly_coeffs", "stability_conditions"]

ARG_NAMES = ("m", "sigma", "beta", "Cf", "s", "kappa", "rho", "k", "L1", "L2")


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


@functools.lru_cache(maxsize=None)
def compiled(variant: str, what: str) -> Callable[..., object]:
    """The NumPy function of the named derivation result.

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
    from . import _generated  # here, so that --regenerate runs without the file

    try:
        fn = _generated.FUNCTIONS[(variant, what)]
    except KeyError:
        raise ValueError(f"compiled: unknown expression {what!r} of variant {variant!r}") from None

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
    from . import _generated

    fnum, fden = _generated.POLY_COEFFS[(variant, which)]

    def call(**kw: float):
        args = [kw[n] for n in ARG_NAMES]
        num_v, den_v = np.asarray(fnum(*args), float), np.asarray(fden(*args), float)
        return num_v / den_v[0], den_v / den_v[0]

    return call


def stability_conditions(variant: str) -> tuple[tuple[str, str, str, str], ...]:
    """Proposition 1 as printed by the derivation: ``(gain, printed gain, relation, condition)`` per gain.

    Parameters
    ----------
    variant : {'lag', 'static'}

    >>> stability_conditions("lag")[1]
    ('L2', 'L_2', '<', 'L_2 < sigma/beta')
    """
    from . import _generated

    return _generated.STABILITY_CONDITIONS[variant]


if __name__ == "__main__":
    from ..symbolic.generate import main

    raise SystemExit(main())
