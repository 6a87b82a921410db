"""The common discrete form of every estimator and the numba step that runs it.

Every estimator of velocity and friction, whatever its continuous design, is
run at the controller's sample time ``dt`` as::

    z[n] = Phi z[n-1] + gu u[n-1] + g0 y[n-1] + g1 y[n]
    (v_hat[n], f_hat[n]) = Cz z[n] + d y[n]

after each measurement ``y[n] = x_meas[n]``, with the input ``u[n-1]`` [N] held
over the last interval. ``nz <= 4``. A continuous observer
``z' = A z + b u + g y`` maps to this form exactly when ``u`` is held (ZOH) and
``y`` is linear between its samples (FOH)::

    Phi = exp(A dt),  gu = Gamma0 b,  g0 = (Gamma0 - Gamma1) g,  g1 = Gamma1 g

with ``Gamma0 = dt phi1(A dt)``, ``Gamma1 = dt phi2(A dt)`` (see
:mod:`obsdesign.design.discretize`). :func:`foh_matrices` computes them from one
matrix exponential of an augmented matrix, for any ``nz``.

Examples
--------
>>> import numpy as np
>>> est = DiscreteEstimator(  # toy: a filtered derivative and a constant friction state
...     name="toy", dt=1e-3, Phi=np.diag([0.5, 1.0]), gu=np.zeros(2), g0=np.array([-100.0, 0.0]),
...     g1=np.array([100.0, 0.0]), Cz=np.eye(2), d=np.zeros(2), params={}, tuning="manual",
...     init=np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
>>> v, f = run_offline(est, np.zeros(4), np.array([0.0, 0.0, 1e-3, 2e-3]))
>>> v.round(6).tolist()
[0.0, 0.0, 0.1, 0.15]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from .._validate import POSITIVE, as_float
from ..params import Config

if TYPE_CHECKING:
    import control as ct

__all__ = [
    "check_config",
    "MAX_STATES",
    "DiscreteEstimator",
    "estimator_step",
    "run_offline",
    "foh_matrices",
    "discretize_observer",
    "check_positive",
]

#: Largest state dimension of the common form (the kernel's loop is written for it).
MAX_STATES = 4


def check_config(cfg) -> Config:
    """``cfg`` if it is a :class:`~obsdesign.params.Config` (validated at its construction), else a TypeError.

    Parameters
    ----------
    cfg : object
        The design handed to an estimator's builder.

    >>> import obsdesign as od
    >>> check_config(od.load_preset("vcm")).name
    'vcm'
    >>> check_config({"rho": 4.0})
    Traceback (most recent call last):
    ...
    TypeError: cfg: expected a Config, found dict
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    return cfg


def check_positive(name: str, value, unit: str) -> float:
    """``value`` as a float, or one ValueError naming ``name``, the range and the value found.

    Parameters
    ----------
    name : str
        The argument's name for messages.
    value : object
        The value to check.
    unit : str
        Its unit, for messages.

    >>> check_positive("omega_o", -1.0, "rad/s")
    Traceback (most recent call last):
    ...
    ValueError: omega_o: expected a finite number > 0 [rad/s], found -1.0
    """
    expected = f"{POSITIVE.describe()} [{unit}]"
    number = as_float(name, value, expected)
    if not POSITIVE.contains(number):
        raise ValueError(f"{name}: expected {expected}, found {number!r}")
    return number


def foh_matrices(A: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Phi, Gamma0, Gamma1)`` of ``A`` over ``h`` from one augmented matrix exponential.

    Parameters
    ----------
    A : ndarray
        Continuous system matrix.
    h : float
        Sample time [s].

    ``expm([[A h, I, 0], [0, 0, I], [0, 0, 0]])`` holds ``exp(A h)``, ``phi1(A h)`` and
    ``phi2(A h)`` in its first block row; ``Gamma0 = h phi1``, ``Gamma1 = h phi2``.

    Examples
    --------
    >>> Phi, G0, G1 = foh_matrices(np.array([[-2.0]]), 0.5)   # closed forms for a scalar
    >>> a = -1.0
    >>> bool(np.isclose(G0[0, 0], 0.5 * (np.exp(a) - 1) / a)), bool(np.isclose(G1[0, 0], 0.5 * (np.exp(a) - 1 - a) / a**2))
    (True, True)
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    M = np.zeros((3 * n, 3 * n))
    M[:n, :n] = A * h
    M[:n, n:2 * n] = np.eye(n)
    M[n:2 * n, 2 * n:] = np.eye(n)
    import scipy.linalg

    E = scipy.linalg.expm(M)
    return E[:n, :n].copy(), h * E[:n, n:2 * n], h * E[:n, 2 * n:]


