"""Fair tuning: each baseline's knob from the paper observer's noise or convergence rate.

Noise model (as :mod:`obsdesign.design.noise`): band-limited white noise of RMS ``eta``,
flat on ``[0, B]`` Hz. Sampled at ``dt`` its spectrum is flat on ``|theta| <= theta_B =
2 pi B dt`` (``B`` capped at the Nyquist frequency), so a discrete transfer ``G(z)`` from
the measurement to an estimate gives::

    rms^2 = eta^2 / theta_B * integral_0^theta_B |G(e^{j theta})|^2 d theta

summed in closed form (:func:`estimate_noise_rms`: a discrete Lyapunov equation and a matrix
logarithm), so the knobs below are solved on an integral exact to rounding.

Rules (``rule``):

``"noise"`` (default)
    The knob (ESO ``omega_o``, Kalman ``q``, DOB ``omega_q``) is solved with ``brentq`` on
    its logarithm so that the RMS of the baseline's own friction estimate equals that of the
    paper observer's friction estimate after the low-pass eq:3:4:5, both at ``k = 0``
    (gross sliding) and both discrete at ``dt``. The baselines get no extra filter: each
    compares the signal used for compensation.
``"rate"``
    The slowest error pole equals the paper's dominant pole ``-sqrt(kappa/m)(rho - 1)`` at
    ``k = 0``: ``omega_o = omega_q = sqrt(kappa/m)(rho - 1)``; for the Kalman filter
    ``q`` is solved so that the largest discrete pole radius is ``exp(p_dom dt)``.
``"min-error"``
    The knob minimises the predicted error of the compensated estimate
    (:func:`obsdesign.estimators.prediction.predict_error`: noise propagation plus tracking lag
    of Coulomb reversals), independently of the paper's observer: a log grid of 33 points over
    the knob's range, then a bounded ``minimize_scalar`` between the best point's neighbours.

Both rules are independent of ``eta`` (every RMS is proportional to it; the Kalman gain
depends on ``q / eta^2`` and its knob scales with ``eta^2``), but depend on ``B`` and ``dt``.

Examples
--------
>>> import obsdesign as od
>>> cfg = od.load_preset("vcm")
>>> ref = reference_noise_rms(cfg)
>>> est = tune("eso", cfg)
>>> round(friction_noise_rms(est, *noise_level(cfg)) / ref, 6)
1.0
"""

from __future__ import annotations

import math

import numpy as np
import scipy.integrate
import scipy.linalg
import scipy.optimize

from ..params import Config
from .base import DiscreteEstimator, check_config, check_positive
from .kalman import noise_level
from .paper import build_paper, paper_dominant_pole, with_lowpass
from .registry import ESTIMATORS, RULES

__all__ = ["RULES", "friction_noise_rms", "velocity_noise_rms", "estimate_noise_rms",
           "reference_noise_rms", "reference_estimator", "tune", "noise_level"]

#: Measurement RMS [m] the knobs' search ranges (``EstimatorInfo.knob_range``) are written for.
_RANGE_ETA = 1e-6
#: Relative tolerance of the solved knob (the RMS is a power of it: well inside 1 %).
_XTOL = 1e-9


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


def reference_estimator(cfg: Config) -> DiscreteEstimator:
    """The paper observer at ``k = 0`` followed by the discretized low-pass eq:3:4:5 (``nz = 4``).

    Parameters
    ----------
    cfg : Config
        The design.
    """
    cfg = check_config(cfg)
    _check_paper_stable(cfg)
    return with_lowpass(build_paper(cfg, stiffness=0.0), cfg.observer.omega_co)


def reference_noise_rms(cfg: Config) -> float:
    """RMS [N] of the paper's low-pass filtered friction estimate at ``k = 0``: the equal-noise target.

    Parameters
    ----------
    cfg : Config
        The design.
    """
    return friction_noise_rms(reference_estimator(cfg), *noise_level(cfg))


def _check_paper_stable(cfg: Config) -> float:
    pole = paper_dominant_pole(cfg)
    if not pole < 0.0:
        raise ValueError(
            f"rho: the reference needs a stable paper observer at k = 0 (rho > 1), found rho = "
            f"{cfg.observer.rho!r} (dominant pole {pole:.4g} 1/s)")
    return pole


