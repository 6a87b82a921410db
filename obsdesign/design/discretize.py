"""Exact discretization of the 2-state observer for a held input and a linear measurement.

The observer ``y' = A y + b u + g x`` (eq:3:1:2) is advanced over one sample
period ``h`` with ``u`` held (zero-order hold) and ``x`` linear between its
samples (first-order hold)::

    y[n+1] = Phi y[n] + Gamma0 b u[n] + (Gamma0 - Gamma1) g x[n] + Gamma1 g x[n+1]

with ``Phi = exp(A h)``, ``Gamma0 = h phi1(A h)``, ``Gamma1 = h phi2(A h)`` and
``phi1(z) = (e^z - 1)/z``, ``phi2(z) = (e^z - 1 - z)/z^2``. This is exact, so the
recursion is stable whenever the continuous observer is, however fast its poles
are compared with the sampling rate.

Closed form for the 2x2 case, with no special case for the double pole the
design places at ``k = kappa`` (the confluent case) or for an eigenvalue at 0:

1. balance ``A' = D^-1 A D`` with ``D = diag(1, c)``, ``c = sqrt(|a21/a12|)`` (the
   observer matrix has ``|a21| >> |a12|``);
2. scale ``h_s = h / 2^s`` so that ``|A' h_s|_1 <= 1/2`` and sum the Taylor series of
   ``phi2`` (16 terms, Horner), then ``phi1 = I + B phi2``, ``exp = I + B phi1``;
3. square back ``s`` times: ``Phi(2h) = Phi^2``, ``Gamma0(2h) = (I + Phi) Gamma0``,
   ``J(2h) = (I + Phi) J + h Gamma0`` with ``J = h Gamma1``.

Examples
--------
>>> import numpy as np, scipy.linalg
>>> A = np.array([[-249.0, -1.86], [15470.0, 0.0]])   # table1 observer at k = kappa
>>> Phi, G0, G1 = coefficient_matrices(A, 1e-4)
>>> bool(np.allclose(Phi, scipy.linalg.expm(A * 1e-4), rtol=1e-14, atol=0))
True
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["coefficients", "coefficient_matrices", "step_matrices", "lowpass_arrays"]

_TERMS = 16


@njit(cache=True, error_model="numpy")
def _mul(a11, a12, a21, a22, b11, b12, b21, b22):
    return (a11 * b11 + a12 * b21, a11 * b12 + a12 * b22, a21 * b11 + a22 * b21, a21 * b12 + a22 * b22)


@njit(cache=True, error_model="numpy")
def coefficients(a11: float, a12: float, a21: float, a22: float, h: float):
    """``Phi, Gamma0, Gamma1`` of ``A = [[a11, a12], [a21, a22]]`` over ``h``, as 12 floats (row-major)."""
    c = 1.0
    if a12 != 0.0 and a21 != 0.0:
        c = math.sqrt(abs(a21 / a12))
    b11, b12, b21, b22 = a11, a12 * c, a21 / c, a22  # balanced A'
    norm = max(abs(b11) + abs(b21), abs(b12) + abs(b22)) * h
    s = 0
    if norm > 0.5:
        s = int(math.ceil(math.log2(norm / 0.5)))
    hs = h / (2.0**s)
    b11, b12, b21, b22 = b11 * hs, b12 * hs, b21 * hs, b22 * hs
    # Horner: phi2(B) = sum_j B^j / (j + 2)!
    fact = 1.0
    for j in range(2, _TERMS + 2):
        fact *= j
    p11, p12, p21, p22 = 1.0 / fact, 0.0, 0.0, 1.0 / fact
    for j in range(_TERMS - 1, 0, -1):
        fact /= j + 2
        p11, p12, p21, p22 = _mul(b11, b12, b21, b22, p11, p12, p21, p22)
        p11 += 1.0 / fact
        p22 += 1.0 / fact
    # p = phi2(B); phi1 = I + B phi2; exp = I + B phi1
    q11, q12, q21, q22 = _mul(b11, b12, b21, b22, p11, p12, p21, p22)
    q11 += 1.0
    q22 += 1.0
    e11, e12, e21, e22 = _mul(b11, b12, b21, b22, q11, q12, q21, q22)
    e11 += 1.0
    e22 += 1.0
    g11, g12, g21, g22 = q11 * hs, q12 * hs, q21 * hs, q22 * hs  # Gamma0
    j11, j12, j21, j22 = p11 * hs * hs, p12 * hs * hs, p21 * hs * hs, p22 * hs * hs  # J = h Gamma1
    hc = hs
    for _ in range(s):
        i11, i12, i21, i22 = e11 + 1.0, e12, e21, e22 + 1.0  # I + Phi
        n11, n12, n21, n22 = _mul(i11, i12, i21, i22, j11, j12, j21, j22)
        j11, j12, j21, j22 = n11 + hc * g11, n12 + hc * g12, n21 + hc * g21, n22 + hc * g22
        g11, g12, g21, g22 = _mul(i11, i12, i21, i22, g11, g12, g21, g22)
        e11, e12, e21, e22 = _mul(e11, e12, e21, e22, e11, e12, e21, e22)
        hc *= 2.0
    # Undo the balancing: f(A) = D f(A') D^-1, D = diag(1, c).
    inv_h = 1.0 / h
    return (e11, e12 / c, e21 * c, e22,
            g11, g12 / c, g21 * c, g22,
            j11 * inv_h, j12 / c * inv_h, j21 * c * inv_h, j22 * inv_h)


def coefficient_matrices(A: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Phi, Gamma0, Gamma1)`` as 2x2 arrays (NumPy wrapper of :func:`coefficients`).

    Parameters
    ----------
    A : array_like, shape (2, 2)
        Observer matrix.
    h : float
        Step [s].
    """
    A = np.asarray(A, float)
    r = np.array(coefficients(A[0, 0], A[0, 1], A[1, 0], A[1, 1], float(h)))
    return r[0:4].reshape(2, 2), r[4:8].reshape(2, 2), r[8:12].reshape(2, 2)


def step_matrices(A: np.ndarray, b: np.ndarray, g: np.ndarray, h: float):
    """One-step recursion ``y[n+1] = Phi y[n] + b_u u[n] + g0 x[n] + g1 x[n+1]``.

    Parameters
    ----------
    A : array_like, shape (2, 2)
        Observer matrix A22 - L A12.
    b : array_like, shape (2,)
        Input vector B2 - L B1.
    g : array_like, shape (2,)
        Measurement gain of eq:3:1:2.
    h : float
        Sample time [s].

    Returns ``Phi (2, 2)``, ``b_u (2,)``, ``g0 (2,)``, ``g1 (2,)``.
    """
    Phi, G0, G1 = coefficient_matrices(A, h)
    return Phi, G0 @ np.asarray(b, float), (G0 - G1) @ np.asarray(g, float), G1 @ np.asarray(g, float)


def lowpass_arrays(omega_co: float, dt: float):
    """FOH recursion ``(Phi, g0, g1)`` of the low-pass eq:3:4:5 with state (f_filtered, its derivative).

    Parameters
    ----------
    omega_co : float
        Cutoff [rad/s].
    dt : float
        Sample time [s].
    """
    w = omega_co
    A = np.array([[0.0, 1.0], [-w * w, -2.0 * w]])
    Phi, _, g0, g1 = step_matrices(A, np.zeros(2), np.array([0.0, w * w]), dt)
    return np.ascontiguousarray(Phi), g0, g1