def discretize_observer(A: np.ndarray, b: np.ndarray, g: np.ndarray, h: float):
    """``(Phi, gu, g0, g1)`` of ``z' = A z + b u + g y`` with ZOH ``u`` and FOH ``y`` (exact).

    Parameters
    ----------
    A : ndarray
        Continuous observer matrix.
    b : ndarray
        Input vector.
    g : ndarray
        Measurement vector.
    h : float
        Sample time [s].
    """
    Phi, G0, G1 = foh_matrices(A, h)
    b, g = np.asarray(b, float), np.asarray(g, float)
    return Phi, G0 @ b, (G0 - G1) @ g, G1 @ g


def _array(name: str, value, shape: tuple[int, ...]) -> np.ndarray:
    a = np.ascontiguousarray(value, dtype=np.float64)
    if a.shape != shape:
        raise ValueError(f"{name}: expected shape {shape}, found {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected finite values, found {a!r}")
    a.setflags(write=False)
    return a


@dataclass(frozen=True, kw_only=True)
class DiscreteEstimator:
    """An estimator of velocity and friction in the common discrete form.

    Attributes
    ----------
    name : str
        Its name in :data:`obsdesign.estimators.ESTIMATORS`.
    dt : float
        Sample time [s] it was discretized at.
    Phi : ndarray, shape (nz, nz)
    gu, g0, g1 : ndarray, shape (nz,)
        Gains of ``u[n-1]`` [N], ``y[n-1]`` and ``y[n]`` [m].
    Cz : ndarray, shape (2, nz)
    d : ndarray, shape (2,)
        Output map: ``(v_hat, f_hat) = Cz z + d y``.
    params : dict
        The design values (knob, model, poles); JSON-ready floats and strings.
    tuning : str
        How the knob was chosen (``"noise"``, ``"rate"``, ``"manual"``, ``"reference"``).
    init : ndarray, shape (nz, 3)
        ``z0 = init @ (x0, v0, f0)`` starts the estimator with outputs ``v0, f0`` at ``y = x0``
        and its model states consistent with them.

    All arrays are float64, C-contiguous and read-only.
    """

    name: str
    dt: float
    Phi: np.ndarray
    gu: np.ndarray
    g0: np.ndarray
    g1: np.ndarray
    Cz: np.ndarray
    d: np.ndarray
    params: dict = field(compare=False)
    tuning: str
    init: np.ndarray

    def __post_init__(self) -> None:
        check_positive("dt", self.dt, "s")
        Phi = np.asarray(self.Phi)
        if Phi.ndim != 2 or Phi.shape[0] != Phi.shape[1] or not 1 <= Phi.shape[0] <= MAX_STATES:
            raise ValueError(f"Phi: expected a square (nz, nz) array with 1 <= nz <= {MAX_STATES}, found shape {Phi.shape}")
        nz = Phi.shape[0]
        for name, shape in (("Phi", (nz, nz)), ("gu", (nz,)), ("g0", (nz,)), ("g1", (nz,)),
                            ("Cz", (2, nz)), ("d", (2,)), ("init", (nz, 3))):
            object.__setattr__(self, name, _array(name, getattr(self, name), shape))
        # The start state must reproduce (v0, f0) at y = x0 for every (x0, v0, f0).
        out = self.Cz @ self.init + np.column_stack([self.d, np.zeros((2, 2))])
        want = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        scale = 1.0 + np.abs(self.Cz) @ np.abs(self.init) + np.abs(self.d)[:, None]
        if not np.all(np.abs(out - want) <= 1e-9 * scale):
            raise ValueError(f"init: Cz @ init + [d, 0, 0] must be [[0, 1, 0], [0, 0, 1]], found {out.tolist()}")

    @property
    def nz(self) -> int:
        """Number of states."""
        return self.Phi.shape[0]

    def initial_state(self, x0: float, v0: float = 0.0, f0: float = 0.0) -> np.ndarray:
        """A writable state ``z0`` whose outputs are ``(v0, f0)`` at ``y = x0``."""
        return np.ascontiguousarray(self.init @ np.array([x0, v0, f0], float))

    def poles(self) -> np.ndarray:
        """Eigenvalues of ``Phi`` (the discrete error poles)."""
        return np.linalg.eigvals(self.Phi)

    def transfer_from_measurement(self) -> ct.StateSpace:
        """Discrete system from ``y`` to ``(v_hat, f_hat)`` at ``u = 0`` (python-control).

        With ``xi[n] = z[n] - g1 y[n]`` the recursion is a proper state-space system
        ``xi[n] = Phi xi[n-1] + (Phi g1 + g0) y[n-1]``, ``out = Cz xi + (Cz g1 + d) y``.
        Use ``sys[1, 0]`` for ``y -> f_hat`` and ``sys[0, 0]`` for ``y -> v_hat``.
        """
        import control as ct

        B = (self.Phi @ self.g1 + self.g0).reshape(-1, 1)
        D = (self.Cz @ self.g1 + self.d).reshape(2, 1)
        return ct.ss(np.array(self.Phi), B, np.array(self.Cz), D, self.dt,
                     inputs=["x_meas"], outputs=["v_hat", "f_hat"], name=f"{self.name}:y")

    def transfer_from_input(self) -> ct.StateSpace:
        """Discrete system from ``u`` (held) to ``(v_hat, f_hat)`` at ``y = 0``."""
        import control as ct

        return ct.ss(np.array(self.Phi), np.array(self.gu).reshape(-1, 1), np.array(self.Cz),
                     np.zeros((2, 1)), self.dt, inputs=["u"], outputs=["v_hat", "f_hat"], name=f"{self.name}:u")