def _solve_log(fun, lo: float, hi: float, what: str) -> float:
    """Root of ``fun(log knob)`` on ``[log lo, log hi]`` (``fun`` increasing in the knob)."""
    a, b = math.log(lo), math.log(hi)
    fa, fb = fun(a), fun(b)
    if not (fa < 0.0 < fb):
        raise ValueError(f"{what}: no knob in [{lo:g}, {hi:g}] reaches the target "
                         f"(relative mismatch {fa:+.3g} at the low end, {fb:+.3g} at the high end)")
    return math.exp(scipy.optimize.brentq(fun, a, b, xtol=_XTOL, rtol=_XTOL, maxiter=200))


def _min_error(make, cfg: Config, lo: float, hi: float) -> float:
    """The knob in ``[lo, hi]`` of least :func:`~obsdesign.estimators.prediction.predict_error` (total)."""
    from .prediction import predict_error

    def cost(log_knob: float) -> float:
        try:
            return predict_error(make(math.exp(log_knob)), cfg).total
        except (ValueError, ArithmeticError, np.linalg.LinAlgError):
            return math.inf

    grid = np.linspace(math.log(lo), math.log(hi), 33)
    values = [cost(x) for x in grid]
    i = int(np.argmin(values))
    if not math.isfinite(values[i]):
        raise ValueError(f"min-error rule: no knob in [{lo:g}, {hi:g}] gives a stable estimator")
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    res = scipy.optimize.minimize_scalar(cost, bounds=(a, b), method="bounded", options={"xatol": 1e-4})
    return math.exp(float(res.x)) if res.fun < values[i] else math.exp(float(grid[i]))


def tune(name: str, cfg: Config, *, rule: str = "noise", sigma_model: float | None = None) -> DiscreteEstimator:
    """An estimator of the registry with its knob set by the fair tuning rule.

    The knob, its search range and the rules come from the entry of
    :data:`~obsdesign.estimators.ESTIMATORS` (:class:`~obsdesign.estimators.EstimatorInfo`).

    Parameters
    ----------
    name : str
        A name of :data:`~obsdesign.estimators.ESTIMATORS`. The paper entries are the reference
        and are returned as designed (``k = 0``).
    cfg : Config
        The design.
    rule : str
        One of :data:`RULES`: equal friction-noise RMS with the paper's filtered estimate
        (``"noise"``), equal slowest pole (``"rate"``), or least predicted error (``"min-error"``).
    sigma_model : float, optional
        Viscous coefficient of the baselines' model (default: ``sigma`` for ``static``, 0 for ``lag``).

    Raises
    ------
    ValueError
        Unknown name or rule; unstable reference (``rho <= 1``); no sensor noise for ``"noise"``
        or for the Kalman filter; no knob in the search range reaches the target.
    """
    info = ESTIMATORS[ESTIMATORS.check(name, kind="name")]
    if not isinstance(rule, str) or rule not in info.rules:
        raise ValueError(f"rule: expected one of {', '.join(info.rules)}, found {rule!r}")
    cfg = check_config(cfg)
    if not info.baseline:
        return info.build(cfg, sigma_model=sigma_model)
    pole = _check_paper_stable(cfg) if rule != "min-error" else math.nan
    knob, (lo, hi), build = info.knob, info.knob_range, info.build

    def make(value: float) -> DiscreteEstimator:
        return build(cfg, **{knob: value}, sigma_model=sigma_model, tuning=rule)

    if rule == "rate" and info.knob_is_rate:
        return make(-pole)
    if info.knob_noise_power:
        eta = noise_level(cfg)[0]
        check_positive("measurement_rms (sensor noise_rms or quantization)", eta, "m")
        for _ in range(info.knob_noise_power):   # lo eta^p / eta_range^p, in this order of operations
            lo, hi = lo * eta, hi * eta
        lo, hi = lo / _RANGE_ETA ** info.knob_noise_power, hi / _RANGE_ETA ** info.knob_noise_power
    if rule == "min-error":
        return make(_min_error(make, cfg, lo, hi))
    if rule == "rate":
        target = pole * cfg.observer.dt          # log of the target pole radius

        def mismatch(log_q: float) -> float:     # > 0 when faster than the target
            return target - math.log(float(np.max(np.abs(make(math.exp(log_q)).poles()))))

        return make(_solve_log(mismatch, lo, hi, "rate rule"))
    eta, B = noise_level(cfg)
    if eta == 0.0:
        raise ValueError("sensor: the noise rule needs noise_rms > 0 or quantization > 0, found both 0")
    ref = reference_noise_rms(cfg)

    def mismatch(log_knob: float) -> float:
        return friction_noise_rms(make(math.exp(log_knob)), eta, B) / ref - 1.0

    return make(_solve_log(mismatch, lo, hi, "noise rule"))
