"""The float32 microcontroller profile's numbers: the switched discretisation tabulated over the stiffness.

The host controller recomputes the exact discretisation (:func:`obsdesign.design.discretize.coefficients`:
square root, logarithm, a 16-term series) whenever the scheduled stiffness changes. A drive's
microcontroller cannot afford that in a 100 us period, so the ``cortex-m4f`` target evaluates, at
export time and in double precision, the same coefficients on ``[0, kappa]`` and stores them as
piecewise cubics in the stiffness (:func:`stiffness_table`); the step evaluates one segment. The
observer runs in increment form (the estimate itself is the state)::

    w[n+1] = w[n] + (Phi - I) w[n] + b_u u[n] + g_d (x[n+1] - x[n]),   g_d = Gamma1 g + L

which is the host's recursion ``y[n+1] = Phi y[n] + b_u u[n] + g0 x[n] + g1 x[n+1]`` with
``w = y + L x``: it holds because the measurement gain is ``g = A L`` (the plant's velocity and
friction rows do not read the absolute position), so the position's coefficients sum to zero and
only its increment enters. :func:`stiffness_table` checks that identity at every node. The step
computes it as ``w[n+1] = w[n] + E w[n] + b_u u[n] + g_d (dx - dt v_hat[n])`` with
``E = Phi - I + dt g_d e1'``: the innovation ``dx - dt v_hat`` is small, and the two large terms
``g_d dx`` and ``dt g_d v_hat`` that cancel in sliding are combined in double at export time, so the
float32 rounding of the stored numbers does not bias the estimate.

The natural logarithm of the stiffness (eq:2:3:5) and of the pre-sliding shape is a polynomial
fitted here (:func:`log_polynomial`) on the mantissa ``[sqrt(1/2), sqrt(2))``; the exponent comes
from the float's bits, so the step calls no library function.

Examples
--------
>>> import obsdesign as od
>>> from obsdesign.sampled import sampled_controller
>>> table = stiffness_table(sampled_controller(od.load_preset("vcm")))
>>> table.segments, table.coefficients.shape
(16, (16, 8, 4))
>>> table.relative_error < 1e-6          # the fit's worst error, relative to each coefficient's range
True
>>> poly = log_polynomial()
>>> poly.max_error < 2e-7                # [natural log units], over the whole mantissa range
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..design.discretize import coefficients

__all__ = ["StiffnessTable", "LogPolynomial", "stiffness_table", "log_polynomial", "exact_coefficients",
           "COEFFICIENT_NAMES"]

#: The eight numbers of the recursion for one stiffness, in the order the table stores them.
COEFFICIENT_NAMES = ("E11", "E12", "E21", "E22", "BU1", "BU2", "GD1", "GD2")

_FIT_POINTS = 12     # least-squares points per segment (Chebyshev nodes)
_CHECK_POINTS = 64   # points per segment where the error bound is measured


@dataclass(frozen=True, eq=False)
class StiffnessTable:
    """The recursion's coefficients as piecewise cubics in the stiffness, stored in float32.

    Attributes
    ----------
    kappa : float
        Upper end of the table [N/m] (the stiffness bound).
    segments : int
        Number of equal segments of ``[0, kappa]``.
    coefficients : ndarray, shape (segments, 8, 4), float32
        ``c[i, j, :]``: coefficient ``j`` (:data:`COEFFICIENT_NAMES`) on segment ``i`` as
        ``c0 + t (c1 + t (c2 + t c3))`` with ``t = k segments / kappa - i`` in ``[0, 1]``.
    max_error : ndarray, shape (8,)
        Largest difference between the stored cubic (float32 coefficients, evaluated in double) and
        the exact double discretisation, over ``_CHECK_POINTS`` points per segment and the ends.
    scale : ndarray, shape (8,)
        Largest magnitude of each coefficient over ``[0, kappa]``.
    """

    kappa: float
    segments: int
    coefficients: np.ndarray
    max_error: np.ndarray
    scale: np.ndarray

    @property
    def relative_error(self) -> float:
        """The worst ``max_error / scale`` over the eight coefficients."""
        return float(np.max(self.max_error / np.where(self.scale > 0, self.scale, 1.0)))

    def evaluate(self, k: float) -> np.ndarray:
        """The eight coefficients at stiffness ``k`` (double evaluation of the stored cubics)."""
        x = min(max(float(k), 0.0), self.kappa) * self.segments / self.kappa
        i = min(int(x), self.segments - 1)
        t = x - i
        c = self.coefficients[i].astype(float)
        return c[:, 0] + t * (c[:, 1] + t * (c[:, 2] + t * c[:, 3]))


@dataclass(frozen=True, eq=False)
class LogPolynomial:
    """``ln(1 + t) ~ t q(t)`` on ``t`` in ``[sqrt(1/2) - 1, sqrt(2) - 1)``.

    Attributes
    ----------
    coefficients : tuple of float
        ``q`` in increasing powers, rounded to float32.
    max_error : float
        Largest ``|ln(1 + t) - t q(t)|`` on a dense grid (double evaluation of the float32 coefficients).
    """

    coefficients: tuple
    max_error: float


def exact_coefficients(ctrl, k: float) -> np.ndarray:
    """The eight recursion coefficients of :data:`COEFFICIENT_NAMES` at stiffness ``k``, in double.

    The same arithmetic as :func:`obsdesign.sampled.kernel.observer_sample` (``Phi``, ``b_u``,
    ``g1``) of the controller ``ctrl`` (a :class:`~obsdesign.sampled.SampledController`), turned
    into the increment form: ``E = Phi - I + dt g_d e1'``, ``g_d = g1 + L``.

    Parameters
    ----------
    ctrl : SampledController
        The controller (its observer arrays and ``dt``).
    k : float
        Stiffness [N/m].

    Returns
    -------
    ndarray, shape (8,)
        In the order of :data:`COEFFICIENT_NAMES`.

    Raises
    ------
    ValueError
        The observer reads the absolute position (``g != A L``): the increment form does not hold.
    """
    obs = ctrl.observer
    A = obs.A0 + k * obs.A1
    b = obs.b0 + k * obs.b1
    g = obs.g0 + k * obs.g1
    c = coefficients(A[0, 0], A[0, 1], A[1, 0], A[1, 1], ctrl.dt)
    Phi = np.array(c[0:4]).reshape(2, 2)
    G0 = np.array(c[4:8]).reshape(2, 2)
    G1 = np.array(c[8:12]).reshape(2, 2)
    L = np.array([obs.design.L1, obs.design.L2])
    bu = G0 @ b
    gx1 = G1 @ g
    gd = gx1 + L
    # increment form: the position's coefficients gx0 - Phi L and gx1 + L cancel when g = A L (checked on the
    # affine arrays, where it is structural; g1 = g(1) - g(0) carries the rounding of g0's magnitude)
    tol = 1e-13 * (np.abs(obs.A0) @ np.abs(L) + np.abs(obs.A1) @ np.abs(L))
    for A_part, g_part in ((obs.A0, obs.g0), (obs.A1, obs.g1)):
        if np.any(np.abs(g_part - A_part @ L) > tol):
            raise ValueError(f"variant: the increment form needs a measurement gain g = A L (no absolute-position "
                             f"term in the observer); found g - A L = {g_part - A_part @ L!r}")
    E = Phi - np.eye(2)
    E[:, 0] += ctrl.dt * gd  # innovation form: the large L v and L dx / h terms cancel here, in double
    return np.array([E[0, 0], E[0, 1], E[1, 0], E[1, 1], bu[0], bu[1], gd[0], gd[1]])


def _segment_fit(ctrl, lo: float, hi: float) -> np.ndarray:
    nodes = 0.5 - 0.5 * np.cos(np.pi * (np.arange(_FIT_POINTS) + 0.5) / _FIT_POINTS)
    values = np.array([exact_coefficients(ctrl, lo + (hi - lo) * t) for t in nodes])
    V = np.vander(nodes, 4, increasing=True)
    fit, *_ = np.linalg.lstsq(V, values, rcond=None)
    return fit.T  # (8, 4)


def stiffness_table(ctrl, *, segments: int = 16) -> StiffnessTable:
    """Tabulate the switched discretisation of ``ctrl`` over ``[0, kappa]``.

    Parameters
    ----------
    ctrl : SampledController
        The controller (the paper observer's arrays, ``kappa`` and ``dt``).
    segments : int
        Number of cubic segments (each holds 8 x 4 float32 numbers, 128 bytes).

    Returns
    -------
    StiffnessTable
        With the error bound measured against the exact double discretisation.

    Raises
    ------
    ValueError
        ``segments`` below 1, or a design whose observer reads the absolute position.
    """
    if isinstance(segments, bool) or not isinstance(segments, int) or segments < 1:
        raise ValueError(f"segments: expected an integer >= 1, found {segments!r}")
    kappa = float(ctrl.config.friction.kappa)
    width = kappa / segments
    table = np.empty((segments, 8, 4), dtype=np.float32)
    for i in range(segments):
        table[i] = _segment_fit(ctrl, i * width, (i + 1) * width).astype(np.float32)
    checks = np.concatenate([(np.arange(segments * _CHECK_POINTS) + 0.5) / _CHECK_POINTS, [0.0, segments]])
    err = np.zeros(8)
    scale = np.zeros(8)
    for x in checks:
        k = x * width
        exact = exact_coefficients(ctrl, k)
        i = min(int(x), segments - 1)
        t = x - i
        c = table[i].astype(float)
        approx = c[:, 0] + t * (c[:, 1] + t * (c[:, 2] + t * c[:, 3]))
        err = np.maximum(err, np.abs(approx - exact))
        scale = np.maximum(scale, np.abs(exact))
    return StiffnessTable(kappa=kappa, segments=segments, coefficients=table, max_error=err, scale=scale)


def log_polynomial(degree: int = 7) -> LogPolynomial:
    """Fit ``ln(1 + t) = t q(t)`` on the reduced mantissa range with ``q`` of the given degree.

    Parameters
    ----------
    degree : int
        Degree of ``q``.

    Returns
    -------
    LogPolynomial
    """
    lo, hi = math.sqrt(0.5) - 1.0, math.sqrt(2.0) - 1.0
    n = 400
    t = lo + (hi - lo) * (0.5 - 0.5 * np.cos(np.pi * (np.arange(n) + 0.5) / n))
    q = np.log1p(t) / t
    V = np.vander(t, degree + 1, increasing=True)
    fit, *_ = np.linalg.lstsq(V, q, rcond=None)
    coef = tuple(float(np.float32(c)) for c in fit)
    dense = np.linspace(lo, hi, 20001)
    approx = dense * np.polynomial.polynomial.polyval(dense, coef)
    return LogPolynomial(coefficients=coef, max_error=float(np.max(np.abs(approx - np.log1p(dense)))))