@njit(cache=True, error_model="numpy")
def estimator_step(Phi, gu, g0, g1, Cz, d, z, u_prev, y_prev, y):
    """Advance ``z`` in place by one sample and return ``(v_hat, f_hat)``.

    ``z[n] = Phi z[n-1] + gu u[n-1] + g0 y[n-1] + g1 y[n]``; no allocation (``nz <= 4``).
    """
    nz = z.shape[0]
    t0 = t1 = t2 = t3 = 0.0
    for i in range(nz):
        acc = gu[i] * u_prev + g0[i] * y_prev + g1[i] * y
        for j in range(nz):
            acc += Phi[i, j] * z[j]
        if i == 0:
            t0 = acc
        elif i == 1:
            t1 = acc
        elif i == 2:
            t2 = acc
        else:
            t3 = acc
    z[0] = t0
    if nz > 1:
        z[1] = t1
    if nz > 2:
        z[2] = t2
    if nz > 3:
        z[3] = t3
    return estimator_output(Cz, d, z, y)


@njit(cache=True, error_model="numpy")
def estimator_output(Cz, d, z, y):
    """``(v_hat, f_hat) = Cz z + d y``."""
    v = d[0] * y
    f = d[1] * y
    for j in range(z.shape[0]):
        v += Cz[0, j] * z[j]
        f += Cz[1, j] * z[j]
    return v, f


@njit(cache=True, error_model="numpy")
def _run(Phi, gu, g0, g1, Cz, d, z, u, y, out_v, out_f):
    out_v[0], out_f[0] = estimator_output(Cz, d, z, y[0])
    for n in range(1, y.shape[0]):
        out_v[n], out_f[n] = estimator_step(Phi, gu, g0, g1, Cz, d, z, u[n - 1], y[n - 1], y[n])


def run_offline(est: DiscreteEstimator, u: np.ndarray, y: np.ndarray, *, z0: np.ndarray | None = None,
                v0: float = 0.0, f0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Run an estimator over recorded arrays with :func:`estimator_step`.

    Parameters
    ----------
    est : DiscreteEstimator
    u : ndarray, shape (n,)
        Applied net force [N]; ``u[n]`` is held over ``[n dt, (n+1) dt)``.
    y : ndarray, shape (n,)
        Measured displacement [m].
    z0 : ndarray, shape (nz,), optional
        Start state; default ``est.initial_state(y[0], v0, f0)``.
    v0, f0 : float
        Initial velocity [m/s] and friction [N] estimates.

    Returns
    -------
    v_hat, f_hat : ndarray, shape (n,)
        Estimates at the sample instants; sample 0 is the start state's output.
    """
    if not isinstance(est, DiscreteEstimator):
        raise TypeError(f"est: expected a DiscreteEstimator, found {type(est).__name__}")
    u = np.ascontiguousarray(u, dtype=np.float64)
    y = np.ascontiguousarray(y, dtype=np.float64)
    if u.ndim != 1 or y.ndim != 1 or u.shape != y.shape or y.size < 1:
        raise ValueError(f"u, y: expected two 1-D arrays of one length >= 1, found shapes {u.shape} and {y.shape}")
    z = est.initial_state(y[0], v0, f0) if z0 is None else np.array(z0, dtype=np.float64)
    if z.shape != (est.nz,):
        raise ValueError(f"z0: expected shape ({est.nz},), found {z.shape}")
    out_v, out_f = np.empty_like(y), np.empty_like(y)
    _run(est.Phi, est.gu, est.g0, est.g1, est.Cz, est.d, z, u, y, out_v, out_f)
    return out_v, out_f
