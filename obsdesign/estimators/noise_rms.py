"""RMS of an estimator's outputs for band-limited measurement noise, summed in closed form.

Noise model (as :mod:`obsdesign.design.noise`): band-limited white noise of RMS ``eta``,
flat on ``[0, B]`` Hz. Sampled at ``dt`` its spectrum is flat on ``|theta| <= theta_B =
2 pi B dt`` (``B`` capped at the Nyquist frequency), so a discrete transfer ``G(z)`` from
the measurement to an estimate gives::

    rms^2 = eta^2 / theta_B * integral_0^theta_B |G(e^{j theta})|^2 d theta

summed in closed form (:func:`estimate_noise_rms`: a discrete Lyapunov equation and a matrix
logarithm). The fair tuning rules (:mod:`obsdesign.estimators.tuning`) and the predicted error
(:mod:`obsdesign.estimators.prediction`) read it from here.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from .base import DiscreteEstimator, check_positive

__all__ = ["estimate_noise_rms", "friction_noise_rms", "velocity_noise_rms"]


def _response(est: DiscreteEstimator, row: int, theta: float) -> complex:
    """``G(e^{j theta})`` of the proper form ``D + C (zI - Phi)^-1 B`` (the feedthrough
    ``Cz g1 + d`` is summed once, not at every frequency where its parts nearly cancel)."""
    z = complex(math.cos(theta), math.sin(theta))
    b = est.Phi @ est.g1 + est.g0
    x = np.linalg.solve(z * np.eye(est.nz) - est.Phi, b.astype(complex))
    return complex(est.Cz[row] @ x + (est.Cz[row] @ est.g1 + est.d[row]))


def _stein(A: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """``P = sum_j A^j Q A^jT`` (``P = A P A^T + Q``, ``A`` stable) by Smith's doubling.

    Each step doubles the number of terms summed, so a pole radius ``1 - eps`` takes about
    ``log2(40 / eps)`` steps; unlike the Kronecker solve it does not square the conditioning
    of repeated poles (an ESO's triple pole near 1).
    """
    P = np.array(Q, dtype=float)
    Ak = np.array(A, dtype=float)
    for _ in range(80):
        step = Ak @ P @ Ak.T
        P = P + step
        if not np.max(np.abs(step)) > 1e-17 * np.max(np.abs(P)):
            break
        Ak = Ak @ Ak
    return P


def _logm(X: np.ndarray) -> np.ndarray:
    """Principal logarithm of ``X`` (eigenvalues in the right half plane) by inverse scaling and squaring.

    Square roots (Denman-Beavers) until ``|X - I| <= 1/4``, then ``log X = 2 atanh((X - I)(X + I)^-1)``
    to 1e-17. NumPy only: SciPy's ``logm`` is exact too, but its triangular solves cost a thread
    hand-off of OpenBLAS each (1 ms for a 5 x 5 on a loaded machine, against 5 us for ``inv``).
    """
    eye = np.eye(X.shape[0])
    halvings = 0
    while np.linalg.norm(X - eye, 1) > 0.25 and halvings < 64:
        Y, Mk = X, X
        for _ in range(100):
            inv = np.linalg.inv(Mk)
            Y = Y @ (eye + inv) / 2.0
            Mk = (eye + (Mk + inv) / 2.0) / 2.0
            if np.linalg.norm(Mk - eye, 1) < 1e-15:
                break
        X, halvings = Y, halvings + 1
    Z = (X - eye) @ np.linalg.inv(X + eye)
    Z2, term, total = Z @ Z, Z, Z
    for k in range(1, 12):
        term = term @ Z2
        total = total + term / (2 * k + 1)
    return 2.0 ** (halvings + 1) * total


def _band_power_closed(est: DiscreteEstimator, row: int, top: float) -> tuple[float, float]:
    """``(int_0^top |G|^2 d theta, scale)`` from the impulse response's autocorrelation.

    ``G(z) z^-1`` is the strictly proper system ``(A, e_n s, c_a)`` (the state augmented by
    the delayed input, scaled by ``s``), so ``r_k = c_a A^k P c_a^T`` with ``P`` the discrete
    Lyapunov solution and ``int_0^top |G|^2 = r_0 top + 2 sum_k r_k sin(k top) / k =
    c_a (top I - 2 Im log(I - e^{j top} A)) P c_a^T``. ``scale`` bounds the terms that cancel.
    """
    Phi = np.asarray(est.Phi, dtype=float)
    n = Phi.shape[0]
    b = Phi @ est.g1 + est.g0
    c = np.asarray(est.Cz[row], dtype=float)
    s = float(np.max(np.abs(b))) or 1.0
    A = np.zeros((n + 1, n + 1))
    A[:n, :n] = Phi
    A[:n, n] = b / s
    A, T = scipy.linalg.matrix_balance(A, permute=False)
    t = np.diag(T)
    ca = np.append(c, float(c @ est.g1 + est.d[row]) / s) * t
    q = np.zeros(n + 1)
    q[n] = s / t[n]
    P = _stein(A, np.outer(q, q))
    S = -_logm(np.eye(n + 1) - complex(math.cos(top), math.sin(top)) * A).imag
    M = top * P + 2.0 * S @ P
    scale = float(np.abs(ca) @ (top * np.abs(P) + 2.0 * np.abs(S) @ np.abs(P)) @ np.abs(ca))
    return float(ca @ M @ ca), scale


def _band_power_quad(est: DiscreteEstimator, row: int, top: float, estimate: float) -> float:
    """The same integral by ``quad``, split at the poles' corners, to ``1e-10`` of ``estimate``."""
    import scipy.integrate  # the rare fallback: SciPy's quadrature is not imported otherwise

    poles = np.linalg.eigvals(est.Phi).astype(complex)
    corners = {abs(np.log(p)) for p in poles if p != 0}
    edges = [0.0, *sorted(c for c in corners if 0.0 < c < top), top]
    # Each corner also gets points a decade either side, where the integrand bends.
    fine = sorted({e * f for e in edges[1:-1] for f in (0.1, 1.0, 10.0) if 0.0 < e * f < top} | {0.0, top})

    def power(theta: float) -> float:
        return abs(_response(est, row, theta)) ** 2

    tol = 1e-10 * estimate / len(fine)
    return sum(scipy.integrate.quad(power, lo, hi, limit=400, epsrel=1e-10, epsabs=tol)[0]
               for lo, hi in zip(fine[:-1], fine[1:]))


def estimate_noise_rms(est: DiscreteEstimator, noise_rms: float, bandwidth_hz: float, *, row: int) -> float:
    """RMS of output ``row`` (0: ``v_hat``, 1: ``f_hat``) for band-limited measurement noise.

    Parameters
    ----------
    est : DiscreteEstimator
        The estimator.
    noise_rms : float
        Noise RMS [m].
    bandwidth_hz : float
        Noise bandwidth [Hz].
    row : int
        Output row (0: velocity, 1: friction).

    Returns
    -------
    float
        ``eta sqrt(int_0^theta_B |G(e^{j theta})|^2 d theta / theta_B)``; ``inf`` when ``est``
        has a pole on or outside the unit circle (its response to noise is unbounded).

    Notes
    -----
    With ``G(z) = D + C (zI - Phi)^-1 B`` (:meth:`DiscreteEstimator.transfer_from_measurement`)
    the integral is ``r_0 theta_B + 2 sum_k r_k sin(k theta_B) / k`` over the autocorrelation
    ``r_k`` of the impulse response, summed in closed form by a discrete Lyapunov equation and
    a matrix logarithm (``theta_B = pi``, noise up to the Nyquist frequency, leaves ``pi r_0``:
    the H2 norm). Where the band holds less than ``1e-6`` of the terms that cancel in that sum
    (a narrow band below a fast estimator) it is refined by adaptive quadrature.

    Examples
    --------
    >>> import math, scipy.linalg, obsdesign as od
    >>> from obsdesign.estimators import build
    >>> est = build("dob", od.load_preset("vcm"), omega_q=100.0)
    >>> sys = est.transfer_from_measurement()              # band up to Nyquist: the H2 norm
    >>> c, d = sys.C[1], sys.D[1, 0]
    >>> P = scipy.linalg.solve_discrete_lyapunov(sys.A, sys.B @ sys.B.T)
    >>> h2 = math.sqrt(d * d + c @ P @ c)
    >>> round(estimate_noise_rms(est, 1e-6, 1e9, row=1) / (1e-6 * h2), 9)
    1.0
    """
    if not isinstance(est, DiscreteEstimator):
        raise TypeError(f"est: expected a DiscreteEstimator, found {type(est).__name__}")
    eta = float(noise_rms)
    if not (math.isfinite(eta) and eta >= 0.0):
        raise ValueError(f"noise_rms: expected a finite number >= 0 [m], found {noise_rms!r}")
    B = check_positive("noise_bandwidth", bandwidth_hz, "Hz")
    if eta == 0.0:
        return 0.0
    if not float(np.max(np.abs(np.linalg.eigvals(est.Phi)))) < 1.0:
        return math.inf
    top = min(2.0 * math.pi * B * est.dt, math.pi)
    total, scale = _band_power_closed(est, row, top)
    if not total > 1e-6 * scale:
        total = _band_power_quad(est, row, top, max(total, 1e-12 * scale))
    return eta * math.sqrt(total / top)


def friction_noise_rms(est: DiscreteEstimator, noise_rms: float, bandwidth_hz: float) -> float:
    """RMS [N] of ``f_hat`` for band-limited measurement noise of RMS ``noise_rms`` [m] over ``[0, B]`` Hz.

    Parameters
    ----------
    est : DiscreteEstimator
        The estimator.
    noise_rms : float
        Noise RMS [m].
    bandwidth_hz : float
        Noise bandwidth [Hz].

    Computed from the discrete transfer ``y -> f_hat`` (:meth:`DiscreteEstimator.transfer_from_measurement`).
    """
    return estimate_noise_rms(est, noise_rms, bandwidth_hz, row=1)


def velocity_noise_rms(est: DiscreteEstimator, noise_rms: float, bandwidth_hz: float) -> float:
    """RMS [m/s] of ``v_hat`` for the same noise.

    Parameters
    ----------
    est : DiscreteEstimator
        The estimator.
    noise_rms : float
        Noise RMS [m].
    bandwidth_hz : float
        Noise bandwidth [Hz].
    """
    return estimate_noise_rms(est, noise_rms, bandwidth_hz, row=0)
